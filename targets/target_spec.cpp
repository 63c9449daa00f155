#include "targets/target_spec.h"

#include <cmath>

#include <apriltag/apriltag.h>
#include <apriltag/tag16h5.h>
#include <apriltag/tag25h9.h>
#include <apriltag/tag36h11.h>
#include <apriltag/tagCircle21h7.h>
#include <apriltag/tagStandard41h12.h>
#include <fmt/format.h>
#include <opencv2/aruco/dictionary.hpp>

#include "targets/speckle_plate.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {

struct DictionaryName {
  const char* name;
  int id;
};

const DictionaryName kDictionaries[] = {
    {"DICT_4X4_50", cv::aruco::DICT_4X4_50},
    {"DICT_4X4_100", cv::aruco::DICT_4X4_100},
    {"DICT_4X4_250", cv::aruco::DICT_4X4_250},
    {"DICT_4X4_1000", cv::aruco::DICT_4X4_1000},
    {"DICT_5X5_50", cv::aruco::DICT_5X5_50},
    {"DICT_5X5_100", cv::aruco::DICT_5X5_100},
    {"DICT_5X5_250", cv::aruco::DICT_5X5_250},
    {"DICT_5X5_1000", cv::aruco::DICT_5X5_1000},
    {"DICT_6X6_50", cv::aruco::DICT_6X6_50},
    {"DICT_6X6_100", cv::aruco::DICT_6X6_100},
    {"DICT_6X6_250", cv::aruco::DICT_6X6_250},
    {"DICT_6X6_1000", cv::aruco::DICT_6X6_1000},
    {"DICT_7X7_50", cv::aruco::DICT_7X7_50},
    {"DICT_7X7_100", cv::aruco::DICT_7X7_100},
    {"DICT_7X7_250", cv::aruco::DICT_7X7_250},
    {"DICT_7X7_1000", cv::aruco::DICT_7X7_1000},
    {"DICT_ARUCO_ORIGINAL", cv::aruco::DICT_ARUCO_ORIGINAL},
    {"DICT_APRILTAG_16h5", cv::aruco::DICT_APRILTAG_16h5},
    {"DICT_APRILTAG_25h9", cv::aruco::DICT_APRILTAG_25h9},
    {"DICT_APRILTAG_36h10", cv::aruco::DICT_APRILTAG_36h10},
    {"DICT_APRILTAG_36h11", cv::aruco::DICT_APRILTAG_36h11},
};

// The libapriltag families glasspiv prints and detects. Larger ones
// (tagStandard52h13, tagCircle49h12) need decoding tables of 100 MB and more.
struct AprilTagFamilyName {
  const char* name;
  apriltag_family_t* (*create)();
  void (*destroy)(apriltag_family_t*);
};

const AprilTagFamilyName kAprilTagFamilies[] = {
    {"tag16h5", tag16h5_create, tag16h5_destroy},
    {"tag25h9", tag25h9_create, tag25h9_destroy},
    {"tag36h11", tag36h11_create, tag36h11_destroy},
    {"tagCircle21h7", tagCircle21h7_create, tagCircle21h7_destroy},
    {"tagStandard41h12", tagStandard41h12_create, tagStandard41h12_destroy},
};

constexpr int kMaxSquares = kMaxTargetSquares;
constexpr int kTag36h11Codes = 587;

// Field names as the target YAML spells them (docs/targets.md).
const char* squares_field(const TargetSpec& s) { return s.kind == TargetKind::aprilgrid ? "tags" : "squares"; }
const char* size_field(const TargetSpec& s) {
  switch (s.kind) {
    case TargetKind::aprilgrid: case TargetKind::apriltag: return "tag_size_mm";
    case TargetKind::aruco_marker: return "marker_size_mm";
    default: return "square_size_mm";
  }
}
const char* id_field(const TargetSpec& s) {
  switch (s.kind) {
    case TargetKind::aruco_marker: return "marker_id";
    case TargetKind::apriltag: return "tag_id";
    default: return "first_id";
  }
}

