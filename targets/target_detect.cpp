#include "targets/target_detect.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <utility>
#include <vector>

#include <apriltag/apriltag.h>
#include <apriltag/tag36h11.h>
#include <fmt/format.h>
#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "targets/marker_detect.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {

// cornerSubPix's stopping rule everywhere: 30 iterations or a step under 1e-3 px.
const cv::TermCriteria kSubPixCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 1e-3);

// libapriltag puts (0, 0) at the outer corner of the top-left pixel; glasspiv at
// its centre (docs/conventions.md). Measured in tests/targets/target_detect_test.cpp.
constexpr double kAprilTagToGlasspivPx = -0.5;

Eigen::Vector2d map_point(const cv::Matx33d& h, const Eigen::Vector2d& p) {
  const cv::Vec3d q = h * cv::Vec3d(p.x(), p.y(), 1.0);
  return Eigen::Vector2d(q[0] / q[2], q[1] / q[2]);
}

// Bilinear sample at a glasspiv pixel position; false when it is not inside the
// image by a pixel.
bool sample(const cv::Mat& gray, const Eigen::Vector2d& p, double& value) {
  if (!(p.x() >= 1 && p.y() >= 1 && p.x() <= gray.cols - 2 && p.y() <= gray.rows - 2)) return false;
  const int x = static_cast<int>(std::floor(p.x())), y = static_cast<int>(std::floor(p.y()));
  const double fx = p.x() - x, fy = p.y() - y;
  auto at = [&](int yy, int xx) { return static_cast<double>(gray.at<unsigned char>(yy, xx)); };
  value = (1 - fy) * ((1 - fx) * at(y, x) + fx * at(y, x + 1)) + fy * ((1 - fx) * at(y + 1, x) + fx * at(y + 1, x + 1));
  return true;
}

// Mean grey level over the central part of a board square (3 x 3 samples at 30,
// 50, 70 % of its side); false when any sample falls outside the image.
bool square_level(const cv::Mat& gray, const cv::Matx33d& image_from_board, double x0, double y0, double side,
                  double& level) {
  double sum = 0;
  for (const double fy : {0.3, 0.5, 0.7})
    for (const double fx : {0.3, 0.5, 0.7}) {
      double v = 0;
      if (!sample(gray, map_point(image_from_board, Eigen::Vector2d(x0 + fx * side, y0 + fy * side)), v))
        return false;
      sum += v;
    }
  level = sum / 9;
  return true;
}

cv::Matx33d to_matx(const cv::Mat& h) {
  cv::Matx33d m;
  h.convertTo(cv::Mat(3, 3, CV_64F, m.val), CV_64F);
  return m;
}

// A homography image_from_board robust to points off it: RANSAC, then least
// squares on the inliers and reclassification until the inliers settle (OpenCV's
// RANSAC stops early and can leave good points out when a sample extrapolates
// poorly). `inlier[i]`: point i lies within `threshold_px`. False if no fit.
bool robust_homography(const std::vector<cv::Point2f>& board, const std::vector<cv::Point2f>& image,
                       double threshold_px, cv::Matx33d& image_from_board, std::vector<bool>& inlier) {
  std::vector<unsigned char> mask;
  cv::Mat h = cv::findHomography(board, image, cv::RANSAC, threshold_px, mask, 2000, 0.995);
  if (h.empty()) return false;
  inlier.assign(board.size(), false);
  for (std::size_t i = 0; i < board.size(); ++i) inlier[i] = mask[i] != 0;
  for (int round = 0; round < 5; ++round) {
    std::vector<cv::Point2f> b, m;
    for (std::size_t i = 0; i < board.size(); ++i)
      if (inlier[i]) b.push_back(board[i]), m.push_back(image[i]);
    if (b.size() < 4) return false;
    const cv::Mat refined = cv::findHomography(b, m, 0);
    if (refined.empty()) return false;
    image_from_board = to_matx(refined);
    bool changed = false;
    for (std::size_t i = 0; i < board.size(); ++i) {
      const Eigen::Vector2d p = map_point(image_from_board, Eigen::Vector2d(board[i].x, board[i].y));
      const bool in = (p - Eigen::Vector2d(image[i].x, image[i].y)).norm() <= threshold_px;
      changed = changed || in != inlier[i];
      inlier[i] = in;
    }
    if (!changed) break;
  }
  return true;
}

