#pragma once
// A calibration target: what is printed on the board, and where every corner
// the detectors report lies on it. See docs/targets.md.
//
// Board frame (docs/conventions.md): origin at the top-left corner of the
// pattern as printed (the outer corner of the top-left square, or of the
// top-left tag's black border), x to the right along the columns, y downwards
// along the rows, z = 0 on the board; millimetres. A single marker's pattern is
// the marker itself: the origin is the top-left outer corner of its black
// border (of its outer data bits for tagStandard41h12 and tagCircle21h7).
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

struct apriltag_family;  // libapriltag's apriltag_family_t

namespace glasspiv {

// aruco_marker and apriltag: one fiducial marker (an ArUco marker of an OpenCV
// dictionary, a libapriltag tag), e.g. glued to an experiment's frame.
// speckle: a plate of random black dots (targets/speckle_plate.h) for dense,
// photometric model fitting; it has no corners and no markers.
enum class TargetKind { chessboard, charuco, aprilgrid, aruco_marker, apriltag, speckle };

// ChArUco boards with an even number of rows were printed differently before
// OpenCV 4.6.0 (see docs/targets.md). Boards with an odd number of rows look the
// same both ways.
//   opencv  OpenCV >= 4.6.0: the top-left square is black.
//   legacy  OpenCV < 4.6.0 (and OpenCV >= 4.8 with setLegacyPattern(true)) for
//           an even number of rows: the top-left square is white and holds
//           marker first_id.
enum class CharucoLayout { opencv, legacy };

struct TargetSpec {
  TargetKind kind = TargetKind::charuco;
  std::string name;  // free text, used as Observations::target_name; may be empty
  // chessboard, charuco: squares across (columns) and down (rows).
  // aprilgrid: tags across and down. 0 for single markers.
  int squares_x = 0, squares_y = 0;
  // chessboard, charuco: side of a square. aprilgrid: side of a tag's black
  // square (its outer black border, 8 of tag36h11's bits), as Kalibr's tagSize.
  // 0 for single markers.
  double square_size_mm = 0;
  // charuco: side of a marker (its black border included).
  // aprilgrid: the white gap between neighbouring tags in mm (Kalibr's
  //   tagSpacing is this gap divided by the tag size). Unused (0) for chessboards.
  // aruco_marker: side of the marker's black border (the whole marker).
  // apriltag: side of the square whose corners libapriltag detects
  //   (width_at_border bits): the outer edge of the black border for tag16h5,
  //   tag25h9 and tag36h11, the inner edge of the black ring for the
  //   reversed-border tagStandard41h12 and tagCircle21h7 (their outer data bits
  //   lie beyond it). libapriltag's tagsize, Kalibr's tagSize.
  double marker_size_mm = 0;
  // charuco, aruco_marker: an OpenCV predefined dictionary ("DICT_5X5_100",
  // "DICT_APRILTAG_36h11", ...). aprilgrid: "tag36h11". apriltag: a libapriltag
  // family (apriltag_family_names()). Empty for chessboards.
  std::string dictionary;
  // charuco: the marker ids are first_id, first_id + 1, ... row by row from the
  // top-left. aprilgrid: likewise for the tag ids. aruco_marker, apriltag: the
  // marker's id. 0 for chessboards.
  int first_id = 0;
  CharucoLayout charuco_layout = CharucoLayout::opencv;  // charuco only
  // speckle only (zero for every other kind): the pattern area (width, height),
  // the diameter of its black discs, the fraction of the area inked, in
  // (0, kMaxSpeckleFill], and the seed of the dots (targets/speckle_plate.h).
  Eigen::Vector2d plate_size_mm = Eigen::Vector2d::Zero();
  double dot_diameter_mm = 0;
  double fill = 0;
  std::uint64_t seed = 0;
};

// "chessboard", "charuco", "aprilgrid", "aruco_marker", "apriltag", "speckle"
std::string target_kind_name(TargetKind kind);
bool is_single_marker(TargetKind kind);  // aruco_marker, apriltag
std::string charuco_layout_name(CharucoLayout layout);  // "opencv", "legacy"

// The limits of a target spec (validate_target refuses anything beyond them,
// naming the field and the limit): at most kMaxTargetSquares squares (tags)
// across and down; every length in mm (square or tag, charuco marker, aprilgrid
// gap) in [kMinTargetLengthMm, kMaxTargetLengthMm]; the printed pattern
// (board_size_mm, margins excluded) at most kMaxTargetPatternMm across and down.
constexpr int kMaxTargetSquares = 200;
constexpr double kMinTargetLengthMm = 0.01;
constexpr double kMaxTargetLengthMm = 10000;
constexpr double kMaxTargetPatternMm = 10000;
// A speckle plate: fill at most kMaxSpeckleFill, at most kMaxSpeckleDots dots
// (a 1 x 1 m plate of 0.5 mm dots at fill 0.4 has 2 million), each side of the
// plate at least kMinSpeckleDotsAcross dot diameters.
constexpr double kMaxSpeckleFill = 0.7;
constexpr double kMaxSpeckleDots = 4e6;
constexpr double kMinSpeckleDotsAcross = 3;

// Throws InputError(file, field, problem) naming the first thing that is wrong:
// too few or too many squares, non-finite sizes or sizes beyond the limits above, a marker not
// smaller than its square, an unknown dictionary, ids beyond the dictionary, a
// chessboard whose 180-degree turn cannot be told apart (equal parity of both
// square counts), fields set that the kind does not use (a single marker's
// squares, square_size_mm, charuco_layout; a speckle plate's squares, markers,
// dictionary and ids; any other kind's plate_size_mm, dot_diameter_mm, fill,
// seed), a single marker's id beyond its dictionary or AprilTag family, a
// speckle plate's fill outside (0, kMaxSpeckleFill], a plate under
// kMinSpeckleDotsAcross dots across or with more than kMaxSpeckleDots dots.
void validate_target(const TargetSpec& spec, const std::string& file = "");

// The OpenCV predefined dictionary id (cv::aruco::PREDEFINED_DICTIONARY_NAME) of
// `name`, or -1 if there is none of that name. Names as in OpenCV ("DICT_4X4_50").
int opencv_dictionary_id(const std::string& name);
// All names opencv_dictionary_id() knows, comma-separated, for error messages.
std::string opencv_dictionary_names();
// The number of markers in an OpenCV predefined dictionary (0 if unknown).
int opencv_dictionary_size(const std::string& name);

// A libapriltag family as printed. Non-reversed families (tag16h5, tag25h9,
// tag36h11) print as their black border square, `border_cells` bits wide; the
// reversed ones (tagStandard41h12, tagCircle21h7) as all `pattern_cells` bits
// (libapriltag's total_width), data bits outside the detected square, which
// sits `inset_cells` bits in from the pattern's edge.
struct AprilTagFamilyInfo {
  int codes = 0;           // ids 0 .. codes - 1
  int border_cells = 0;    // libapriltag's width_at_border: the detected square
  int pattern_cells = 0;   // the printed pattern, bits across
  int inset_cells = 0;     // (pattern_cells - border_cells) / 2
  bool reversed_border = false;
  int min_hamming = 0;     // the family's h
};
// The family of that name, or codes == 0 if glasspiv does not know it.
AprilTagFamilyInfo apriltag_family_info(const std::string& name);
// The names apriltag_family_info() knows, comma-separated, for error messages.
std::string apriltag_family_names();

// libapriltag's family of that name (tag36h11_create() ...), freed by its own
// destroy function; null if glasspiv does not know it.
struct AprilTagFamilyDeleter {
  void (*destroy)(apriltag_family*) = nullptr;
  void operator()(apriltag_family* family) const {
    if (family != nullptr && destroy != nullptr) destroy(family);
  }
};
using AprilTagFamilyPtr = std::unique_ptr<apriltag_family, AprilTagFamilyDeleter>;
AprilTagFamilyPtr create_apriltag_family(const std::string& name);

struct BoardCorner {
  int id = 0;
  Eigen::Vector3d point_mm = Eigen::Vector3d::Zero();  // board frame
};

// Every corner a detector can report, ordered by id:
//   chessboard, charuco: the inner corners, (squares_x - 1) per row, row by row
//     from the top-left, id = row * (squares_x - 1) + col, at
//     ((col + 1) * square, (row + 1) * square, 0). For charuco these are
//     OpenCV's charuco corner ids (OpenCV >= 4.6 numbering, in both layouts).
//   aprilgrid: 4 per tag, id = 4 * tag_index + corner, tag_index = row *
//     squares_x + col (the tag's id is first_id + tag_index); corner 0, 1, 2, 3
//     = the top-left, top-right, bottom-right, bottom-left corner of the tag's
//     black square as printed.
//   aruco_marker, apriltag: 4, id 0, 1, 2, 3 = the top-left, top-right,
//     bottom-right, bottom-left corner of the marker's black border (apriltag:
//     of the square libapriltag detects), the order of OpenCV's detectMarkers:
//     (0, 0), (s, 0), (s, s), (0, s) with s = marker_size_mm, shifted by the
//     inset (2 bits) for reversed-border AprilTag families.
//   speckle: none (a speckle plate has no corners).
std::vector<BoardCorner> board_corners(const TargetSpec& spec);
std::size_t board_corner_count(const TargetSpec& spec);

// The corners as a regular grid (chessboard, charuco): width x height points,
// spaced `spacing_mm`, the point of id 0 first. An aprilgrid has no such grid:
// returns false, as for single markers and speckle plates.
bool corner_grid(const TargetSpec& spec, int& width, int& height, double& spacing_mm);

// The printed pattern's size (width, height) in mm, margins excluded. A single
// marker: its black border square (reversed-border AprilTags: with their outer
// data bits, pattern_cells / border_cells times the tag size). A speckle
// plate: plate_size_mm.
Eigen::Vector2d board_size_mm(const TargetSpec& spec);

// Squares of a chessboard or charuco board: is square (col, row) black?
bool square_is_black(const TargetSpec& spec, int col, int row);

// A marker (charuco, aruco_marker) or tag (aprilgrid, apriltag) on the board.
struct BoardMarker {
  int id = 0;             // dictionary id
  int col = 0, row = 0;   // its square (charuco) or tag position (aprilgrid)
  // Outer corner of its black border (apriltag: of its detected square).
  Eigen::Vector2d top_left_mm = Eigen::Vector2d::Zero();
  double size_mm = 0;     // side of its black border (apriltag: of its detected square)
};
// In order of id (row by row from the top-left). Empty for chessboards and
// speckle plates; one for single markers.
std::vector<BoardMarker> board_markers(const TargetSpec& spec);

// One line: "charuco, 11 x 8 squares of 15 mm, markers 11 mm, DICT_5X5_100,
// first id 0, opencv layout".
std::string describe_target(const TargetSpec& spec);

// Refuses a target whose corners a command needs but which has none (a speckle
// plate): InputError(file, "kind", ...) naming `what` the corners are for.
void require_target_corners(const TargetSpec& spec, const std::string& file, const std::string& what);

}  // namespace glasspiv