// Where a single marker's detected square starts in its pattern, mm.
double single_marker_inset_mm(const TargetSpec& s) {
  if (s.kind != TargetKind::apriltag) return 0;
  const AprilTagFamilyInfo f = apriltag_family_info(s.dictionary);
  return f.codes == 0 ? 0 : s.marker_size_mm * f.inset_cells / f.border_cells;
}
bool legacy_even(const TargetSpec& s) {
  return s.kind == TargetKind::charuco && s.charuco_layout == CharucoLayout::legacy && s.squares_y % 2 == 0;
}

int marker_count(const TargetSpec& s) {
  if (s.kind == TargetKind::aprilgrid) return s.squares_x * s.squares_y;
  if (s.kind == TargetKind::chessboard) return 0;
  int n = 0;
  for (int r = 0; r < s.squares_y; ++r)
    for (int c = 0; c < s.squares_x; ++c) n += square_is_black(s, c, r) ? 0 : 1;
  return n;
}

// A length in mm within [kMinTargetLengthMm, kMaxTargetLengthMm].
void check_length(double value, const std::string& field, const std::string& file) {
  if (!std::isfinite(value) || !(value > 0))
    throw InputError(file, field, fmt::format("must be a positive length in mm, got {}", value));
  if (value < kMinTargetLengthMm)
    throw InputError(file, field, fmt::format("{} mm is less than {} mm, the smallest length a target may have", value,
                                              kMinTargetLengthMm));
  if (value > kMaxTargetLengthMm)
    throw InputError(file, field, fmt::format("{} mm is more than {} mm; the unit is mm", value, kMaxTargetLengthMm));
}

// Any kind but speckle: the plate fields stay zero.
void refuse_speckle_fields(const TargetSpec& s, const std::string& file) {
  const std::string problem = "applies to speckle plates only";
  if (s.plate_size_mm != Eigen::Vector2d::Zero()) throw InputError(file, "plate_size_mm", problem);
  if (s.dot_diameter_mm != 0) throw InputError(file, "dot_diameter_mm", problem);
  if (s.fill != 0) throw InputError(file, "fill", problem);
  if (s.seed != 0) throw InputError(file, "seed", problem);
}

void validate_speckle(const TargetSpec& s, const std::string& file) {
  auto fail = [&](const std::string& field, const std::string& problem) { throw InputError(file, field, problem); };
  const std::string none = "a speckle plate has no squares or markers";
  if (s.squares_x != 0 || s.squares_y != 0) fail("squares", none);
  if (s.square_size_mm != 0) fail("square_size_mm", none);
  if (s.marker_size_mm != 0) fail("marker_size_mm", none);
  if (!s.dictionary.empty()) fail("dictionary", none);
  if (s.first_id != 0) fail("first_id", none);
  if (s.charuco_layout != CharucoLayout::opencv) fail("charuco_layout", "applies to charuco boards only");
  for (int k = 0; k < 2; ++k) {
    const double side = s.plate_size_mm[k];
    const std::string field = fmt::format("plate_size_mm[{}]", k);
    check_length(side, field, file);
    if (side > kMaxTargetPatternMm)
      fail(field, fmt::format("{} mm is more than the {} mm across and down a target may have", side,
                              kMaxTargetPatternMm));
  }
  check_length(s.dot_diameter_mm, "dot_diameter_mm", file);
  if (!std::isfinite(s.fill) || !(s.fill > 0) || !(s.fill <= kMaxSpeckleFill))
    fail("fill", fmt::format("{} is not in (0, {}]: the fraction of the plate inked", s.fill, kMaxSpeckleFill));
  const double shortest = s.plate_size_mm.minCoeff();
  if (shortest < kMinSpeckleDotsAcross * s.dot_diameter_mm)
    fail("plate_size_mm", fmt::format("{:.6g} mm is less than {} dot diameters ({} mm) across", shortest,
                                      kMinSpeckleDotsAcross, kMinSpeckleDotsAcross * s.dot_diameter_mm));
  // The dot count, from the pitch before rounding to cells (no overflow).
  const double pitch = s.dot_diameter_mm / speckle_diameter_over_pitch(s.fill);
  const double dots = (s.plate_size_mm.x() / pitch + 0.5) * (s.plate_size_mm.y() / pitch + 0.5);
  if (dots > kMaxSpeckleDots)
    fail("dot_diameter_mm", fmt::format("{} mm dots at fill {} make about {:.3g} dots on a {} x {} mm plate, more "
                                        "than the {:.3g} a plate may have",
                                        s.dot_diameter_mm, s.fill, dots, s.plate_size_mm.x(), s.plate_size_mm.y(),
                                        kMaxSpeckleDots));
}

