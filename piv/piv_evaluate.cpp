#include "piv/piv_evaluate.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

#include "piv/cross_correlation.h"
#include "piv/mask_overlap.h"
#include "piv/row_threads.h"
#include "piv/subpixel_peak.h"

namespace glasspiv {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Window pairs per batch of DFTs (cross_correlation.h); planes do not depend on it.
constexpr int kBatchPairs = 16;

// Windows that give no vector: centre pixel unusable or more than half the pixels.
std::vector<std::uint8_t> masked_windows(const InterrogationGrid& g, const cv::Mat& usable) {
  std::vector<std::uint8_t> masked(static_cast<std::size_t>(g.size()), 0);
  if (usable.empty()) return masked;
  cv::Mat unusable = usable == 0, counts;
  cv::integral(unusable / 255, counts, CV_32S);
  const int n = g.window_px;
  for (int r = 0; r < g.rows; ++r)
    for (int c = 0; c < g.cols; ++c) {
      const int x = g.left_px(c), y = g.top_px(r);
      const int bad = counts.at<int>(y + n, x + n) - counts.at<int>(y, x + n) - counts.at<int>(y + n, x) +
                      counts.at<int>(y, x);
      masked[static_cast<std::size_t>(g.index(c, r))] = !usable.at<std::uint8_t>(y + n / 2, x + n / 2) || 2 * bad > n * n;
    }
  return masked;
}

// Invalid vectors get the mean of their filled neighbours, ring after ring; a
// field with no valid vector becomes zero.
void fill_invalid(const InterrogationGrid& g, std::vector<double>& u, std::vector<double>& v,
                  const std::vector<VectorFlag>& flags) {
  std::vector<std::uint8_t> filled(flags.size());
  std::size_t missing = 0;
  for (std::size_t i = 0; i < flags.size(); ++i) missing += !(filled[i] = flags[i] != VectorFlag::invalid);
  if (missing == flags.size()) {
    std::fill(u.begin(), u.end(), 0.0);
    std::fill(v.begin(), v.end(), 0.0);
    return;
  }
  while (missing > 0) {
    std::vector<std::uint8_t> next = filled;
    for (int r = 0; r < g.rows; ++r)
      for (int c = 0; c < g.cols; ++c) {
        const std::size_t i = static_cast<std::size_t>(g.index(c, r));
        if (filled[i]) continue;
        double su = 0, sv = 0;
        int k = 0;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int cc = c + dx, rr = r + dy;
            if (cc < 0 || rr < 0 || cc >= g.cols || rr >= g.rows) continue;
            const std::size_t j = static_cast<std::size_t>(g.index(cc, rr));
            if (!filled[j]) continue;
            su += u[j];
            sv += v[j];
            ++k;
          }
        if (k == 0) continue;
        u[i] = su / k;
        v[i] = sv / k;
        next[i] = 1;
        --missing;
      }
    filled.swap(next);
  }
}

InterrogationGrid pass_grid(int width_px, int height_px, int window_px, double overlap) {
  return interrogation_grid(width_px, height_px, window_px, step_from_overlap(window_px, overlap));
}

}  // namespace

void PivOptions::check() const {
  if (window_px.empty()) throw std::invalid_argument("window_px: at least one pass");
  for (int n : window_px)
    if (n < 8) throw std::invalid_argument("window_px: windows of " + std::to_string(n) + " px (at least 8)");
  if (!(overlap >= 0 && overlap <= 0.9)) throw std::invalid_argument("overlap: must lie in [0, 0.9]");
  if (!(validation.epsilon_px > 0) || !(validation.threshold > 0))
    throw std::invalid_argument("validation: epsilon_px and threshold must be positive");
  if (peak_exclusion_radius_px < 1) throw std::invalid_argument("peak_exclusion_radius_px: at least 1");
}

