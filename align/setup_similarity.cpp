#include "align/setup_similarity.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>

#include <opencv2/core/hal/intrin.hpp>
#include <opencv2/imgproc.hpp>

namespace glasspiv {

namespace {

// Half the length of the tangent segment an edge point stands for. Points of a
// chain lie at most 1 / cos(22.5 deg) = 1.08 px apart along a straight edge, so
// 0.6 closes the gaps; on a curve of radius R it errs by 0.6^2 / (2 R) px.
constexpr double kSegmentHalfPx = 0.6;
constexpr double kIndexCellPx = 2;  // near-aligned queries end after 3 x 3 cells

int blur_radius_px(double sigma_px) { return sigma_px > 0 ? int(std::ceil(3 * sigma_px)) : 0; }

void check_image(const cv::Mat& image, const char* what) {
  if (image.empty() || image.type() != CV_32FC1)
    throw std::invalid_argument(std::string(what) + " must be a non-empty CV_32FC1 image");
  if (image.rows < 3 || image.cols < 3) throw std::invalid_argument(std::string(what) + " must be at least 3 x 3 px");
}

void blur_into(const cv::Mat& image, double sigma_px, cv::Mat& out) {
  const int r = blur_radius_px(sigma_px);
  if (r == 0) {
    image.copyTo(out);
    return;
  }
  cv::GaussianBlur(image, out, cv::Size(2 * r + 1, 2 * r + 1), sigma_px, sigma_px, cv::BORDER_REPLICATE);
}

// |g| by central differences of the blurred image; 0 on the outer frame.
void gradient_magnitude_into(const cv::Mat& b, cv::Mat& g) {
  const int w = b.cols, h = b.rows;
  g.create(h, w, CV_32F);
  std::memset(g.ptr<float>(0), 0, sizeof(float) * w);
  std::memset(g.ptr<float>(h - 1), 0, sizeof(float) * w);
  for (int y = 1; y < h - 1; ++y) {
    const float* up = b.ptr<float>(y - 1);
    const float* row = b.ptr<float>(y);
    const float* down = b.ptr<float>(y + 1);
    float* out = g.ptr<float>(y);
    out[0] = out[w - 1] = 0;
    for (int x = 1; x < w - 1; ++x) {  // squared here (vectorises), root below
      const float gx = 0.5f * (row[x + 1] - row[x - 1]);
      const float gy = 0.5f * (down[x] - up[x]);
      out[x] = gx * gx + gy * gy;
    }
  }
  cv::sqrt(g, g);
}

// Nonzero mask pixels, shrunk by the filter support; never the outer frame.
cv::Mat valid_mask_of(cv::Size size, const cv::Mat& mask8u, int support_px) {
  cv::Mat valid;
  if (mask8u.empty()) {
    valid = cv::Mat(size, CV_8U, cv::Scalar(255));
  } else {
    if (mask8u.type() != CV_8UC1 || mask8u.size() != size)
      throw std::invalid_argument("mask must be CV_8UC1 of the images' size");
    valid = mask8u != 0;
    if (support_px > 0)  // the default border value keeps the image edge from eroding
      cv::erode(valid, valid,
                cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * support_px + 1, 2 * support_px + 1)));
  }
  valid.row(0).setTo(0);
  valid.row(size.height - 1).setTo(0);
  valid.col(0).setTo(0);
  valid.col(size.width - 1).setTo(0);
  return valid;
}

// Sums over the valid runs for both NCCs: of the intensities r (against the
// photo's p) and of the gradient magnitudes g (against the photo's q).
// Non-finite pixels (a float photo may hold NaN) become 0 in `image` and
// ignored in the returned mask, so the shrinking keeps them out of every
// compared pixel's filter support. The mask is returned unchanged when all are finite.
cv::Mat drop_non_finite(cv::Mat& image, const cv::Mat& mask8u) {
  cv::Mat mask = mask8u;
  for (int y = 0; y < image.rows; ++y) {
    float* row = image.ptr<float>(y);
    for (int x = 0; x < image.cols; ++x) {
      if (std::isfinite(row[x])) continue;
      if (mask.data == mask8u.data) {
        if (!mask8u.empty() && (mask8u.type() != CV_8UC1 || mask8u.size() != image.size()))
          throw std::invalid_argument("mask must be CV_8UC1 of the images' size");
        mask = mask8u.empty() ? cv::Mat(image.size(), CV_8U, cv::Scalar(255)) : mask8u.clone();
      }
      row[x] = 0;
      mask.at<std::uint8_t>(y, x) = 0;
    }
  }
  return mask;
}