void validate_single_marker(const TargetSpec& s, const std::string& file) {
  auto fail = [&](const std::string& field, const std::string& problem) { throw InputError(file, field, problem); };
  const bool aruco = s.kind == TargetKind::aruco_marker;
  const std::string what = aruco ? "an ArUco marker" : "an AprilTag";
  if (s.squares_x != 0 || s.squares_y != 0)
    fail("squares", fmt::format("[{}, {}]: {} is a single marker, it has no squares", s.squares_x, s.squares_y, what));
  if (s.square_size_mm != 0)
    fail("square_size_mm", fmt::format("{} has no squares; its size is {}", what, size_field(s)));
  if (s.charuco_layout != CharucoLayout::opencv) fail("charuco_layout", "applies to charuco boards only");
  check_length(s.marker_size_mm, size_field(s), file);
  int size = 0;
  if (aruco) {
    size = opencv_dictionary_size(s.dictionary);
    if (size == 0)
      fail("dictionary", fmt::format("'{}' is not an OpenCV dictionary (known: {})", s.dictionary,
                                     opencv_dictionary_names()));
  } else {
    size = apriltag_family_info(s.dictionary).codes;
    if (size == 0)
      fail("dictionary", fmt::format("'{}' is not an AprilTag family glasspiv knows ({})", s.dictionary,
                                     apriltag_family_names()));
  }
  if (s.first_id < 0 || s.first_id >= size)
    fail(id_field(s), fmt::format("{} is not an id of {}, which has ids 0 to {}", s.first_id, s.dictionary, size - 1));
  const Eigen::Vector2d pattern = board_size_mm(s);
  if (pattern.maxCoeff() > kMaxTargetPatternMm)
    fail(size_field(s), fmt::format("the marker would print {:.6g} mm across, more than the {} mm a target may have",
                                    pattern.x(), kMaxTargetPatternMm));
}

}  // namespace

std::string target_kind_name(TargetKind kind) {
  switch (kind) {
    case TargetKind::chessboard: return "chessboard";
    case TargetKind::charuco: return "charuco";
    case TargetKind::aprilgrid: return "aprilgrid";
    case TargetKind::aruco_marker: return "aruco_marker";
    case TargetKind::apriltag: return "apriltag";
    case TargetKind::speckle: return "speckle";
  }
  return "?";
}

bool is_single_marker(TargetKind kind) { return kind == TargetKind::aruco_marker || kind == TargetKind::apriltag; }

std::string charuco_layout_name(CharucoLayout layout) {
  return layout == CharucoLayout::legacy ? "legacy" : "opencv";
}

int opencv_dictionary_id(const std::string& name) {
  for (const auto& d : kDictionaries)
    if (name == d.name) return d.id;
  return -1;
}

std::string opencv_dictionary_names() {
  std::string list;
  for (const auto& d : kDictionaries) list += (list.empty() ? "" : ", ") + std::string(d.name);
  return list;
}

int opencv_dictionary_size(const std::string& name) {
  const int id = opencv_dictionary_id(name);
  if (id < 0) return 0;
  return cv::aruco::getPredefinedDictionary(id)->bytesList.rows;
}

AprilTagFamilyPtr create_apriltag_family(const std::string& name) {
  for (const auto& f : kAprilTagFamilies)
    if (name == f.name) return AprilTagFamilyPtr(f.create(), AprilTagFamilyDeleter{f.destroy});
  return AprilTagFamilyPtr();
}

AprilTagFamilyInfo apriltag_family_info(const std::string& name) {
  AprilTagFamilyInfo info;
  if (const AprilTagFamilyPtr family = create_apriltag_family(name)) {
    info.codes = static_cast<int>(family->ncodes);
    info.border_cells = family->width_at_border;
    info.reversed_border = family->reversed_border;
    // libapriltag's total_width adds a one-bit white ring around a normal
    // family's black border: that ring is the margin's, not the pattern's.
    info.pattern_cells = family->reversed_border ? family->total_width : family->width_at_border;
    info.inset_cells = (info.pattern_cells - info.border_cells) / 2;
    info.min_hamming = static_cast<int>(family->h);
  }
  return info;
}

