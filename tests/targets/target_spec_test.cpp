// Target specs: corner geometry, marker layouts (against OpenCV's own boards),
// validation, and the YAML file with every rejection.
#include <string>

#include <gtest/gtest.h>
#include <opencv2/aruco/charuco.hpp>

#include "targets/target_spec.h"
#include "targets/target_yaml.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {

const std::string kData = std::string(GLASSPIV_SOURCE_DIR) + "/data/targets/";

TargetSpec charuco(int sx, int sy, CharucoLayout layout = CharucoLayout::opencv) {
  TargetSpec s;
  s.kind = TargetKind::charuco;
  s.squares_x = sx;
  s.squares_y = sy;
  s.square_size_mm = 15;
  s.marker_size_mm = 11;
  s.dictionary = "DICT_5X5_100";
  s.charuco_layout = layout;
  return s;
}

TargetSpec chessboard() {
  TargetSpec s;
  s.kind = TargetKind::chessboard;
  s.squares_x = 9;
  s.squares_y = 6;
  s.square_size_mm = 25;
  return s;
}

TargetSpec aprilgrid() {
  TargetSpec s;
  s.kind = TargetKind::aprilgrid;
  s.squares_x = 6;
  s.squares_y = 5;
  s.square_size_mm = 22;
  s.marker_size_mm = 6.6;
  s.dictionary = "tag36h11";
  return s;
}

TargetSpec aruco_marker() {
  TargetSpec s;
  s.kind = TargetKind::aruco_marker;
  s.dictionary = "DICT_4X4_50";
  s.first_id = 7;
  s.marker_size_mm = 30;
  return s;
}

TargetSpec apriltag(const std::string& family = "tag36h11") {
  TargetSpec s;
  s.kind = TargetKind::apriltag;
  s.dictionary = family;
  s.first_id = 3;
  s.marker_size_mm = 40;
  return s;
}

// Expects `f` to throw InputError for `field`; returns its message.
template <typename F>
std::string expect_input_error(F f, const std::string& field, const std::string& file = "") {
  try {
    f();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), field) << e.what();
    EXPECT_EQ(e.file(), file) << e.what();
    return e.what();
  }
  ADD_FAILURE() << "no InputError for field '" << field << "'";
  return "";
}

// ------------------------------------------------------------ geometry

TEST(BoardCorners, ChessboardInnerCornersRowMajor) {
  const TargetSpec s = chessboard();
  const auto corners = board_corners(s);
  ASSERT_EQ(corners.size(), 8u * 5u);
  ASSERT_EQ(board_corner_count(s), corners.size());
  for (int row = 0; row < 5; ++row)
    for (int col = 0; col < 8; ++col) {
      const BoardCorner& c = corners[static_cast<std::size_t>(row * 8 + col)];
      EXPECT_EQ(c.id, row * 8 + col);
      // Exact: small integers times 25.
      EXPECT_EQ(c.point_mm, Eigen::Vector3d((col + 1) * 25.0, (row + 1) * 25.0, 0));
    }
  EXPECT_EQ(board_size_mm(s), Eigen::Vector2d(225, 150));
  int w = 0, h = 0;
  double spacing = 0;
  ASSERT_TRUE(corner_grid(s, w, h, spacing));
  EXPECT_EQ(w, 8);
  EXPECT_EQ(h, 5);
  EXPECT_EQ(spacing, 25);
  // Top-left square black; the 180-degree turn swaps colours (9 + 6 odd).
  EXPECT_TRUE(square_is_black(s, 0, 0));
  EXPECT_FALSE(square_is_black(s, 8, 5));
}