void sort_by_id(std::vector<CornerObservation>& corners) {
  std::sort(corners.begin(), corners.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
}

// ---------------------------------------------------------------- chessboard

// One attempt at finding a chessboard: which OpenCV finder, with which flags.
struct ChessboardAttempt {
  bool sector_based;
  int flags;
};

// The attempts, in order; the first to find the board wins. OpenCV's finders
// only report a board of exactly the pattern's size, and the sector-based one's
// outcome is not monotonic in its flags. CALIB_CB_EXHAUSTIVE raises its key
// points from 100 to 1000 (and its seeds from 30 to 100); the weak points it
// adds can include points along the board's outer edge, where the outer squares
// meet a narrow margin and a dark frame (made more contrasty by
// CALIB_CB_NORMALIZE_IMAGE's histogram equalisation). Every seed's board then
// grows by that spurious row, is larger than the pattern and is thrown away:
// OpenCV's right09.jpg, whose board with CALIB_CB_LARGER added comes out 9 x 7
// for 9 x 6, the extra row on the edge; without either CALIB_CB_EXHAUSTIVE or
// the equalisation it is found. So a miss is retried without
// CALIB_CB_EXHAUSTIVE, then by the classic finder, another algorithm.
std::vector<ChessboardAttempt> chessboard_attempts(DetectOptions::ChessboardMethod method) {
  const ChessboardAttempt sb_exhaustive{
      true, cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_EXHAUSTIVE | cv::CALIB_CB_ACCURACY};
  const ChessboardAttempt sb{true, cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_ACCURACY};
  const ChessboardAttempt classic{
      false, cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_FAST_CHECK};
  if (method == DetectOptions::ChessboardMethod::sector_based) return {sb_exhaustive, sb, classic};
  return {classic, sb_exhaustive, sb};
}

std::vector<cv::Point2f> find_chessboard(const cv::Mat& gray, const TargetSpec& spec,
                                         DetectOptions::ChessboardMethod method) {
  const cv::Size pattern(spec.squares_x - 1, spec.squares_y - 1);
  std::vector<cv::Point2f> corners;
  bool found = false;
  for (const ChessboardAttempt& attempt : chessboard_attempts(method)) {
    corners.clear();
    found = attempt.sector_based ? cv::findChessboardCornersSB(gray, pattern, corners, attempt.flags)
                                 : cv::findChessboardCorners(gray, pattern, corners, attempt.flags);
    if (found && corners.size() == static_cast<std::size_t>(pattern.area())) break;
    found = false;
  }
  if (!found) return {};
  // Whichever finder found them, the corners are refined by cornerSubPix: an
  // 11 x 11 window, smaller where the squares are too small for it (it must not
  // reach the neighbouring corners).
  double spacing = 1e30;
  for (int r = 0; r < pattern.height; ++r)
    for (int c = 0; c + 1 < pattern.width; ++c)
      spacing = std::min(spacing, cv::norm(corners[static_cast<std::size_t>(r * pattern.width + c + 1)] -
                                           corners[static_cast<std::size_t>(r * pattern.width + c)]));
  const int half = std::clamp(static_cast<int>(spacing / 2) - 1, 2, 5);
  cv::cornerSubPix(gray, corners, cv::Size(half, half), cv::Size(-1, -1), kSubPixCriteria);
  return corners;
}

// OpenCV orders a chessboard's corners row by row, but may start at any of its
// four corners and run either way round. Puts corner 0 at the board's top-left
// inner corner: the ordering must not mirror the board (seen from the front), and
// the top-left square of the pattern is black.
void orient_chessboard(const cv::Mat& gray, const TargetSpec& spec, std::vector<cv::Point2f>& corners) {
  const int w = spec.squares_x - 1, h = spec.squares_y - 1;
  auto at = [&](int c, int r) -> cv::Point2f& { return corners[static_cast<std::size_t>(r * w + c)]; };
  const cv::Point2f along = at(w - 1, 0) - at(0, 0), down = at(0, h - 1) - at(0, 0);
  if (along.x * down.y - along.y * down.x < 0)
    for (int r = 0; r < h; ++r) std::reverse(corners.begin() + r * w, corners.begin() + (r + 1) * w);

  std::vector<cv::Point2f> board;
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c)
      board.emplace_back(static_cast<float>((c + 1) * spec.square_size_mm),
                         static_cast<float>((r + 1) * spec.square_size_mm));
  const cv::Mat hm = cv::findHomography(board, corners, 0);
  if (hm.empty()) return;
  const cv::Matx33d image_from_board = to_matx(hm);
  // The four corner squares: with one square count odd and the other even the
  // 180-degree turn swaps their colours.
  double black = 0, white = 0;
  int n_black = 0, n_white = 0;
  for (const int c : {0, spec.squares_x - 1})
    for (const int r : {0, spec.squares_y - 1}) {
      double level = 0;
      if (!square_level(gray, image_from_board, c * spec.square_size_mm, r * spec.square_size_mm,
                        spec.square_size_mm, level))
        continue;
      if (square_is_black(spec, c, r)) black += level, ++n_black;
      else white += level, ++n_white;
    }
  if (n_black > 0 && n_white > 0 && black / n_black > white / n_white)
    std::reverse(corners.begin(), corners.end());
}