std::string apriltag_family_names() {
  std::string list;
  for (const auto& f : kAprilTagFamilies) list += (list.empty() ? "" : ", ") + std::string(f.name);
  return list;
}

void validate_target(const TargetSpec& s, const std::string& file) {
  auto fail = [&](const std::string& field, const std::string& problem) { throw InputError(file, field, problem); };
  const std::string kind = target_kind_name(s.kind);
  if (s.kind == TargetKind::speckle) {
    validate_speckle(s, file);
    return;
  }
  refuse_speckle_fields(s, file);
  if (is_single_marker(s.kind)) {
    validate_single_marker(s, file);
    return;
  }

  const int min_squares = s.kind == TargetKind::chessboard ? 4 : s.kind == TargetKind::charuco ? 3 : 2;
  for (const int n : {s.squares_x, s.squares_y}) {
    if (n < min_squares)
      fail(squares_field(s),
           fmt::format("[{}, {}]: a {} needs at least {} {} across and down{}", s.squares_x, s.squares_y, kind,
                       min_squares, s.kind == TargetKind::aprilgrid ? "tags" : "squares",
                       s.kind == TargetKind::chessboard ? " (OpenCV finds at least 3 x 3 inner corners)" : ""));
    if (n > kMaxSquares)
      fail(squares_field(s), fmt::format("[{}, {}]: more than {} across or down; is this a typo?", s.squares_x,
                                         s.squares_y, kMaxSquares));
  }
  // A length in mm within [kMinTargetLengthMm, kMaxTargetLengthMm].
  auto length = [&](double value, const std::string& field) {
    if (!std::isfinite(value) || !(value > 0))
      fail(field, fmt::format("must be a positive length in mm, got {}", value));
    if (value < kMinTargetLengthMm)
      fail(field, fmt::format("{} mm is less than {} mm, the smallest length a target may have", value,
                              kMinTargetLengthMm));
    if (value > kMaxTargetLengthMm)
      fail(field, fmt::format("{} mm is more than {} mm; the unit is mm", value, kMaxTargetLengthMm));
  };
  length(s.square_size_mm, size_field(s));

  // The printed pattern, once its lengths are known to be sane.
  auto pattern = [&]() {
    const Eigen::Vector2d size = board_size_mm(s);
    if (size.maxCoeff() > kMaxTargetPatternMm)
      fail(size_field(s), fmt::format("the pattern would print {:.6g} x {:.6g} mm, more than the {} mm across and "
                                      "down a target may have (margins excluded)",
                                      size.x(), size.y(), kMaxTargetPatternMm));
  };

  switch (s.kind) {
    case TargetKind::chessboard:
      if ((s.squares_x + s.squares_y) % 2 == 0)
        fail("squares", fmt::format("[{}, {}]: one count must be odd and the other even, else the board looks the "
                                    "same turned by 180 degrees and its corner ids are ambiguous",
                                    s.squares_x, s.squares_y));
      if (s.marker_size_mm != 0) fail("marker_size_mm", "a chessboard has no markers");
      if (!s.dictionary.empty()) fail("dictionary", "a chessboard has no markers");
      if (s.first_id != 0) fail("first_id", "a chessboard has no markers");
      if (s.charuco_layout != CharucoLayout::opencv) fail("charuco_layout", "applies to charuco boards only");
      pattern();
      return;
    case TargetKind::charuco: {
      length(s.marker_size_mm, "marker_size_mm");
      if (!(s.marker_size_mm < s.square_size_mm))
        fail("marker_size_mm", fmt::format("{} mm must be smaller than the square ({} mm)", s.marker_size_mm,
                                           s.square_size_mm));
      const int size = opencv_dictionary_size(s.dictionary);
      if (size == 0)
        fail("dictionary", fmt::format("'{}' is not an OpenCV dictionary (known: {})", s.dictionary,
                                       opencv_dictionary_names()));
      if (s.first_id < 0) fail("first_id", fmt::format("must be 0 or more, got {}", s.first_id));
      const int n = marker_count(s);
      if (static_cast<long long>(s.first_id) + n > size)
        fail("first_id", fmt::format("the board needs {} markers, ids {} to {}, but {} has only ids 0 to {}", n,
                                     s.first_id, static_cast<long long>(s.first_id) + n - 1, s.dictionary,
                                     size - 1));
      pattern();
      return;
    }
    case TargetKind::aprilgrid: {
      if (!std::isfinite(s.marker_size_mm) || s.marker_size_mm < 0)
        fail("tag_spacing_mm", fmt::format("must be a length in mm, got {}", s.marker_size_mm));
      // libapriltag needs a white border of one bit around each tag's black square;
      // neighbours may share it.
      if (s.marker_size_mm < s.square_size_mm / 8 * (1 - 1e-9))
        fail("tag_spacing_mm", fmt::format("{} mm is narrower than one bit of the tag ({} mm / 8 = {} mm): the tags "
                                           "need a white border that wide",
                                           s.marker_size_mm, s.square_size_mm, s.square_size_mm / 8));
      length(s.marker_size_mm, "tag_spacing_mm");
      if (s.dictionary != "tag36h11")
        fail("dictionary", fmt::format("'{}': an aprilgrid uses tag36h11", s.dictionary));
      if (s.first_id < 0) fail("first_id", fmt::format("must be 0 or more, got {}", s.first_id));
      const int n = marker_count(s);
      if (static_cast<long long>(s.first_id) + n > kTag36h11Codes)
        fail("first_id", fmt::format("the grid needs {} tags, ids {} to {}, but tag36h11 has only ids 0 to {}", n,
                                     s.first_id, static_cast<long long>(s.first_id) + n - 1, kTag36h11Codes - 1));
      if (s.charuco_layout != CharucoLayout::opencv) fail("charuco_layout", "applies to charuco boards only");
      pattern();
      return;
    }
    case TargetKind::aruco_marker:
    case TargetKind::apriltag:
    case TargetKind::speckle: return;  // validated above
  }
}

