#include "targets/marker_detect.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include <apriltag/apriltag.h>
#include <fmt/format.h>
#include <opencv2/aruco.hpp>
#include <opencv2/imgproc.hpp>

#include "targets/target_spec.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {

// libapriltag puts (0, 0) at the outer corner of the top-left pixel; glasspiv at
// its centre (docs/conventions.md; measured in target_detect_test.cpp).
constexpr double kAprilTagToGlasspivPx = -0.5;

// libapriltag's p[0..3] for one of its own tags upright in the image
// (apriltag_to_image's layout): bottom-left, bottom-right, top-right, top-left
// (its homography maps tag (-1, 1), (1, 1), (1, -1), (-1, -1) there, y down).
// Ours k = top-left, top-right, bottom-right, bottom-left is p[kAprilTagCorner[k]].
constexpr int kAprilTagCorner[4] = {3, 2, 1, 0};

// The edge fit. Profiles across each side, 0.5 px apart along it and one cell
// clear of the corners; each spans +-half a cell (at most kMaxHalfWidthPx)
// across the edge, sampled every ~0.25 px.
constexpr double kProfileSpacingPx = 0.5;
constexpr double kProfileStepPx = 0.25;
constexpr double kMaxHalfWidthPx = 5.0;
constexpr double kMinContrast = 8.0;  // grey levels between the two sides of an edge
constexpr int kMinProfiles = 4;
constexpr int kIterations = 4;

// Bilinear sample at a glasspiv pixel position; false outside the pixel centres.
bool sample(const cv::Mat& gray, const Eigen::Vector2d& p, double& value) {
  if (!(p.x() >= 0 && p.y() >= 0 && p.x() <= gray.cols - 1 && p.y() <= gray.rows - 1)) return false;
  const int x = std::min(static_cast<int>(p.x()), gray.cols - 2), y = std::min(static_cast<int>(p.y()), gray.rows - 2);
  const double fx = p.x() - x, fy = p.y() - y;
  const unsigned char* r0 = gray.ptr<unsigned char>(y);
  const unsigned char* r1 = gray.ptr<unsigned char>(y + 1);
  value = (1 - fy) * ((1 - fx) * r0[x] + fx * r0[x + 1]) + fy * ((1 - fx) * r1[x] + fx * r1[x + 1]);
  return true;
}