// ---------------------------------------------------------------- charuco

// One ChArUco layout: its markers, and for every charuco corner the markers
// next to it (the two nearest; OpenCV's nearestMarkerIdx) with the index of
// their corner nearest to it (nearestMarkerCorners).
struct CharucoLayoutModel {
  TargetSpec spec;
  int marker_cells = 0;                // data bits + the black border, per side
  std::map<int, BoardMarker> markers;  // by dictionary id
  struct Neighbour {
    int id, corner;
  };
  std::vector<std::vector<Neighbour>> neighbours;  // by charuco corner id
};

CharucoLayoutModel make_charuco_model(const TargetSpec& spec, const cv::aruco::Dictionary& dictionary) {
  CharucoLayoutModel model;
  model.spec = spec;
  model.marker_cells = dictionary.markerSize + 2;
  const std::vector<BoardMarker> markers = board_markers(spec);
  for (const BoardMarker& m : markers) model.markers[m.id] = m;
  const double tolerance = std::pow(0.01 * spec.square_size_mm, 2);
  for (const BoardCorner& corner : board_corners(spec)) {
    const Eigen::Vector2d p = corner.point_mm.head<2>();
    double nearest = 1e300;
    for (const BoardMarker& m : markers)
      nearest = std::min(nearest, (m.top_left_mm + Eigen::Vector2d::Constant(m.size_mm / 2) - p).squaredNorm());
    std::vector<CharucoLayoutModel::Neighbour> next;
    for (const BoardMarker& m : markers) {
      if ((m.top_left_mm + Eigen::Vector2d::Constant(m.size_mm / 2) - p).squaredNorm() > nearest + tolerance) continue;
      // Marker corners 0..3: top-left, top-right, bottom-right, bottom-left.
      const Eigen::Vector2d at[4] = {m.top_left_mm, m.top_left_mm + Eigen::Vector2d(m.size_mm, 0),
                                     m.top_left_mm + Eigen::Vector2d(m.size_mm, m.size_mm),
                                     m.top_left_mm + Eigen::Vector2d(0, m.size_mm)};
      int best = 0;
      for (int k = 1; k < 4; ++k)
        if ((at[k] - p).squaredNorm() < (at[best] - p).squaredNorm()) best = k;
      next.push_back({m.id, best});
    }
    model.neighbours.push_back(next);
  }
  return model;
}

struct MarkerDetections {
  std::vector<std::vector<cv::Point2f>> corners;
  std::vector<int> ids;
};

// How well the detected markers fit one layout: markers off a common homography
// (RANSAC, 3/4 of a square) and black squares of the layout, next to a fitting
// marker and wholly in the image, that look white.
struct LayoutFit {
  MarkerDetections inliers;
  int outliers = 0;
  int bright_black_squares = 0;
  int problems() const { return outliers + bright_black_squares; }
};