struct Sums {
  double r = 0, rr = 0, rp = 0, g = 0, gg = 0, gq = 0;
};

template <class Run>
Sums accumulate(const std::vector<Run>& runs, const cv::Mat& r, const cv::Mat& p, const cv::Mat& g, const cv::Mat& q) {
  Sums s;
  for (const Run& run : runs) {
    const float* pr = r.ptr<float>(run.y);
    const float* pp = p.ptr<float>(run.y);
    const float* pg = g.ptr<float>(run.y);
    const float* pq = q.ptr<float>(run.y);
    int x = run.x0;
#if CV_SIMD128
    // 4 float lanes, folded into doubles every 64 pixels (16 terms per lane:
    // rounding stays near float epsilon, far below the 1e-6 the NCCs need).
    constexpr int kLanes = 4, kBlock = 64;
    const cv::v_float32x4 one = cv::v_setall_f32(1.f);
    while (x + kLanes <= run.x1) {
      cv::v_float32x4 ar = cv::v_setzero_f32(), arr = ar, arp = ar, ag = ar, agg = ar, agq = ar;
      const int end = std::min(run.x1 - (run.x1 - x) % kLanes, x + kBlock);
      for (; x < end; x += kLanes) {
        const cv::v_float32x4 vr = cv::v_load(pr + x), vg = cv::v_load(pg + x);
        ar = cv::v_fma(vr, one, ar);
        arr = cv::v_fma(vr, vr, arr);
        arp = cv::v_fma(vr, cv::v_load(pp + x), arp);
        ag = cv::v_fma(vg, one, ag);
        agg = cv::v_fma(vg, vg, agg);
        agq = cv::v_fma(vg, cv::v_load(pq + x), agq);
      }
      s.r += cv::v_reduce_sum(ar), s.rr += cv::v_reduce_sum(arr), s.rp += cv::v_reduce_sum(arp);
      s.g += cv::v_reduce_sum(ag), s.gg += cv::v_reduce_sum(agg), s.gq += cv::v_reduce_sum(agq);
    }
#endif
    for (; x < run.x1; ++x) {
      const double rv = pr[x], gv = pg[x];
      s.r += rv, s.rr += rv * rv, s.rp += rv * pp[x];
      s.g += gv, s.gg += gv * gv, s.gq += gv * pq[x];
    }
  }
  return s;
}

double ncc_of(long n, double sa, double saa, double sb, double sbb, double sab) {
  if (n < 2) return 0;
  const double va = saa - sa * sa / n, vb = sbb - sb * sb / n, cov = sab - sa * sb / n;
  if (!(va > 0) || !(vb > 0)) return 0;
  return std::clamp(cov / std::sqrt(va * vb), -1.0, 1.0);
}