TEST(BoardCorners, CharucoMatchesOpenCv46) {
  // OpenCV >= 4.6's CharucoBoard is the reference for the opencv layout: its
  // chessboard corners are our corners, its markers (ids 0, 1, ... row by row)
  // our markers. float vs double: compare to 1e-4 mm.
  for (const auto& [sx, sy] : {std::pair{11, 8}, std::pair{5, 7}, std::pair{4, 4}}) {
    const TargetSpec s = charuco(sx, sy);
    const auto board = cv::aruco::CharucoBoard::create(sx, sy, 15.f, 11.f,
                                                       cv::aruco::getPredefinedDictionary(cv::aruco::DICT_5X5_100));
    const auto corners = board_corners(s);
    ASSERT_EQ(corners.size(), board->chessboardCorners.size());
    for (std::size_t i = 0; i < corners.size(); ++i) {
      EXPECT_EQ(corners[i].id, static_cast<int>(i));
      EXPECT_NEAR(corners[i].point_mm.x(), board->chessboardCorners[i].x, 1e-4);
      EXPECT_NEAR(corners[i].point_mm.y(), board->chessboardCorners[i].y, 1e-4);
    }
    const auto markers = board_markers(s);
    ASSERT_EQ(markers.size(), board->ids.size());
    for (std::size_t i = 0; i < markers.size(); ++i) {
      EXPECT_EQ(markers[i].id, board->ids[i]);
      EXPECT_NEAR(markers[i].top_left_mm.x(), board->objPoints[i][0].x, 1e-4);
      EXPECT_NEAR(markers[i].top_left_mm.y(), board->objPoints[i][0].y, 1e-4);
      EXPECT_NEAR(markers[i].size_mm, board->objPoints[i][1].x - board->objPoints[i][0].x, 1e-4);
    }
    EXPECT_TRUE(square_is_black(s, 0, 0)) << "OpenCV >= 4.6: the top-left square is black";
  }
}

TEST(BoardCorners, LegacyLayoutIsOpenCvBefore46) {
  // OpenCV <= 4.5.5 built its ChArUco board with y pointing up from the bottom
  // row: square (x, y_up) is black when y_up % 2 == x % 2, markers numbered from
  // the top row down, left to right, marker corner 0 at its top-left as printed.
  // Rebuild that here and compare, in our frame (y down), with the legacy layout.
  for (const auto& [sx, sy] : {std::pair{11, 8}, std::pair{6, 4}, std::pair{5, 7}}) {
    const TargetSpec s = charuco(sx, sy, CharucoLayout::legacy);
    const double sq = 15, m = 11, inset = (sq - m) / 2;
    std::vector<Eigen::Vector2d> old_top_left;
    for (int y_up = sy - 1; y_up >= 0; --y_up)
      for (int x = 0; x < sx; ++x) {
        if (y_up % 2 == x % 2) continue;
        const double top_y_up = y_up * sq + inset + m;  // corner 0, y up
        old_top_left.emplace_back(x * sq + inset, sy * sq - top_y_up);
      }
    const auto markers = board_markers(s);
    ASSERT_EQ(markers.size(), old_top_left.size());
    for (std::size_t i = 0; i < markers.size(); ++i) {
      EXPECT_EQ(markers[i].id, static_cast<int>(i));
      EXPECT_NEAR((markers[i].top_left_mm - old_top_left[i]).norm(), 0, 1e-9) << "marker " << i;
    }
    // Black squares: the old rule, with y_up = sy - 1 - row.
    for (int row = 0; row < sy; ++row)
      for (int col = 0; col < sx; ++col)
        EXPECT_EQ(square_is_black(s, col, row), (sy - 1 - row) % 2 == col % 2) << col << "," << row;
  }
  // Even rows: the top-left square is white and holds marker first_id; odd rows:
  // both layouts are the same board.
  TargetSpec even = charuco(11, 8, CharucoLayout::legacy);
  even.first_id = 7;
  EXPECT_FALSE(square_is_black(even, 0, 0));
  EXPECT_EQ(board_markers(even).front().col, 0);
  EXPECT_EQ(board_markers(even).front().row, 0);
  EXPECT_EQ(board_markers(even).front().id, 7);
  const auto odd_legacy = board_markers(charuco(11, 7, CharucoLayout::legacy));
  const auto odd_opencv = board_markers(charuco(11, 7, CharucoLayout::opencv));
  ASSERT_EQ(odd_legacy.size(), odd_opencv.size());
  for (std::size_t i = 0; i < odd_legacy.size(); ++i) EXPECT_EQ(odd_legacy[i].top_left_mm, odd_opencv[i].top_left_mm);
}