double median(std::vector<double> v) {
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

struct Line {
  Eigen::Vector2d point, direction;
};

// The edge along one side a -> b of the marker's square, `cells` cells long.
// Each profile's edge position comes from the area under its normalised
// profile: for a step blurred by any symmetric kernel (lens, pixel area,
// bilinear interpolation) the integral over [-h, h] of (I - I_in) / (I_out -
// I_in) is h - e, e the edge's offset, without bias; the window is recentred on
// the fitted line each pass. h is half a cell, so that the window does not
// reach the next edge (an inner bit, or the end of the quiet zone);
// `half_cells` sets it.
bool fit_side(const cv::Mat& gray, const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& centre,
              int cells, double half_cells, Line& line) {
  const double length = (b - a).norm();
  if (!(length > 0)) return false;
  const Eigen::Vector2d d = (b - a) / length;
  Eigen::Vector2d n(-d.y(), d.x());
  if (n.dot(a - centre) < 0) n = -n;  // outward
  const double cell = length / cells;
  const double h = std::min(half_cells * cell, kMaxHalfWidthPx);
  const int steps = std::max(6, static_cast<int>(std::ceil(2 * h / kProfileStepPx)));
  const double dt = 2 * h / steps;

  std::vector<double> us;
  std::vector<std::vector<double>> profiles;
  for (double u = cell; u <= length - cell + 1e-9; u += kProfileSpacingPx) {
    const Eigen::Vector2d s = a + u * d;
    std::vector<double> profile(static_cast<std::size_t>(steps));
    bool inside = true;
    for (int j = 0; j < steps && inside; ++j)
      inside = sample(gray, s + (-h + (j + 0.5) * dt) * n, profile[static_cast<std::size_t>(j)]);
    if (!inside) continue;
    us.push_back(u);
    profiles.push_back(std::move(profile));
  }
  if (static_cast<int>(profiles.size()) < kMinProfiles) return false;
  std::vector<double> ins, outs;
  for (const auto& p : profiles) ins.push_back(p.front()), outs.push_back(p.back());
  const double level_in = median(ins), level_out = median(outs);
  if (std::fabs(level_out - level_in) < kMinContrast) return false;

  std::vector<double> es;
  for (const auto& p : profiles) {
    double area = 0;
    for (const double v : p) area += (v - level_in) / (level_out - level_in) * dt;
    es.push_back(h - area);
  }
  // e(u) = alpha + beta u by least squares; profiles off it by more than
  // 3 robust sigmas (a speck of dirt, a particle) dropped once, then refitted.
  std::vector<bool> use(es.size(), true);
  double alpha = 0, beta = 0;
  for (int round = 0; round < 2; ++round) {
    double s1 = 0, su = 0, suu = 0, se = 0, sue = 0;
    for (std::size_t i = 0; i < es.size(); ++i)
      if (use[i]) s1 += 1, su += us[i], suu += us[i] * us[i], se += es[i], sue += us[i] * es[i];
    const double det = s1 * suu - su * su;
    if (s1 < kMinProfiles || !(std::fabs(det) > 0)) return false;
    alpha = (suu * se - su * sue) / det;
    beta = (s1 * sue - su * se) / det;
    if (round == 1) break;
    std::vector<double> residuals;
    for (std::size_t i = 0; i < es.size(); ++i) residuals.push_back(std::fabs(es[i] - alpha - beta * us[i]));
    const double limit = std::max(3 * 1.4826 * median(residuals), 0.05);
    for (std::size_t i = 0; i < es.size(); ++i) use[i] = residuals[i] <= limit;
  }
  line.point = a + alpha * n;
  line.direction = (d + beta * n).normalized();
  return true;
}

// p = l1.point + s l1.direction on l2 (Cramer's rule); false for parallel lines.
bool intersect(const Line& l1, const Line& l2, Eigen::Vector2d& p) {
  const Eigen::Vector2d& d1 = l1.direction;
  const Eigen::Vector2d& d2 = l2.direction;
  const double det = d2.x() * d1.y() - d1.x() * d2.y();
  if (!(std::fabs(det) > 1e-6)) return false;
  const Eigen::Vector2d r = l2.point - l1.point;
  const double s = (d2.x() * r.y() - r.x() * d2.y()) / det;
  p = l1.point + s * d1;
  return true;
}

// Refines a marker's 4 corners (in order around the square, within about a
// pixel of the truth) by the edge fit; `cells`: the square's side in cells.
// False, leaving `corners` alone, when a side cannot be fitted or the corners
// move further than the detector's initial guess can be off.
bool refine_corners(const cv::Mat& gray, int cells, std::array<Eigen::Vector2d, 4>& corners) {
  std::array<Eigen::Vector2d, 4> c = corners;
  double side_px = 0;
  for (int k = 0; k < 4; ++k) side_px += (c[static_cast<std::size_t>((k + 1) % 4)] - c[static_cast<std::size_t>(k)]).norm();
  side_px /= 4;
  for (int iteration = 0; iteration < kIterations; ++iteration) {
    // The first pass reads 3/4 of a cell each side, to catch an edge that far
    // off the detector's guess; then half a cell, clear of the inner bits.
    const Eigen::Vector2d centre = (c[0] + c[1] + c[2] + c[3]) / 4;
    std::array<Line, 4> lines;
    for (std::size_t k = 0; k < 4; ++k)
      if (!fit_side(gray, c[k], c[(k + 1) % 4], centre, cells, iteration == 0 ? 0.75 : 0.5, lines[k])) return false;
    std::array<Eigen::Vector2d, 4> next;
    for (std::size_t k = 0; k < 4; ++k)
      if (!intersect(lines[(k + 3) % 4], lines[k], next[k])) return false;
    double moved = 0;
    for (std::size_t k = 0; k < 4; ++k) moved = std::max(moved, (next[k] - c[k]).norm());
    c = next;
    if (moved < 1e-4) break;
  }
  const double limit = std::max(2.0, 0.5 * side_px / cells);
  for (std::size_t k = 0; k < 4; ++k)
    if (!((c[k] - corners[k]).norm() <= limit)) return false;
  corners = c;
  return true;
}

// The corners of a marker the edge fit gave up on: cornerSubPix in a window
// of 0.4 cells (1 to 5 px half-width), small enough to stay off the inner
// bits; false if a corner moves by more than half a cell (not a corner there).
bool corner_subpix_fallback(const cv::Mat& gray, int cells, std::array<Eigen::Vector2d, 4>& corners) {
  double side_px = 0;
  for (std::size_t k = 0; k < 4; ++k) side_px += (corners[(k + 1) % 4] - corners[k]).norm();
  const double cell_px = side_px / 4 / cells;
  const int half = std::clamp(static_cast<int>(std::lround(0.4 * cell_px)), 1, 5);
  std::vector<cv::Point2f> points;
  for (const Eigen::Vector2d& c : corners) points.emplace_back(static_cast<float>(c.x()), static_cast<float>(c.y()));
  cv::cornerSubPix(gray, points, cv::Size(half, half), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 1e-3));
  for (std::size_t k = 0; k < 4; ++k) {
    const Eigen::Vector2d moved(points[k].x, points[k].y);
    if (!((moved - corners[k]).norm() <= 0.5 * cell_px)) return false;
    corners[k] = moved;
  }
  return true;
}