// Percentile of |g| over the valid runs, every 2nd row and 4th column: a histogram
// on the float's bits (sign 0, 8 exponent + 7 mantissa bits: 0.8 % wide bins),
// interpolated linearly inside the bin.
template <class Run>
double gradient_percentile(const std::vector<Run>& runs, const cv::Mat& g, double percentile) {
  constexpr std::uint32_t kLowBin = (127u - 32u) << 7;  // 2^-32
  constexpr std::uint32_t kHighBin = (127u + 8u) << 7;  // 2^8
  constexpr int kBins = int(kHighBin - kLowBin) + 1;
  std::vector<std::uint32_t> hist(kBins, 0);
  long count = 0;
  for (const Run& run : runs) {
    if (run.y % 2) continue;
    const float* row = g.ptr<float>(run.y);
    for (int x = run.x0 + (4 - run.x0 % 4) % 4; x < run.x1; x += 4) {
      std::uint32_t bits;
      std::memcpy(&bits, &row[x], 4);
      const std::uint32_t bin = std::clamp(bits >> 16, kLowBin, kHighBin) - kLowBin;
      ++hist[bin];
      ++count;
    }
  }
  if (count == 0) return 0;
  const double rank = std::clamp(percentile, 0.0, 100.0) / 100.0 * double(count);
  double below = 0;
  for (int i = 0; i < kBins; ++i) {
    if (below + hist[i] >= rank && hist[i] > 0) {
      const auto value_of = [&](std::uint32_t bin_bits) {
        const std::uint32_t bits = (bin_bits + kLowBin) << 16;
        float v;
        std::memcpy(&v, &bits, 4);
        return double(v);
      };
      const double lo = value_of(i), hi = value_of(i + 1);
      return lo + (hi - lo) * (rank - below) / hist[i];
    }
    below += hist[i];
  }
  return 0;
}

struct Thresholds {
  float low = 0, high = 0;
};

template <class Run>
Thresholds thresholds_of(const std::vector<Run>& runs, const cv::Mat& g, const SimilarityOptions& o) {
  const double reference = gradient_percentile(runs, g, o.edge_reference_percentile);
  Thresholds t;
  t.high = float(std::max(o.edge_threshold * reference, o.edge_min_gradient_per_px));
  t.low = float(std::max(o.edge_low_ratio * t.high, o.edge_min_gradient_per_px));
  return t;
}

// Non-maximum suppression across the edge, Gaussian sub-pixel peak, hysteresis.
template <class Run>
std::vector<EdgePoint> edges_of(const cv::Mat& b, const cv::Mat& g, const std::vector<Run>& runs, Thresholds t,
                                cv::Mat& flags) {
  const int w = g.cols, h = g.rows;
  enum : std::uint8_t { kNone = 0, kWeak = 1, kAccepted = 2 };
  if (!flags.isContinuous()) flags.release();
  flags.create(h, w, CV_8U);
  flags.setTo(kNone);
  std::vector<EdgePoint> candidates;
  std::vector<int> pixel_of;
  std::vector<int> stack;
  for (const Run& run : runs) {
    const int y = run.y;
    const float* grow = g.ptr<float>(y);
    const float* bup = b.ptr<float>(y - 1);
    const float* brow = b.ptr<float>(y);
    const float* bdown = b.ptr<float>(y + 1);
    std::uint8_t* frow = flags.ptr<std::uint8_t>(y);
    for (int x = run.x0; x < run.x1; ++x) {
#if CV_SIMD128
      // Most pixels are far below the low threshold: skip them 16 at a time.
      if ((x & 15) == 0 && x + 16 <= run.x1) {
        const cv::v_float32x4 top = cv::v_max(cv::v_max(cv::v_load(grow + x), cv::v_load(grow + x + 4)),
                                              cv::v_max(cv::v_load(grow + x + 8), cv::v_load(grow + x + 12)));
        if (!(cv::v_reduce_max(top) > t.low)) {
          x += 15;
          continue;
        }
      }
#endif
      const float m = grow[x];
      if (!(m > t.low)) continue;
      const float gx = 0.5f * (brow[x + 1] - brow[x - 1]);
      const float gy = 0.5f * (bdown[x] - bup[x]);
      const float ax = std::abs(gx), ay = std::abs(gy);
      int sx = 1, sy = 0;  // step across the edge, rounded to one of 4 directions
      if (ay <= 0.41421356f * ax) {
        sx = 1, sy = 0;
      } else if (ax <= 0.41421356f * ay) {
        sx = 0, sy = 1;
      } else {
        sx = 1, sy = (gx * gy > 0) ? 1 : -1;
      }
      const float m_minus = g.ptr<float>(y - sy)[x - sx];
      const float m_plus = g.ptr<float>(y + sy)[x + sx];
      if (!(m > m_minus && m >= m_plus)) continue;
      // Gaussian through the three samples: parabola in log |g|.
      const double l_minus = std::log(std::max(m_minus, 1e-30f)), l0 = std::log(m),
                   l_plus = std::log(std::max(m_plus, 1e-30f));
      const double curvature = l_minus - 2 * l0 + l_plus;
      const double offset = curvature < 0 ? std::clamp(0.5 * (l_minus - l_plus) / curvature, -0.5, 0.5) : 0.0;
      EdgePoint p;
      p.x_px = float(x + offset * sx);
      p.y_px = float(y + offset * sy);
      const float norm = std::sqrt(gx * gx + gy * gy);
      p.normal_x = gx / norm;
      p.normal_y = gy / norm;
      p.gradient_per_px = m;
      candidates.push_back(p);
      pixel_of.push_back(y * w + x);
      if (m >= t.high) {
        frow[x] = kAccepted;
        stack.push_back(y * w + x);
      } else {
        frow[x] = kWeak;
      }
    }
  }
  std::uint8_t* f = flags.ptr<std::uint8_t>(0);  // continuous (create() of a whole image)
  while (!stack.empty()) {  // candidates never touch the frame, so neighbours exist
    const int i = stack.back();
    stack.pop_back();
    for (const int d : {-w - 1, -w, -w + 1, -1, 1, w - 1, w, w + 1}) {
      if (f[i + d] == kWeak) {
        f[i + d] = kAccepted;
        stack.push_back(i + d);
      }
    }
  }
  std::vector<EdgePoint> edges;
  edges.reserve(candidates.size());
  for (std::size_t k = 0; k < candidates.size(); ++k)
    if (f[pixel_of[k]] == kAccepted) edges.push_back(candidates[k]);
  return edges;
}

}  // namespace