TEST(BoardCorners, AprilgridFourPerTag) {
  const TargetSpec s = aprilgrid();
  const auto corners = board_corners(s);
  ASSERT_EQ(corners.size(), 4u * 6u * 5u);
  const double pitch = 22 + 6.6;
  // Tag (col 2, row 3): index 3 * 6 + 2 = 20; corners TL, TR, BR, BL.
  const int base = 4 * 20;
  EXPECT_EQ(corners[base].id, base);
  EXPECT_NEAR((corners[base + 0].point_mm - Eigen::Vector3d(2 * pitch, 3 * pitch, 0)).norm(), 0, 1e-12);
  EXPECT_NEAR((corners[base + 1].point_mm - Eigen::Vector3d(2 * pitch + 22, 3 * pitch, 0)).norm(), 0, 1e-12);
  EXPECT_NEAR((corners[base + 2].point_mm - Eigen::Vector3d(2 * pitch + 22, 3 * pitch + 22, 0)).norm(), 0, 1e-12);
  EXPECT_NEAR((corners[base + 3].point_mm - Eigen::Vector3d(2 * pitch, 3 * pitch + 22, 0)).norm(), 0, 1e-12);
  EXPECT_NEAR((board_size_mm(s) - Eigen::Vector2d(6 * 22 + 5 * 6.6, 5 * 22 + 4 * 6.6)).norm(), 0, 1e-12);
  int w = 0, h = 0;
  double spacing = 0;
  EXPECT_FALSE(corner_grid(s, w, h, spacing));
  const auto markers = board_markers(s);
  ASSERT_EQ(markers.size(), 30u);
  EXPECT_EQ(markers[20].id, 20);
  EXPECT_EQ(markers[20].col, 2);
  EXPECT_EQ(markers[20].row, 3);
}

TEST(BoardCorners, SingleMarkerFourCornersOfItsBorder) {
  // TL, TR, BR, BL of the black border, the origin at its top-left.
  for (const TargetSpec& s : {aruco_marker(), apriltag("tag36h11"), apriltag("tag16h5"), apriltag("tag25h9")}) {
    SCOPED_TRACE(s.dictionary);
    const double m = s.marker_size_mm;
    const auto corners = board_corners(s);
    ASSERT_EQ(corners.size(), 4u);
    EXPECT_EQ(board_corner_count(s), 4u);
    const Eigen::Vector3d expected[4] = {{0, 0, 0}, {m, 0, 0}, {m, m, 0}, {0, m, 0}};
    for (int k = 0; k < 4; ++k) {
      EXPECT_EQ(corners[static_cast<std::size_t>(k)].id, k);
      EXPECT_EQ(corners[static_cast<std::size_t>(k)].point_mm, expected[k]);
    }
    EXPECT_EQ(board_size_mm(s), Eigen::Vector2d(m, m));
    int w = 0, h = 0;
    double spacing = 0;
    EXPECT_FALSE(corner_grid(s, w, h, spacing));
    const auto markers = board_markers(s);
    ASSERT_EQ(markers.size(), 1u);
    EXPECT_EQ(markers[0].id, s.first_id);
    EXPECT_EQ(markers[0].top_left_mm, Eigen::Vector2d(0, 0));
    EXPECT_EQ(markers[0].size_mm, m);
  }
}

TEST(BoardCorners, ReversedBorderTagsPrintTheirOuterBits) {
  // tagStandard41h12, tagCircle21h7: the detected square (5 bits) sits 2 bits
  // in from the 9-bit pattern's edge; the outer ring holds data bits.
  for (const std::string family : {"tagStandard41h12", "tagCircle21h7"}) {
    SCOPED_TRACE(family);
    const AprilTagFamilyInfo f = apriltag_family_info(family);
    EXPECT_TRUE(f.reversed_border);
    EXPECT_EQ(f.border_cells, 5);
    EXPECT_EQ(f.pattern_cells, 9);
    EXPECT_EQ(f.inset_cells, 2);
    const TargetSpec s = apriltag(family);  // 40 mm: 8 mm bits
    EXPECT_EQ(board_size_mm(s), Eigen::Vector2d(72, 72));
    const auto corners = board_corners(s);
    EXPECT_EQ(corners[0].point_mm, Eigen::Vector3d(16, 16, 0));
    EXPECT_EQ(corners[2].point_mm, Eigen::Vector3d(56, 56, 0));
    EXPECT_EQ(board_markers(s)[0].top_left_mm, Eigen::Vector2d(16, 16));
  }
  const AprilTagFamilyInfo t = apriltag_family_info("tag36h11");
  EXPECT_EQ(t.codes, 587);
  EXPECT_EQ(t.border_cells, 8);
  EXPECT_EQ(t.pattern_cells, 8);
  EXPECT_EQ(t.min_hamming, 11);
  EXPECT_EQ(apriltag_family_info("tag16h5").codes, 30);
  EXPECT_EQ(apriltag_family_info("tag25h9").codes, 35);
  EXPECT_EQ(apriltag_family_info("tagCircle21h7").codes, 38);
  EXPECT_EQ(apriltag_family_info("tagStandard41h12").codes, 2115);
  EXPECT_EQ(apriltag_family_info("tag99h1").codes, 0);
  EXPECT_EQ(apriltag_family_names(), "tag16h5, tag25h9, tag36h11, tagCircle21h7, tagStandard41h12");
}