LayoutFit fit_layout(const CharucoLayoutModel& model, const MarkerDetections& found, const cv::Mat& gray) {
  LayoutFit fit;
  const TargetSpec& spec = model.spec;
  std::vector<cv::Point2f> board, image;
  double side_px = 0;
  for (std::size_t i = 0; i < found.ids.size(); ++i) {
    const BoardMarker& m = model.markers.at(found.ids[i]);
    const double s = m.size_mm;
    const double dx[4] = {0, s, s, 0}, dy[4] = {0, 0, s, s};
    for (int k = 0; k < 4; ++k) {
      board.emplace_back(static_cast<float>(m.top_left_mm.x() + dx[k]), static_cast<float>(m.top_left_mm.y() + dy[k]));
      image.push_back(found.corners[i][static_cast<std::size_t>(k)]);
      side_px += cv::norm(found.corners[i][static_cast<std::size_t>(k)] - found.corners[i][static_cast<std::size_t>((k + 1) % 4)]);
    }
  }
  side_px /= static_cast<double>(image.size());
  const double square_px = side_px * spec.square_size_mm / spec.marker_size_mm;
  cv::Matx33d image_from_board;
  std::vector<bool> inlier;
  if (!robust_homography(board, image, 0.75 * square_px, image_from_board, inlier)) {
    fit.outliers = static_cast<int>(found.ids.size());
    return fit;
  }
  for (std::size_t i = 0; i < found.ids.size(); ++i) {
    bool all = true;
    for (std::size_t k = 0; k < 4; ++k) all = all && inlier[4 * i + k];
    if (!all) {
      ++fit.outliers;
      continue;
    }
    fit.inliers.ids.push_back(found.ids[i]);
    fit.inliers.corners.push_back(found.corners[i]);
  }
  if (fit.inliers.ids.size() < 2) return fit;

  // Grey levels of ink and paper next to the fitting markers: the centres of
  // their black border cells, and the white ring between marker and square.
  const int cells = model.marker_cells;
  double ink = 0, paper = 0;
  int n_ink = 0, n_paper = 0;
  std::set<std::pair<int, int>> marker_squares;
  for (const int id : fit.inliers.ids) {
    const BoardMarker& m = model.markers.at(id);
    marker_squares.insert({m.col, m.row});
    const double cell = m.size_mm / cells, ring = (spec.square_size_mm - spec.marker_size_mm) / 4;
    for (int i = 0; i < cells; ++i) {
      const double t = (i + 0.5) * cell;
      const Eigen::Vector2d o = m.top_left_mm;
      const Eigen::Vector2d border[4] = {o + Eigen::Vector2d(t, cell / 2), o + Eigen::Vector2d(t, m.size_mm - cell / 2),
                                         o + Eigen::Vector2d(cell / 2, t), o + Eigen::Vector2d(m.size_mm - cell / 2, t)};
      const Eigen::Vector2d outside[4] = {o + Eigen::Vector2d(t, -ring), o + Eigen::Vector2d(t, m.size_mm + ring),
                                          o + Eigen::Vector2d(-ring, t), o + Eigen::Vector2d(m.size_mm + ring, t)};
      for (int k = 0; k < 4; ++k) {
        double v = 0;
        if (sample(gray, map_point(image_from_board, border[k]), v)) ink += v, ++n_ink;
        if (sample(gray, map_point(image_from_board, outside[k]), v)) paper += v, ++n_paper;
      }
    }
  }
  if (n_ink == 0 || n_paper == 0) return fit;
  ink /= n_ink;
  paper /= n_paper;
  if (paper - ink < 10) return fit;  // too little contrast to judge squares by
  const double threshold = (ink + paper) / 2;
  for (int r = 0; r < spec.squares_y; ++r)
    for (int c = 0; c < spec.squares_x; ++c) {
      if (!square_is_black(spec, c, r)) continue;
      bool near = false;
      for (int dr = -1; dr <= 1 && !near; ++dr)
        for (int dc = -1; dc <= 1 && !near; ++dc) near = marker_squares.count({c + dc, r + dr}) > 0;
      if (!near) continue;
      double level = 0;
      if (!square_level(gray, image_from_board, c * spec.square_size_mm, r * spec.square_size_mm,
                        spec.square_size_mm, level))
        continue;
      if (level > threshold) ++fit.bright_black_squares;
    }
  return fit;
}