// Shared by PhotoEdgeModel and detect_edges.
struct SimilarityDetail {
  using Run = PhotoEdgeModel::Run;
  static std::vector<Run> runs_of(const cv::Mat& valid, long* count) {
    std::vector<Run> runs;
    *count = 0;
    for (int y = 0; y < valid.rows; ++y) {
      const std::uint8_t* row = valid.ptr<std::uint8_t>(y);
      for (int x = 0; x < valid.cols;) {
        if (!row[x]) {
          ++x;
          continue;
        }
        const int x0 = x;
        while (x < valid.cols && row[x]) ++x;
        runs.push_back({y, x0, x});
        *count += x - x0;
      }
    }
    return runs;
  }
  static int support_px(const SimilarityOptions& o) { return blur_radius_px(o.edge_blur_px) + 2; }
};

void SimilarityOptions::check() const {
  const auto require = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(std::string("SimilarityOptions: ") + what);
  };
  require(edge_blur_px >= 0 && edge_blur_px <= 50, "edge_blur_px must be in [0, 50]");
  require(edge_threshold > 0 && edge_threshold <= 10, "edge_threshold must be in (0, 10]");
  require(edge_reference_percentile > 0 && edge_reference_percentile <= 100,
          "edge_reference_percentile must be in (0, 100]");
  require(edge_low_ratio > 0 && edge_low_ratio <= 1, "edge_low_ratio must be in (0, 1]");
  require(edge_min_gradient_per_px > 0, "edge_min_gradient_per_px must be positive");
  require(chamfer_cutoff_px > 0 && chamfer_cutoff_px <= 1000, "chamfer_cutoff_px must be in (0, 1000]");
}

std::vector<EdgePoint> detect_edges(const cv::Mat& image32f, const SimilarityOptions& options, const cv::Mat& mask8u) {
  options.check();
  check_image(image32f, "image");
  cv::Mat image = image32f.clone();
  const cv::Mat valid =
      valid_mask_of(image.size(), drop_non_finite(image, mask8u), SimilarityDetail::support_px(options));
  long count = 0;
  const auto runs = SimilarityDetail::runs_of(valid, &count);
  SimilarityWorkspace ws;
  blur_into(image, options.edge_blur_px, ws.blurred);
  gradient_magnitude_into(ws.blurred, ws.gradient);
  return edges_of(ws.blurred, ws.gradient, runs, thresholds_of(runs, ws.gradient, options), ws.flags);
}