InterrogationGrid final_piv_grid(int width_px, int height_px, const PivOptions& options) {
  options.check();
  return pass_grid(width_px, height_px, options.window_px.back(), options.overlap);
}

PivField evaluate_piv(const cv::Mat& frame_a, const cv::Mat& frame_b, const cv::Mat& usable_in, const PivOptions& options,
                      const std::function<void(std::size_t, std::size_t)>& progress) {
  options.check();
  if (frame_a.type() != CV_32F || frame_b.type() != CV_32F || frame_a.size() != frame_b.size())
    throw std::invalid_argument("evaluate_piv: frames must be CV_32F of one size");
  if (!usable_in.empty() && (usable_in.type() != CV_8U || usable_in.size() != frame_a.size()))
    throw std::invalid_argument("evaluate_piv: the mask must be CV_8U of the frames' size");
  const int w = frame_a.cols, h = frame_a.rows;
  std::vector<InterrogationGrid> grids;
  std::size_t total = 0;
  for (int n : options.window_px) {
    grids.push_back(pass_grid(w, h, n, options.overlap));
    total += static_cast<std::size_t>(grids.back().size());
  }

  // Non-finite pixels are unusable and read as zero. Continuous frames with
  // none and no mask are used as they are (read only), without copies; the
  // windows below take one row stride (the width) for frames and mask.
  bool any_unusable = false;
  for (int y = 0; y < h && !any_unusable; ++y) {
    const float* pa = frame_a.ptr<float>(y);
    const float* pb = frame_b.ptr<float>(y);
    const std::uint8_t* m = usable_in.empty() ? nullptr : usable_in.ptr<std::uint8_t>(y);
    bool bad = false;
    for (int x = 0; x < w; ++x) bad |= !(std::isfinite(pa[x]) && std::isfinite(pb[x])) || (m && !m[x]);
    any_unusable = bad;
  }
  cv::Mat a = frame_a.isContinuous() ? frame_a : frame_a.clone();
  cv::Mat b = frame_b.isContinuous() ? frame_b : frame_b.clone(), usable;
  if (any_unusable) {
    a = frame_a.clone();
    b = frame_b.clone();
    usable.create(h, w, CV_8U);
    for (int y = 0; y < h; ++y) {
      float* pa = a.ptr<float>(y);
      float* pb = b.ptr<float>(y);
      const std::uint8_t* m = usable_in.empty() ? nullptr : usable_in.ptr<std::uint8_t>(y);
      std::uint8_t* o = usable.ptr<std::uint8_t>(y);
      for (int x = 0; x < w; ++x) {
        const bool finite = std::isfinite(pa[x]) && std::isfinite(pb[x]);
        if (!finite) pa[x] = pb[x] = 0;
        o[x] = finite && (!m || m[x]);
      }
    }
  }

  std::atomic<std::size_t> done{0};
  std::size_t done_before = 0;
  std::function<void()> poll;
  if (progress) poll = [&]() { progress(done_before + done.load(), total); };
  const int threads = resolved_thread_count(options.threads);
  PivField field;
  InterrogationGrid previous;
  std::vector<double> predictor_u, predictor_v;  // filled field of the previous pass
  for (std::size_t pass = 0; pass < grids.size(); ++pass) {
    const InterrogationGrid& g = grids[pass];
    const std::vector<std::uint8_t> masked = masked_windows(g, usable);
    cv::Mat da = a, db = b, ua = usable, ub = usable, dense_u, dense_v;
    if (pass > 0) {
      dense_u = dense_field(previous, predictor_u, w, h);
      dense_v = dense_field(previous, predictor_v, w, h);
      DeformedFrame fa = deform_frame(a, usable, dense_u, dense_v, -0.5, options.interpolation, threads);
      DeformedFrame fb = deform_frame(b, usable, dense_u, dense_v, +0.5, options.interpolation, threads);
      da = fa.values;
      db = fb.values;
      ua = fa.usable;
      ub = fb.usable;
    }
    const std::size_t count = static_cast<std::size_t>(g.size());
    std::vector<double> u(count, kNaN), v(count, kNaN), ratio(count, 0.0);
    std::vector<VectorFlag> flags(count, VectorFlag::invalid);
    std::vector<std::unique_ptr<BatchCorrelator>> correlators(static_cast<std::size_t>(threads));
    std::vector<std::unique_ptr<MaskOverlap>> overlaps(static_cast<std::size_t>(threads));
    done = 0;
    for_each_row(
        g.rows, threads,
        [&](int row, int thread) {
          auto& corr = correlators[static_cast<std::size_t>(thread)];
          if (!corr) corr = std::make_unique<BatchCorrelator>(g.window_px, kBatchPairs);
          auto& overlap = overlaps[static_cast<std::size_t>(thread)];
          if (!overlap && (!ua.empty() || !ub.empty()))
            overlap = std::make_unique<MaskOverlap>(g.window_px, corr->plane_px());
          int cols_of_slots[kBatchPairs];
          const std::uint8_t* valid_a_of_slots[kBatchPairs];
          const std::uint8_t* valid_b_of_slots[kBatchPairs];
          // Peaks of the batch's planes become vectors.
          auto flush = [&]() {
            corr->correlate();
            for (int slot = 0; slot < corr->size(); ++slot) {
              const int col = cols_of_slots[slot];
              const std::size_t i = static_cast<std::size_t>(g.index(col, row));
              if (overlap)
                overlap->normalise(corr->plane(slot), valid_a_of_slots[slot],
                                   static_cast<int>(ua.step1()), valid_b_of_slots[slot], static_cast<int>(ub.step1()));
              const CorrelationPeak peak =
                  find_correlation_peak(corr->plane(slot), corr->plane_px(), options.peak_exclusion_radius_px);
              if (!peak.found) continue;
              double pu = 0, pv = 0;
              if (pass > 0) {
                pu = grid_field_at(previous, predictor_u, g.x_px(col), g.y_px(row));
                pv = grid_field_at(previous, predictor_v, g.x_px(col), g.y_px(row));
              }
              u[i] = pu + peak.u_px;
              v[i] = pv + peak.v_px;
              ratio[i] = peak.peak_ratio;
              flags[i] = VectorFlag::valid;
            }
            corr->clear();
          };
          for (int col = 0; col < g.cols; ++col) {
            const std::size_t i = static_cast<std::size_t>(g.index(col, row));
            if (masked[i]) continue;
            const int x = g.left_px(col), y = g.top_px(row);
            const auto* va = ua.empty() ? nullptr : ua.ptr<std::uint8_t>(y) + x;
            const auto* vb = ub.empty() ? nullptr : ub.ptr<std::uint8_t>(y) + x;
            const int stride = static_cast<int>(da.step1());
            const int slot = corr->add(da.ptr<float>(y) + x, stride, va, db.ptr<float>(y) + x, stride, vb);
            if (slot < 0) continue;
            cols_of_slots[slot] = col;
            valid_a_of_slots[slot] = va;
            valid_b_of_slots[slot] = vb;
            if (corr->full()) flush();
          }
          flush();
          done.fetch_add(static_cast<std::size_t>(g.cols));
        },
        poll);
    done_before += count;
    MedianTestOptions validation = options.validation;
    validation.threads = threads;
    field.validation = normalised_median_test(g.cols, g.rows, u, v, flags, validation);
    if (pass + 1 < grids.size()) {
      predictor_u = u;
      predictor_v = v;
      fill_invalid(g, predictor_u, predictor_v, flags);
      previous = g;
    } else {
      field.grid = g;
      field.u_px = std::move(u);
      field.v_px = std::move(v);
      field.flags = std::move(flags);
      field.peak_ratio = std::move(ratio);
    }
  }
  return field;
}

}  // namespace glasspiv