TEST(Validate, SingleMarkers) {
  EXPECT_NO_THROW(validate_target(aruco_marker()));
  EXPECT_NO_THROW(validate_target(apriltag()));
  TargetSpec s = aruco_marker();
  s.first_id = 50;  // DICT_4X4_50: ids 0 to 49
  EXPECT_NE(expect_input_error([&] { validate_target(s, "m.yaml"); }, "marker_id", "m.yaml").find("0 to 49"),
            std::string::npos);
  s.first_id = -1;
  expect_input_error([&] { validate_target(s); }, "marker_id");
  s.first_id = 49;
  EXPECT_NO_THROW(validate_target(s));
  s = aruco_marker();
  s.dictionary = "tag36h11";  // a libapriltag family is no OpenCV dictionary
  expect_input_error([&] { validate_target(s); }, "dictionary");
  s = aruco_marker();
  s.dictionary = "DICT_APRILTAG_36h11";  // OpenCV's own AprilTag dictionaries are
  s.first_id = 586;
  EXPECT_NO_THROW(validate_target(s));
  s = aruco_marker();
  s.marker_size_mm = 0;
  expect_input_error([&] { validate_target(s); }, "marker_size_mm");
  s.marker_size_mm = 1e300;
  expect_input_error([&] { validate_target(s); }, "marker_size_mm");
  // Fields a single marker does not use.
  s = aruco_marker();
  s.squares_x = 1;
  expect_input_error([&] { validate_target(s); }, "squares");
  s = aruco_marker();
  s.square_size_mm = 30;
  expect_input_error([&] { validate_target(s); }, "square_size_mm");
  s = apriltag();
  s.charuco_layout = CharucoLayout::legacy;
  expect_input_error([&] { validate_target(s); }, "charuco_layout");

  s = apriltag();
  s.first_id = 587;
  expect_input_error([&] { validate_target(s); }, "tag_id");
  s = apriltag("tag16h5");
  s.first_id = 30;
  expect_input_error([&] { validate_target(s); }, "tag_id");
  s = apriltag("DICT_APRILTAG_36h11");  // OpenCV's name: an aruco_marker
  EXPECT_NE(expect_input_error([&] { validate_target(s); }, "dictionary").find("tag36h11"), std::string::npos);
  s = apriltag();
  s.marker_size_mm = std::nan("");
  expect_input_error([&] { validate_target(s); }, "tag_size_mm");
  s = apriltag("tagStandard41h12");
  s.marker_size_mm = 6000;  // prints 10800 mm with its outer bits
  expect_input_error([&] { validate_target(s); }, "tag_size_mm");
}

TEST(Validate, RejectsWithTheFieldNamed) {
  TargetSpec s = chessboard();
  s.squares_x = 3;
  expect_input_error([&] { validate_target(s, "b.yaml"); }, "squares", "b.yaml");
  s = chessboard();
  s.squares_x = 10;  // 10 + 6 even: the board looks the same turned by 180 degrees
  EXPECT_NE(expect_input_error([&] { validate_target(s); }, "squares").find("180"), std::string::npos);
  s = chessboard();
  s.square_size_mm = -1;
  expect_input_error([&] { validate_target(s); }, "square_size_mm");
  s = chessboard();
  s.square_size_mm = std::nan("");
  expect_input_error([&] { validate_target(s); }, "square_size_mm");
  s = chessboard();
  s.dictionary = "DICT_4X4_50";
  expect_input_error([&] { validate_target(s); }, "dictionary");

  s = charuco(11, 8);
  s.marker_size_mm = 15;
  expect_input_error([&] { validate_target(s); }, "marker_size_mm");
  s = charuco(11, 8);
  s.dictionary = "DICT_5X5_99";
  expect_input_error([&] { validate_target(s); }, "dictionary");
  s = charuco(11, 8);
  s.dictionary = "DICT_4X4_50";  // 44 markers fit in 50 ids ...
  EXPECT_NO_THROW(validate_target(s));
  s.first_id = 7;                // ... but not from 7
  expect_input_error([&] { validate_target(s); }, "first_id");
  s = charuco(2, 8);
  expect_input_error([&] { validate_target(s); }, "squares");

  s = aprilgrid();
  s.marker_size_mm = 2;  // under one bit (22 / 8 = 2.75 mm)
  expect_input_error([&] { validate_target(s); }, "tag_spacing_mm");
  s = aprilgrid();
  s.dictionary = "DICT_APRILTAG_36h11";
  expect_input_error([&] { validate_target(s); }, "dictionary");
  s = aprilgrid();
  s.first_id = 570;  // 30 tags from 570 pass tag36h11's 587
  expect_input_error([&] { validate_target(s); }, "first_id");
  s = aprilgrid();
  s.squares_y = 1;
  expect_input_error([&] { validate_target(s); }, "tags");
}