EdgeDistanceIndex::EdgeDistanceIndex(std::vector<EdgePoint> points, cv::Size image_size, double cutoff_px)
    : cell_px_(kIndexCellPx), cutoff_px_(cutoff_px) {
  cells_x_ = std::max(1, int(std::ceil(image_size.width / cell_px_)));
  cells_y_ = std::max(1, int(std::ceil(image_size.height / cell_px_)));
  const auto cell_of = [&](const EdgePoint& p) {
    const int cx = std::clamp(int(std::floor(p.x_px / cell_px_)), 0, cells_x_ - 1);
    const int cy = std::clamp(int(std::floor(p.y_px / cell_px_)), 0, cells_y_ - 1);
    return cy * cells_x_ + cx;
  };
  cell_start_.assign(std::size_t(cells_x_) * cells_y_ + 1, 0);  // counting sort by cell
  for (const EdgePoint& p : points) ++cell_start_[cell_of(p) + 1];
  for (std::size_t i = 1; i < cell_start_.size(); ++i) cell_start_[i] += cell_start_[i - 1];
  std::vector<int> fill(cell_start_.begin(), cell_start_.end() - 1);
  points_.resize(points.size());
  for (const EdgePoint& p : points) points_[fill[cell_of(p)]++] = p;
  packed_.resize(points_.size());
  for (std::size_t i = 0; i < points_.size(); ++i)
    packed_[i] = {points_[i].x_px, points_[i].y_px, points_[i].normal_x, points_[i].normal_y};
}

double EdgeDistanceIndex::distance_px(double x_px, double y_px) const {
  if (points_.empty()) return cutoff_px_;
  const int cx = std::clamp(int(std::floor(x_px / cell_px_)), 0, cells_x_ - 1);
  const int cy = std::clamp(int(std::floor(y_px / cell_px_)), 0, cells_y_ - 1);
  const float qx = float(x_px), qy = float(y_px), half = float(kSegmentHalfPx);
  float best_sq = float(cutoff_px_ * cutoff_px_);
  // Cells of one row are contiguous in points_: visit row iy, columns ix0..ix1.
  const auto visit = [&](int iy, int ix0, int ix1) {
    if (iy < 0 || iy >= cells_y_) return;
    ix0 = std::max(ix0, 0), ix1 = std::min(ix1, cells_x_ - 1);
    if (ix0 > ix1) return;
    const int end = cell_start_[iy * cells_x_ + ix1 + 1];
    for (int k = cell_start_[iy * cells_x_ + ix0]; k < end; ++k) {
      const Packed& p = packed_[k];
      const float dx = qx - p.x, dy = qy - p.y;
      const float across = dx * p.nx + dy * p.ny;
      const float along = std::max(0.f, std::abs(dx * p.ny - dy * p.nx) - half);
      best_sq = std::min(best_sq, across * across + along * along);
    }
  };
  // Rings of cells around the query's: whatever lies beyond ring k is at least
  // k cells away, i.e. k * cell - kSegmentHalfPx from the query (segment reach).
  const int max_ring = std::max(cells_x_, cells_y_);
  for (int k = 0; k <= max_ring; ++k) {
    visit(cy - k, cx - k, cx + k);
    if (k > 0) {
      visit(cy + k, cx - k, cx + k);
      for (int iy = cy - k + 1; iy <= cy + k - 1; ++iy) {
        visit(iy, cx - k, cx - k);
        visit(iy, cx + k, cx + k);
      }
    }
    const double reach = k * cell_px_ - kSegmentHalfPx;
    if (reach > 0 && (reach * reach >= best_sq || reach >= cutoff_px_)) break;
  }
  return std::min(std::sqrt(double(best_sq)), cutoff_px_);
}