// ---------------------------------------------------------------- aprilgrid

struct AprilTagDetector {
  apriltag_family_t* family = nullptr;
  apriltag_detector_t* detector = nullptr;
  AprilTagDetector() {
    family = tag36h11_create();
    detector = apriltag_detector_create();
    apriltag_detector_add_family_bits(detector, family, 1);
    detector->quad_decimate = 1.0f;  // full resolution: decimation costs corner accuracy
    detector->quad_sigma = 0.0f;
    detector->refine_edges = true;
    detector->nthreads = 1;
  }
  ~AprilTagDetector() {
    apriltag_detector_destroy(detector);
    tag36h11_destroy(family);
  }
  AprilTagDetector(const AprilTagDetector&) = delete;
  AprilTagDetector& operator=(const AprilTagDetector&) = delete;
};

// libapriltag's p[0..3] for a tag upright in the image: top-right, top-left,
// bottom-left, bottom-right (measured on rendered tags, whatever its header's
// "counter-clockwise" means). board_corners() numbers top-left, top-right,
// bottom-right, bottom-left: ours k is libapriltag's kAprilTagCorner[k].
constexpr int kAprilTagCorner[4] = {1, 0, 3, 2};

}  // namespace

struct TargetDetector::Impl {
  TargetSpec spec;
  DetectOptions options;
  std::vector<BoardCorner> corners;  // by id
  // charuco
  cv::Ptr<cv::aruco::Dictionary> dictionary;
  cv::Ptr<cv::aruco::DetectorParameters> parameters;
  CharucoLayoutModel model, other_model;  // the requested layout, and the other one
  // aprilgrid
  std::unique_ptr<AprilTagDetector> apriltag;
  // aruco_marker, apriltag
  std::unique_ptr<MarkerDetector> markers;

  DetectionResult detect_chessboard(const cv::Mat& gray, DetectionResult result) const;
  DetectionResult detect_charuco(const cv::Mat& gray, DetectionResult result) const;
  DetectionResult detect_aprilgrid(const cv::Mat& gray, DetectionResult result) const;
  DetectionResult detect_single_marker(const cv::Mat& gray, const std::string& source, DetectionResult result) const;
  CornerObservation observation(int id, double x, double y) const {
    CornerObservation o;
    o.id = id;
    o.pixel_px = Eigen::Vector2d(x, y);
    o.board_point_mm = corners[static_cast<std::size_t>(id)].point_mm;
    return o;
  }
};

TargetDetector::TargetDetector(const TargetSpec& spec, DetectOptions options) : impl_(std::make_unique<Impl>()) {
  validate_target(spec);
  require_target_corners(spec, "", "a TargetDetector");
  impl_->spec = spec;
  impl_->options = options;
  impl_->corners = board_corners(spec);
  if (spec.kind == TargetKind::charuco) {
    impl_->dictionary = cv::aruco::getPredefinedDictionary(opencv_dictionary_id(spec.dictionary));
    impl_->parameters = cv::aruco::DetectorParameters::create();
    impl_->parameters->cornerRefinementMethod = cv::aruco::CORNER_REFINE_NONE;
    impl_->model = make_charuco_model(spec, *impl_->dictionary);
    TargetSpec other = spec;
    other.charuco_layout =
        spec.charuco_layout == CharucoLayout::opencv ? CharucoLayout::legacy : CharucoLayout::opencv;
    impl_->other_model = make_charuco_model(other, *impl_->dictionary);
  } else if (spec.kind == TargetKind::aprilgrid) {
    impl_->apriltag = std::make_unique<AprilTagDetector>();
  } else if (is_single_marker(spec.kind)) {
    impl_->markers = std::make_unique<MarkerDetector>(spec.dictionary);
  }
}