// Every length in mm and the printed pattern have limits, stated in the
// message (a square of 1e-308 mm used to reach an OpenCV assertion when printed).
TEST(Validate, LengthsAndThePrintedSizeHaveLimits) {
  auto says = [](const std::string& message, const std::string& words) {
    EXPECT_NE(message.find(words), std::string::npos) << message;
  };
  TargetSpec s = chessboard();
  s.square_size_mm = 1e-308;
  says(expect_input_error([&] { validate_target(s, "b.yaml"); }, "square_size_mm", "b.yaml"), "0.01 mm");
  s.square_size_mm = 1e308;
  says(expect_input_error([&] { validate_target(s); }, "square_size_mm"), "10000 mm");
  s.square_size_mm = kMinTargetLengthMm;
  EXPECT_NO_THROW(validate_target(s));

  s = charuco(11, 8);
  s.marker_size_mm = 1e-308;
  says(expect_input_error([&] { validate_target(s); }, "marker_size_mm"), "0.01 mm");
  s = charuco(11, 8);
  s.square_size_mm = 0.005;
  s.marker_size_mm = 0.004;
  says(expect_input_error([&] { validate_target(s); }, "square_size_mm"), "0.01 mm");

  s = aprilgrid();
  s.square_size_mm = 1e-308;
  s.marker_size_mm = 1e-308;
  says(expect_input_error([&] { validate_target(s); }, "tag_size_mm"), "0.01 mm");
  s = aprilgrid();
  s.marker_size_mm = 1e300;
  says(expect_input_error([&] { validate_target(s); }, "tag_spacing_mm"), "10000 mm");
  s = aprilgrid();
  s.marker_size_mm = std::nan("");
  expect_input_error([&] { validate_target(s); }, "tag_spacing_mm");

  // Each length within its limit, the whole pattern too large.
  s = chessboard();
  s.squares_x = 199;
  s.squares_y = 100;
  s.square_size_mm = 60;  // 11940 x 6000 mm
  says(expect_input_error([&] { validate_target(s); }, "square_size_mm"), "more than the 10000 mm");
  s.square_size_mm = 50;  // 9950 x 5000 mm
  EXPECT_NO_THROW(validate_target(s));
  s = aprilgrid();
  s.squares_x = 100;  // 500 tags, within tag36h11's 587
  s.square_size_mm = 90;
  s.marker_size_mm = 27;  // 100 * 90 + 99 * 27 = 11673 mm
  says(expect_input_error([&] { validate_target(s); }, "tag_size_mm"), "11673");

  // The reader applies the same limits, naming the file.
  says(expect_input_error([] { parse_target_yaml("glasspiv_target: 1\nkind: chessboard\nsquares: [9, 6]\n"
                                                 "square_size_mm: 1e-308\n",
                                                 "spec.yaml"); },
                          "square_size_mm", "spec.yaml"),
       "0.01 mm");
}

TEST(Describe, OneLine) {
  EXPECT_EQ(describe_target(charuco(11, 8)),
            "charuco, 11 x 8 squares of 15 mm, markers 11 mm, DICT_5X5_100, first id 0, opencv layout");
  EXPECT_EQ(describe_target(chessboard()), "chessboard, 9 x 6 squares of 25 mm (8 x 5 inner corners)");
  EXPECT_EQ(describe_target(aruco_marker()), "aruco_marker, DICT_4X4_50 id 7, 30 mm (its black border)");
  EXPECT_EQ(describe_target(apriltag()), "apriltag, tag36h11 id 3, tag size 40 mm");
}

// ------------------------------------------------------------ YAML