struct Candidate {
  int id;
  std::array<Eigen::Vector2d, 4> corners_px;
};

}  // namespace

struct MarkerDetector::Impl {
  std::string dictionary;
  int cells = 0;  // the refined square's side in cells
  // ArUco
  cv::Ptr<cv::aruco::Dictionary> aruco;
  cv::Ptr<cv::aruco::DetectorParameters> parameters;
  // AprilTag
  AprilTagFamilyPtr family;
  apriltag_detector_t* detector = nullptr;

  ~Impl() {
    if (detector != nullptr) apriltag_detector_destroy(detector);
  }
  std::vector<Candidate> find_aruco(const cv::Mat& gray) const;
  std::vector<Candidate> find_apriltags(const cv::Mat& gray) const;
};

MarkerDetector::MarkerDetector(const std::string& dictionary, const std::string& source)
    : impl_(std::make_unique<Impl>()) {
  impl_->dictionary = dictionary;
  const int opencv_id = opencv_dictionary_id(dictionary);
  if (opencv_id >= 0) {
    impl_->aruco = cv::aruco::getPredefinedDictionary(opencv_id);
    impl_->cells = impl_->aruco->markerSize + 2;
    impl_->parameters = cv::aruco::DetectorParameters::create();
    // Our edge fit refines; OpenCV's cornerSubPix on the corners of a black
    // border (L-corners, not X-junctions) is pulled inwards by blur and, with
    // its 11 px window, onto the inner bits of small markers.
    impl_->parameters->cornerRefinementMethod = cv::aruco::CORNER_REFINE_NONE;
    return;
  }
  impl_->family = create_apriltag_family(dictionary);
  if (!impl_->family)
    throw InputError(source, "dictionary",
                     fmt::format("'{}' is neither an OpenCV dictionary ({}) nor an AprilTag family ({})", dictionary,
                                 opencv_dictionary_names(), apriltag_family_names()));
  impl_->cells = impl_->family->width_at_border;
  impl_->detector = apriltag_detector_create();
  // One corrected bit, as for aprilgrids: more lets noise (or PIV particles)
  // decode as tags of the small families.
  apriltag_detector_add_family_bits(impl_->detector, impl_->family.get(), 1);
  impl_->detector->quad_decimate = 1.0f;  // full resolution: small tags
  impl_->detector->quad_sigma = 0.0f;
  impl_->detector->refine_edges = true;
  impl_->detector->nthreads = 1;
}