double EdgeDistanceIndex::mean_distance_px(const std::vector<EdgePoint>& from) const {
  if (from.empty()) return cutoff_px_;
  double sum = 0;
  for (const EdgePoint& p : from) sum += distance_px(p.x_px, p.y_px);
  return sum / double(from.size());
}

PhotoEdgeModel::PhotoEdgeModel(const cv::Mat& photo32f, const SimilarityOptions& options, const cv::Mat& mask8u)
    : options_(options) {
  options_.check();
  check_image(photo32f, "photo");
  size_ = photo32f.size();
  photo_ = photo32f.clone();  // the caller may reuse its buffer
  valid_ = valid_mask_of(size_, drop_non_finite(photo_, mask8u), SimilarityDetail::support_px(options_));
  runs_ = SimilarityDetail::runs_of(valid_, &valid_pixels_);
  SimilarityWorkspace ws;
  blur_into(photo_, options_.edge_blur_px, ws.blurred);
  gradient_magnitude_into(ws.blurred, grad_);
  // Through the same code as the render's sums, so identical images give identical sums.
  const Sums p = accumulate(runs_, photo_, photo_, grad_, grad_);
  sum_p_ = p.r, sum_pp_ = p.rr, sum_g_ = p.g, sum_gg_ = p.gg;
  edges_ = EdgeDistanceIndex(edges_of(ws.blurred, grad_, runs_, thresholds_of(runs_, grad_, options_), ws.flags), size_,
                             options_.chamfer_cutoff_px);
}

Similarity PhotoEdgeModel::compare(const cv::Mat& render32f) const {
  SimilarityWorkspace workspace;
  return compare(render32f, workspace);
}

Similarity PhotoEdgeModel::compare(const cv::Mat& render32f, SimilarityWorkspace& workspace) const {
  check_image(render32f, "render");
  if (render32f.size() != size_) throw std::invalid_argument("render and photo differ in size");
  const cv::Mat& b = workspace.blurred;
  const cv::Mat& g = workspace.gradient;
  blur_into(render32f, options_.edge_blur_px, workspace.blurred);
  gradient_magnitude_into(b, workspace.gradient);
  const Sums r = accumulate(runs_, render32f, photo_, g, grad_);

  Similarity s;
  s.valid_pixels = valid_pixels_;
  s.ncc = ncc_of(valid_pixels_, r.r, r.rr, sum_p_, sum_pp_, r.rp);
  s.gradient_ncc = ncc_of(valid_pixels_, r.g, r.gg, sum_g_, sum_gg_, r.gq);

  const EdgeDistanceIndex render_edges(edges_of(b, g, runs_, thresholds_of(runs_, g, options_), workspace.flags), size_,
                                       options_.chamfer_cutoff_px);
  s.render_edge_pixels = long(render_edges.points().size());
  s.photo_edge_pixels = long(edges_.points().size());
  s.chamfer_render_to_photo_px = edges_.mean_distance_px(render_edges.points());
  s.chamfer_photo_to_render_px = render_edges.mean_distance_px(edges_.points());
  s.chamfer_px = 0.5 * (s.chamfer_render_to_photo_px + s.chamfer_photo_to_render_px);
  return s;
}

cv::Mat blurred_gradient_magnitude(const cv::Mat& image32f, double sigma_px) {
  check_image(image32f, "image");
  cv::Mat b, g;
  blur_into(image32f, sigma_px, b);
  gradient_magnitude_into(b, g);
  return g;
}

Similarity compare_render_to_photo(const cv::Mat& render32f, const cv::Mat& photo32f, const SimilarityOptions& options,
                                   const cv::Mat& mask8u) {
  check_image(render32f, "render");
  check_image(photo32f, "photo");
  if (render32f.size() != photo32f.size()) throw std::invalid_argument("render and photo differ in size");
  return PhotoEdgeModel(photo32f, options, mask8u).compare(render32f);
}

}  // namespace glasspiv