TEST(TargetYaml, ShippedSpecsReadAndRoundTrip) {
  for (const char* file : {"charuco_11x8_15mm.yaml", "chessboard_9x6.yaml", "aprilgrid_6x6.yaml"}) {
    SCOPED_TRACE(file);
    const TargetSpec s = read_target_yaml(kData + file);
    EXPECT_EQ(s.name, std::string(file).substr(0, std::string(file).size() - 5));
    const TargetSpec back = parse_target_yaml(format_target_yaml(s), "again.yaml");
    EXPECT_EQ(back.kind, s.kind);
    EXPECT_EQ(back.name, s.name);
    EXPECT_EQ(back.squares_x, s.squares_x);
    EXPECT_EQ(back.squares_y, s.squares_y);
    EXPECT_EQ(back.square_size_mm, s.square_size_mm);  // exact: written at full precision
    EXPECT_EQ(back.marker_size_mm, s.marker_size_mm);
    EXPECT_EQ(back.dictionary, s.dictionary);
    EXPECT_EQ(back.first_id, s.first_id);
    EXPECT_EQ(back.charuco_layout, s.charuco_layout);
  }
  const TargetSpec c = read_target_yaml(kData + "charuco_11x8_15mm.yaml");
  EXPECT_EQ(c.kind, TargetKind::charuco);
  EXPECT_EQ(c.squares_x, 11);
  EXPECT_EQ(c.squares_y, 8);
  EXPECT_EQ(c.square_size_mm, 15);
  EXPECT_EQ(c.marker_size_mm, 11);
  const TargetSpec a = read_target_yaml(kData + "aprilgrid_6x6.yaml");
  EXPECT_EQ(a.marker_size_mm, 6.6);
  EXPECT_EQ(a.square_size_mm, 22);
}

TEST(TargetYaml, RoundTripIsExactForAwkwardNumbers) {
  TargetSpec s = charuco(5, 4, CharucoLayout::legacy);
  s.name = "bench: board #2";  // needs quoting in YAML
  s.square_size_mm = 0.1 + 0.2;
  s.marker_size_mm = 1.0 / 7;
  s.first_id = 3;
  const TargetSpec back = parse_target_yaml(format_target_yaml(s), "x.yaml");
  EXPECT_EQ(back.name, s.name);
  EXPECT_EQ(back.square_size_mm, s.square_size_mm);
  EXPECT_EQ(back.marker_size_mm, s.marker_size_mm);
  EXPECT_EQ(back.first_id, 3);
  EXPECT_EQ(back.charuco_layout, CharucoLayout::legacy);
}

TEST(TargetYaml, SingleMarkersRoundTrip) {
  TargetSpec m = aruco_marker();
  m.name = "frame fiducial, left";
  m.marker_size_mm = 1.0 / 3;
  TargetSpec t = apriltag("tagStandard41h12");
  t.first_id = 2114;
  t.marker_size_mm = 0.1 + 0.2;
  for (const TargetSpec& s : {m, t, apriltag("tag16h5"), aruco_marker()}) {
    SCOPED_TRACE(describe_target(s));
    const std::string yaml = format_target_yaml(s);
    const TargetSpec back = parse_target_yaml(yaml, "again.yaml");
    EXPECT_EQ(back.kind, s.kind);
    EXPECT_EQ(back.name, s.name.empty() ? "again" : s.name);
    EXPECT_EQ(back.marker_size_mm, s.marker_size_mm);  // exact
    EXPECT_EQ(back.dictionary, s.dictionary);
    EXPECT_EQ(back.first_id, s.first_id);
    EXPECT_EQ(back.squares_x, 0);
    EXPECT_EQ(back.square_size_mm, 0);
    EXPECT_EQ(format_target_yaml(back.name == s.name ? back : s), yaml);
  }
  const TargetSpec a = parse_target_yaml(
      "glasspiv_target: 1\nkind: aruco_marker\ndictionary: DICT_4X4_50\nmarker_id: 7\nmarker_size_mm: 30\n", "m.yaml");
  EXPECT_EQ(a.kind, TargetKind::aruco_marker);
  EXPECT_EQ(a.first_id, 7);
  EXPECT_EQ(a.marker_size_mm, 30);
  const TargetSpec b = parse_target_yaml(
      "glasspiv_target: 1\nkind: apriltag\ndictionary: tag25h9\ntag_id: 4\ntag_size_mm: 22.5\n", "t.yaml");
  EXPECT_EQ(b.kind, TargetKind::apriltag);
  EXPECT_EQ(b.dictionary, "tag25h9");
  EXPECT_EQ(b.first_id, 4);
  EXPECT_EQ(b.marker_size_mm, 22.5);
}