TargetDetector::~TargetDetector() = default;
TargetDetector::TargetDetector(TargetDetector&&) noexcept = default;
TargetDetector& TargetDetector::operator=(TargetDetector&&) noexcept = default;

const TargetSpec& TargetDetector::spec() const { return impl_->spec; }

DetectionResult TargetDetector::detect(const cv::Mat& gray, const std::string& source) const {
  if (gray.empty()) throw InputError(source, "image", "is empty");
  if (gray.type() != CV_8UC1)
    throw InputError(source, "image", fmt::format("must be 8-bit grey for detection (OpenCV type {})", gray.type()));
  DetectionResult result;
  result.view.source = source;
  switch (impl_->spec.kind) {
    case TargetKind::chessboard: result = impl_->detect_chessboard(gray, std::move(result)); break;
    case TargetKind::charuco: result = impl_->detect_charuco(gray, std::move(result)); break;
    case TargetKind::aprilgrid: result = impl_->detect_aprilgrid(gray, std::move(result)); break;
    case TargetKind::aruco_marker:
    case TargetKind::apriltag: result = impl_->detect_single_marker(gray, source, std::move(result)); break;
    case TargetKind::speckle: break;  // refused by the constructor
  }
  sort_by_id(result.view.corners);
  return result;
}

DetectionResult TargetDetector::Impl::detect_chessboard(const cv::Mat& gray, DetectionResult result) const {
  std::vector<cv::Point2f> found = find_chessboard(gray, spec, options.chessboard);
  if (found.empty()) {
    result.note = "no chessboard found";
    return result;
  }
  orient_chessboard(gray, spec, found);
  for (std::size_t id = 0; id < found.size(); ++id)
    result.view.corners.push_back(observation(static_cast<int>(id), found[id].x, found[id].y));
  return result;
}