bool square_is_black(const TargetSpec& s, int col, int row) {
  const bool even = (col + row) % 2 == 0;
  return legacy_even(s) ? !even : even;
}

std::vector<BoardCorner> board_corners(const TargetSpec& s) {
  std::vector<BoardCorner> corners;
  if (s.kind == TargetKind::speckle) return corners;
  if (is_single_marker(s.kind)) {
    const double o = single_marker_inset_mm(s), m = s.marker_size_mm;
    const double dx[4] = {0, m, m, 0}, dy[4] = {0, 0, m, m};
    for (int k = 0; k < 4; ++k) corners.push_back({k, Eigen::Vector3d(o + dx[k], o + dy[k], 0)});
    return corners;
  }
  if (s.kind == TargetKind::aprilgrid) {
    const double t = s.square_size_mm, pitch = s.square_size_mm + s.marker_size_mm;
    const double dx[4] = {0, t, t, 0}, dy[4] = {0, 0, t, t};
    for (int r = 0; r < s.squares_y; ++r)
      for (int c = 0; c < s.squares_x; ++c)
        for (int k = 0; k < 4; ++k) {
          const int index = r * s.squares_x + c;
          corners.push_back({4 * index + k, Eigen::Vector3d(c * pitch + dx[k], r * pitch + dy[k], 0)});
        }
    return corners;
  }
  for (int r = 0; r + 1 < s.squares_y; ++r)
    for (int c = 0; c + 1 < s.squares_x; ++c)
      corners.push_back({r * (s.squares_x - 1) + c,
                         Eigen::Vector3d((c + 1) * s.square_size_mm, (r + 1) * s.square_size_mm, 0)});
  return corners;
}

std::size_t board_corner_count(const TargetSpec& s) {
  if (s.kind == TargetKind::speckle) return 0;
  if (is_single_marker(s.kind)) return 4;
  if (s.kind == TargetKind::aprilgrid) return 4 * static_cast<std::size_t>(s.squares_x) * s.squares_y;
  if (s.squares_x < 2 || s.squares_y < 2) return 0;
  return static_cast<std::size_t>(s.squares_x - 1) * (s.squares_y - 1);
}

bool corner_grid(const TargetSpec& s, int& width, int& height, double& spacing_mm) {
  if (s.kind == TargetKind::aprilgrid || is_single_marker(s.kind) || s.kind == TargetKind::speckle) return false;
  width = s.squares_x - 1;
  height = s.squares_y - 1;
  spacing_mm = s.square_size_mm;
  return true;
}