const char* const kGood =
    "glasspiv_target: 1\n"
    "kind: charuco\n"
    "squares: [11, 8]\n"
    "square_size_mm: 15\n"
    "marker_size_mm: 11\n"
    "dictionary: DICT_5X5_100\n";

TEST(TargetYaml, DefaultsAndOptionalKeys) {
  const TargetSpec s = parse_target_yaml(kGood, "dir/lab_board.yaml");
  EXPECT_EQ(s.name, "lab_board");
  EXPECT_EQ(s.first_id, 0);
  EXPECT_EQ(s.charuco_layout, CharucoLayout::opencv);
  const TargetSpec g = parse_target_yaml(
      "glasspiv_target: 1\nkind: aprilgrid\ntags: [6, 6]\ntag_size_mm: 22\ntag_spacing_mm: 6.6\n", "g.yaml");
  EXPECT_EQ(g.dictionary, "tag36h11");
}

struct Rejection {
  const char* name;
  std::string yaml;
  const char* field;
  const char* says;  // part of the message
};

TEST(TargetYaml, RejectsEveryKindOfMistake) {
  const std::string good = kGood;
  auto replace = [&](const std::string& from, const std::string& to) {
    std::string s = good;
    s.replace(s.find(from), from.size(), to);
    return s;
  };
  const Rejection cases[] = {
      {"unknown key", good + "colour: red\n", "colour", "unknown field"},
      {"key of another kind", good + "tag_size_mm: 3\n", "tag_size_mm", "charuco targets do not use it"},
      {"chessboard with markers",
       "glasspiv_target: 1\nkind: chessboard\nsquares: [9, 6]\nsquare_size_mm: 25\nmarker_size_mm: 3\n",
       "marker_size_mm", "chessboard targets do not use it"},
      {"aprilgrid with squares",
       "glasspiv_target: 1\nkind: aprilgrid\nsquares: [6, 6]\ntag_size_mm: 22\ntag_spacing_mm: 6.6\n", "squares",
       "aprilgrid targets do not use it"},
      {"missing key", replace("marker_size_mm: 11\n", ""), "marker_size_mm", "missing"},
      {"missing version", replace("glasspiv_target: 1\n", ""), "glasspiv_target", "missing"},
      {"wrong version", replace("glasspiv_target: 1", "glasspiv_target: 2"), "glasspiv_target", "version 2"},
      {"unknown kind", replace("kind: charuco", "kind: circles"), "kind", "not a target kind"},
      {"squares not a list", replace("[11, 8]", "11x8"), "squares", "list of two"},
      {"squares of three", replace("[11, 8]", "[11, 8, 2]"), "squares", "list of two"},
      {"squares not whole", replace("[11, 8]", "[11.5, 8]"), "squares[0]", "whole number"},
      {"squares text", replace("[11, 8]", "[eleven, 8]"), "squares[0]", "must be a number"},
      {"too few squares", replace("[11, 8]", "[11, 2]"), "squares", "at least 3"},
      {"negative size", replace("square_size_mm: 15", "square_size_mm: -15"), "square_size_mm", "positive"},
      {"zero marker", replace("marker_size_mm: 11", "marker_size_mm: 0"), "marker_size_mm", "positive"},
      {"size as text", replace("square_size_mm: 15", "square_size_mm: 15mm"), "square_size_mm", "number"},
      {"size as list", replace("square_size_mm: 15", "square_size_mm: [15]"), "square_size_mm", "number"},
      {"size infinite", replace("square_size_mm: 15", "square_size_mm: .inf"), "square_size_mm", "number"},
      {"marker >= square", replace("marker_size_mm: 11", "marker_size_mm: 15"), "marker_size_mm", "smaller"},
      {"unknown dictionary", replace("DICT_5X5_100", "DICT_5X5_101"), "dictionary", "not an OpenCV dictionary"},
      {"dictionary too small", replace("DICT_5X5_100", "DICT_4X4_50") + "first_id: 10\n", "first_id", "only ids"},
      {"negative first id", good + "first_id: -1\n", "first_id", "0 or more"},
      {"unknown layout", good + "charuco_layout: new\n", "charuco_layout", "not a layout"},
      {"repeated key", good + "square_size_mm: 16\n", "square_size_mm", "twice"},
      {"aprilgrid gap too small",
       "glasspiv_target: 1\nkind: aprilgrid\ntags: [6, 6]\ntag_size_mm: 22\ntag_spacing_mm: 1\n", "tag_spacing_mm",
       "one bit"},
      {"aprilgrid family", "glasspiv_target: 1\nkind: aprilgrid\ntags: [6, 6]\ntag_size_mm: 22\ntag_spacing_mm: 6\n"
                           "dictionary: tag25h9\n",
       "dictionary", "tag36h11"},
      {"chessboard parity", "glasspiv_target: 1\nkind: chessboard\nsquares: [8, 6]\nsquare_size_mm: 25\n", "squares",
       "180 degrees"},
  };
  for (const Rejection& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string message =
        expect_input_error([&] { parse_target_yaml(c.yaml, "spec.yaml"); }, c.field, "spec.yaml");
    EXPECT_NE(message.find(c.says), std::string::npos) << message;
  }
  // Whole-file problems name no field.
  expect_input_error([] { parse_target_yaml("kind: [charuco", "spec.yaml"); }, "", "spec.yaml");
  expect_input_error([] { parse_target_yaml("- 1\n- 2\n", "spec.yaml"); }, "", "spec.yaml");
  expect_input_error([] { read_target_yaml("no/such/spec.yaml"); }, "", "no/such/spec.yaml");
}