DetectionResult TargetDetector::Impl::detect_charuco(const cv::Mat& gray, DetectionResult result) const {
  MarkerDetections all;
  cv::aruco::detectMarkers(gray, dictionary, all.corners, all.ids, parameters);
  // Keep the board's markers; an id seen twice is dropped (which one is real?).
  std::map<int, int> count;
  for (const int id : all.ids) ++count[id];
  MarkerDetections found;
  for (std::size_t i = 0; i < all.ids.size(); ++i)
    if (model.markers.count(all.ids[i]) && count[all.ids[i]] == 1) {
      found.ids.push_back(all.ids[i]);
      found.corners.push_back(all.corners[i]);
    }
  result.markers_found = static_cast<int>(found.ids.size());
  if (found.ids.size() < 2) {
    result.note = fmt::format("{} of the board's markers found, need 2", found.ids.size());
    return result;
  }

  const LayoutFit fit = fit_layout(model, found, gray);
  if (spec.squares_y % 2 == 0) {
    // Even rows: the two layouts place the markers differently; see which one the
    // photo shows.
    const LayoutFit other = fit_layout(other_model, found, gray);
    const std::string requested = charuco_layout_name(spec.charuco_layout);
    const std::string other_name = charuco_layout_name(other_model.spec.charuco_layout);
    if (fit.problems() > 0 && other.problems() == 0) {
      result.note = fmt::format("the markers match the {} layout, not the requested {} layout (set charuco_layout: {})",
                                other_name, requested, other_name);
      return result;
    }
    if (fit.problems() >= other.problems() && fit.problems() > 0) {
      result.note = fmt::format("the markers fit neither layout ({} layout: {} markers out of place, {} black squares "
                                "look white)",
                                requested, fit.outliers, fit.bright_black_squares);
      return result;
    }
    if (fit.problems() == 0 && other.problems() == 0 && options.require_layout_evidence) {
      result.note = fmt::format("this view cannot tell the {} layout from the {} layout (neither side edge of the "
                                "board is visible); skipped",
                                requested, other_name);
      return result;
    }
  }
  if (fit.inliers.ids.size() < 2) {
    result.note = fmt::format("the {} markers found do not lie on one board", found.ids.size());
    return result;
  }

  // Interpolate and refine as OpenCV's interpolateCornersCharuco does (the
  // corner predicted by the local homography of each of its two neighbouring
  // markers, averaged, then cornerSubPix), but with our own refinement: OpenCV
  // 4.6 sizes its window by the Euclidean distance to the nearest marker corner,
  // which lets small boards' corners snap onto marker corners (4 px errors
  // measured at 30 px squares), stops at 0.1 px and shifts its result by half a
  // pixel (opencv_contrib #3024). Here the window stays clear of the marker
  // corners along both axes and iterates to 1e-3 px, in glasspiv's convention.
  std::map<int, std::size_t> marker_index;
  for (std::size_t i = 0; i < fit.inliers.ids.size(); ++i) marker_index[fit.inliers.ids[i]] = i;
  std::map<int, cv::Matx33d> image_from_marker;
  for (const auto& [id, i] : marker_index) {
    const BoardMarker& m = model.markers.at(id);
    const cv::Point2f board[4] = {
        {static_cast<float>(m.top_left_mm.x()), static_cast<float>(m.top_left_mm.y())},
        {static_cast<float>(m.top_left_mm.x() + m.size_mm), static_cast<float>(m.top_left_mm.y())},
        {static_cast<float>(m.top_left_mm.x() + m.size_mm), static_cast<float>(m.top_left_mm.y() + m.size_mm)},
        {static_cast<float>(m.top_left_mm.x()), static_cast<float>(m.top_left_mm.y() + m.size_mm)}};
    image_from_marker[id] = to_matx(cv::getPerspectiveTransform(board, fit.inliers.corners[i].data()));
  }
  int dropped = 0;
  for (std::size_t id = 0; id < model.neighbours.size(); ++id) {
    const auto& next = model.neighbours[id];
    bool all = !next.empty();
    for (const auto& n : next) all = all && marker_index.count(n.id) > 0;
    if (!all) continue;  // both neighbouring markers must be seen (OpenCV's minMarkers = 2)
    const Eigen::Vector2d board_point = corners[id].point_mm.head<2>();
    Eigen::Vector2d guess = Eigen::Vector2d::Zero();
    for (const auto& n : next) guess += map_point(image_from_marker.at(n.id), board_point);
    guess /= static_cast<double>(next.size());
    if (!(guess.x() >= 2 && guess.y() >= 2 && guess.x() <= gray.cols - 3 && guess.y() <= gray.rows - 3)) continue;
    double clearance = 1e30;  // per-axis distance to the nearest marker corner, px
    for (const auto& n : next) {
      const cv::Point2f c = fit.inliers.corners[marker_index.at(n.id)][static_cast<std::size_t>(n.corner)];
      clearance = std::min(clearance, std::max(std::fabs(c.x - guess.x()), std::fabs(c.y - guess.y())));
    }
    const int half = std::clamp(static_cast<int>(clearance) - 2, 2, 10);
    std::vector<cv::Point2f> refined{cv::Point2f(static_cast<float>(guess.x()), static_cast<float>(guess.y()))};
    cv::cornerSubPix(gray, refined, cv::Size(half, half), cv::Size(-1, -1), kSubPixCriteria);
    if ((Eigen::Vector2d(refined[0].x, refined[0].y) - guess).norm() > 0.5 * clearance) {
      ++dropped;  // ran off towards something else than the X-junction
      continue;
    }
    result.view.corners.push_back(observation(static_cast<int>(id), refined[0].x, refined[0].y));
  }
  if (result.view.corners.empty() && result.note.empty())
    result.note = "no charuco corner between two found markers";
  else if (fit.outliers > 0 || dropped > 0)
    result.note = fmt::format("{} markers out of place ignored, {} corners lost in refinement", fit.outliers, dropped);
  return result;
}