MarkerDetector::~MarkerDetector() = default;
MarkerDetector::MarkerDetector(MarkerDetector&&) noexcept = default;
MarkerDetector& MarkerDetector::operator=(MarkerDetector&&) noexcept = default;

const std::string& MarkerDetector::dictionary() const { return impl_->dictionary; }

std::vector<Candidate> MarkerDetector::Impl::find_aruco(const cv::Mat& gray) const {
  std::vector<std::vector<cv::Point2f>> corners;
  std::vector<int> ids;
  cv::aruco::detectMarkers(gray, aruco, corners, ids, parameters);
  std::vector<Candidate> found;
  // detectMarkers' corners: top-left, top-right, bottom-right, bottom-left of
  // the marker as drawn; contour pixels, within about a pixel of the edge.
  for (std::size_t i = 0; i < ids.size(); ++i) {
    Candidate c{ids[i], {}};
    for (std::size_t k = 0; k < 4; ++k) c.corners_px[k] = Eigen::Vector2d(corners[i][k].x, corners[i][k].y);
    found.push_back(c);
  }
  return found;
}

std::vector<Candidate> MarkerDetector::Impl::find_apriltags(const cv::Mat& gray) const {
  cv::Mat copy = gray.clone();  // libapriltag takes a non-const buffer
  image_u8_t image{copy.cols, copy.rows, static_cast<int32_t>(copy.step[0]), copy.data};
  zarray_t* detections = apriltag_detector_detect(detector, &image);
  std::vector<Candidate> found;
  for (int i = 0; i < zarray_size(detections); ++i) {
    apriltag_detection_t* d = nullptr;
    zarray_get(detections, i, &d);
    Candidate c{d->id, {}};
    for (std::size_t k = 0; k < 4; ++k) {
      const double* p = d->p[kAprilTagCorner[k]];
      c.corners_px[k] = Eigen::Vector2d(p[0] + kAprilTagToGlasspivPx, p[1] + kAprilTagToGlasspivPx);
    }
    found.push_back(c);
  }
  apriltag_detections_destroy(detections);
  return found;
}

MarkerDetection MarkerDetector::detect(const cv::Mat& gray8, const std::string& source) const {
  MarkerDetection result;
  if (gray8.empty()) return result;
  if (gray8.type() != CV_8UC1)
    throw InputError(source, "image", fmt::format("must be 8-bit grey for detection (OpenCV type {})", gray8.type()));
  if (gray8.cols < 2 || gray8.rows < 2) return result;
  const std::vector<Candidate> found = impl_->aruco ? impl_->find_aruco(gray8) : impl_->find_apriltags(gray8);
  std::map<int, int> count;
  for (const Candidate& c : found) ++count[c.id];
  for (const auto& [id, n] : count)
    if (n > 1) result.duplicated_ids.push_back(id);
  for (const Candidate& c : found) {
    if (count[c.id] > 1) continue;
    DetectedMarker m;
    m.id = c.id;
    m.corners_px = c.corners_px;
    if (!refine_corners(gray8, impl_->cells, m.corners_px)) {
      m.edge_fit = false;
      if (!corner_subpix_fallback(gray8, impl_->cells, m.corners_px)) continue;
    }
    result.markers.push_back(m);
  }
  std::sort(result.markers.begin(), result.markers.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
  return result;
}

MarkerDetection detect_markers(const cv::Mat& gray8, const std::string& dictionary, const std::string& source) {
  return MarkerDetector(dictionary, source).detect(gray8, source);
}

}  // namespace glasspiv