TEST(TargetYaml, SingleMarkerRejections) {
  const std::string aruco = "glasspiv_target: 1\nkind: aruco_marker\ndictionary: DICT_4X4_50\nmarker_id: 7\n";
  const std::string tag = "glasspiv_target: 1\nkind: apriltag\ndictionary: tag36h11\ntag_id: 3\n";
  const Rejection cases[] = {
      {"aruco without size", aruco, "marker_size_mm", "missing"},
      {"aruco without id", "glasspiv_target: 1\nkind: aruco_marker\ndictionary: DICT_4X4_50\nmarker_size_mm: 30\n",
       "marker_id", "missing"},
      {"aruco without dictionary", "glasspiv_target: 1\nkind: aruco_marker\nmarker_id: 1\nmarker_size_mm: 30\n",
       "dictionary", "missing"},
      {"aruco with a tag size", aruco + "tag_size_mm: 30\n", "tag_size_mm", "aruco_marker targets do not use it"},
      {"aruco with squares", aruco + "marker_size_mm: 30\nsquares: [1, 1]\n", "squares", "do not use it"},
      {"aruco with first_id", aruco + "marker_size_mm: 30\nfirst_id: 7\n", "first_id", "do not use it"},
      {"aruco id beyond", "glasspiv_target: 1\nkind: aruco_marker\ndictionary: DICT_4X4_50\nmarker_id: 50\n"
                          "marker_size_mm: 30\n",
       "marker_id", "0 to 49"},
      {"aruco negative id", "glasspiv_target: 1\nkind: aruco_marker\ndictionary: DICT_4X4_50\nmarker_id: -2\n"
                            "marker_size_mm: 30\n",
       "marker_id", "0 or more"},
      {"aruco of a tag family", "glasspiv_target: 1\nkind: aruco_marker\ndictionary: tag36h11\nmarker_id: 2\n"
                                "marker_size_mm: 30\n",
       "dictionary", "not an OpenCV dictionary"},
      {"aruco size text", aruco + "marker_size_mm: 3cm\n", "marker_size_mm", "number"},
      {"tag without size", tag, "tag_size_mm", "missing"},
      {"tag with marker size", tag + "marker_size_mm: 30\n", "marker_size_mm", "apriltag targets do not use it"},
      {"tag with spacing", tag + "tag_size_mm: 30\ntag_spacing_mm: 3\n", "tag_spacing_mm", "do not use it"},
      {"tag id beyond", "glasspiv_target: 1\nkind: apriltag\ndictionary: tag16h5\ntag_id: 30\ntag_size_mm: 30\n",
       "tag_id", "0 to 29"},
      {"tag family unknown",
       "glasspiv_target: 1\nkind: apriltag\ndictionary: tag36h12\ntag_id: 0\ntag_size_mm: 30\n", "dictionary",
       "not an AprilTag family"},
      {"tag id not whole", "glasspiv_target: 1\nkind: apriltag\ndictionary: tag36h11\ntag_id: 1.5\ntag_size_mm: 30\n",
       "tag_id", "whole number"},
      {"tag size zero", tag + "tag_size_mm: 0\n", "tag_size_mm", "positive"},
  };
  for (const Rejection& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string message =
        expect_input_error([&] { parse_target_yaml(c.yaml, "spec.yaml"); }, c.field, "spec.yaml");
    EXPECT_NE(message.find(c.says), std::string::npos) << message;
  }
}

}  // namespace
}  // namespace glasspiv