DetectionResult TargetDetector::Impl::detect_aprilgrid(const cv::Mat& gray, DetectionResult result) const {
  cv::Mat copy = gray.clone();  // libapriltag takes a non-const buffer
  image_u8_t image{copy.cols, copy.rows, static_cast<int32_t>(copy.step[0]), copy.data};
  zarray_t* detections = apriltag_detector_detect(apriltag->detector, &image);
  const int n_tags = spec.squares_x * spec.squares_y;
  std::map<int, std::vector<Eigen::Vector2d>> tags;  // tag index -> our corners 0..3
  std::map<int, int> count;
  for (int i = 0; i < zarray_size(detections); ++i) {
    apriltag_detection_t* d = nullptr;
    zarray_get(detections, i, &d);
    const int index = d->id - spec.first_id;
    if (index < 0 || index >= n_tags) continue;
    ++count[index];
    std::vector<Eigen::Vector2d> p(4);
    for (int k = 0; k < 4; ++k)
      p[static_cast<std::size_t>(k)] = Eigen::Vector2d(d->p[kAprilTagCorner[k]][0] + kAprilTagToGlasspivPx,
                                                       d->p[kAprilTagCorner[k]][1] + kAprilTagToGlasspivPx);
    tags[index] = p;
  }
  apriltag_detections_destroy(detections);
  for (const auto& [index, n] : count)
    if (n > 1) tags.erase(index);
  result.markers_found = static_cast<int>(tags.size());
  if (tags.empty()) {
    result.note = "no tag of the grid found";
    return result;
  }

  // Drop tags off a common homography (RANSAC at half a tag): misread ids.
  std::vector<int> keep;
  if (tags.size() >= 2) {
    std::vector<cv::Point2f> board, image;
    std::vector<int> order;
    double side_px = 0;
    for (const auto& [index, p] : tags) {
      order.push_back(index);
      for (int k = 0; k < 4; ++k) {
        const Eigen::Vector3d& b = corners[static_cast<std::size_t>(4 * index + k)].point_mm;
        board.emplace_back(static_cast<float>(b.x()), static_cast<float>(b.y()));
        image.emplace_back(static_cast<float>(p[static_cast<std::size_t>(k)].x()),
                           static_cast<float>(p[static_cast<std::size_t>(k)].y()));
        side_px += (p[static_cast<std::size_t>(k)] - p[static_cast<std::size_t>((k + 1) % 4)]).norm();
      }
    }
    side_px /= static_cast<double>(image.size());
    cv::Matx33d image_from_board;
    std::vector<bool> inlier;
    const bool ok = robust_homography(board, image, 0.5 * side_px, image_from_board, inlier);
    for (std::size_t t = 0; t < order.size(); ++t) {
      bool all = ok;
      for (std::size_t k = 0; k < 4 && all; ++k) all = inlier[4 * t + k];
      if (all) keep.push_back(order[t]);
    }
  } else {
    keep.push_back(tags.begin()->first);
  }
  if (keep.size() < tags.size())
    result.note = fmt::format("{} tags out of place ignored", tags.size() - keep.size());
  for (const int index : keep)
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector2d& p = tags[index][static_cast<std::size_t>(k)];
      result.view.corners.push_back(observation(4 * index + k, p.x(), p.y()));
    }
  return result;
}

// The marker of the spec's id among all of its dictionary (detect_markers: the
// same detection and corner refinement).
DetectionResult TargetDetector::Impl::detect_single_marker(const cv::Mat& gray, const std::string& source,
                                                           DetectionResult result) const {
  const MarkerDetection found = markers->detect(gray, source);
  const int id = spec.first_id;
  if (std::binary_search(found.duplicated_ids.begin(), found.duplicated_ids.end(), id)) {
    result.note = fmt::format("{} id {} is seen more than once; which one is the target?", spec.dictionary, id);
    return result;
  }
  for (const DetectedMarker& m : found.markers) {
    if (m.id != id) continue;
    result.markers_found = 1;
    for (int k = 0; k < 4; ++k)
      result.view.corners.push_back(
          observation(k, m.corners_px[static_cast<std::size_t>(k)].x(), m.corners_px[static_cast<std::size_t>(k)].y()));
    return result;
  }
  result.note = fmt::format("{} id {} not found ({} other markers of the dictionary seen)", spec.dictionary, id,
                            found.markers.size());
  return result;
}

ViewObservations detect_target(const cv::Mat& gray, const TargetSpec& spec, const std::string& source) {
  return TargetDetector(spec).detect(gray, source).view;
}

}  // namespace glasspiv