Eigen::Vector2d board_size_mm(const TargetSpec& s) {
  if (s.kind == TargetKind::speckle) return s.plate_size_mm;
  if (is_single_marker(s.kind)) {
    const double side = s.marker_size_mm + 2 * single_marker_inset_mm(s);
    return Eigen::Vector2d(side, side);
  }
  if (s.kind == TargetKind::aprilgrid)
    return Eigen::Vector2d(s.squares_x * s.square_size_mm + (s.squares_x - 1) * s.marker_size_mm,
                           s.squares_y * s.square_size_mm + (s.squares_y - 1) * s.marker_size_mm);
  return Eigen::Vector2d(s.squares_x * s.square_size_mm, s.squares_y * s.square_size_mm);
}

std::vector<BoardMarker> board_markers(const TargetSpec& s) {
  std::vector<BoardMarker> markers;
  if (s.kind == TargetKind::chessboard || s.kind == TargetKind::speckle) return markers;
  if (is_single_marker(s.kind)) {
    BoardMarker m;
    m.id = s.first_id;
    m.top_left_mm = Eigen::Vector2d::Constant(single_marker_inset_mm(s));
    m.size_mm = s.marker_size_mm;
    markers.push_back(m);
    return markers;
  }
  int id = s.first_id;
  for (int r = 0; r < s.squares_y; ++r)
    for (int c = 0; c < s.squares_x; ++c) {
      BoardMarker m;
      m.col = c;
      m.row = r;
      if (s.kind == TargetKind::aprilgrid) {
        const double pitch = s.square_size_mm + s.marker_size_mm;
        m.top_left_mm = Eigen::Vector2d(c * pitch, r * pitch);
        m.size_mm = s.square_size_mm;
      } else {
        if (square_is_black(s, c, r)) continue;
        const double inset = (s.square_size_mm - s.marker_size_mm) / 2;
        m.top_left_mm = Eigen::Vector2d(c * s.square_size_mm + inset, r * s.square_size_mm + inset);
        m.size_mm = s.marker_size_mm;
      }
      m.id = id++;
      markers.push_back(m);
    }
  return markers;
}

std::string describe_target(const TargetSpec& s) {
  const std::string named = s.name.empty() ? "" : fmt::format("'{}': ", s.name);
  switch (s.kind) {
    case TargetKind::chessboard:
      return fmt::format("{}chessboard, {} x {} squares of {} mm ({} x {} inner corners)", named, s.squares_x,
                         s.squares_y, s.square_size_mm, s.squares_x - 1, s.squares_y - 1);
    case TargetKind::charuco:
      return fmt::format("{}charuco, {} x {} squares of {} mm, markers {} mm, {}, first id {}, {} layout", named,
                         s.squares_x, s.squares_y, s.square_size_mm, s.marker_size_mm, s.dictionary, s.first_id,
                         charuco_layout_name(s.charuco_layout));
    case TargetKind::aprilgrid:
      return fmt::format("{}aprilgrid, {} x {} {} tags of {} mm, {} mm apart, first id {}", named, s.squares_x,
                         s.squares_y, s.dictionary, s.square_size_mm, s.marker_size_mm, s.first_id);
    case TargetKind::aruco_marker:
      return fmt::format("{}aruco_marker, {} id {}, {} mm (its black border)", named, s.dictionary, s.first_id,
                         s.marker_size_mm);
    case TargetKind::apriltag:
      return fmt::format("{}apriltag, {} id {}, tag size {} mm", named, s.dictionary, s.first_id, s.marker_size_mm);
    case TargetKind::speckle:
      return fmt::format("{}speckle, {} x {} mm plate, dots {} mm, fill {}, seed {}", named, s.plate_size_mm.x(),
                         s.plate_size_mm.y(), s.dot_diameter_mm, s.fill, s.seed);
  }
  return named;
}

void require_target_corners(const TargetSpec& spec, const std::string& file, const std::string& what) {
  if (spec.kind == TargetKind::speckle)
    throw InputError(file, "kind",
                     fmt::format("a speckle plate has no corners to detect, and {} needs corners; use a chessboard, "
                                 "charuco, aprilgrid or single-marker spec",
                                 what));
}

}  // namespace glasspiv
