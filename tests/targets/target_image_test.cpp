// Pictures of targets: the raster's pixel convention and exact area sampling,
// the SVG's scale and caption, the PNG's resolution tag, and that libapriltag
// reads the tag36h11 codes OpenCV draws with the same ids.
#include <cmath>
#include <filesystem>
#include <regex>
#include <string>

#include <apriltag/apriltag.h>
#include <apriltag/tag16h5.h>
#include <apriltag/tag25h9.h>
#include <apriltag/tag36h11.h>
#include <apriltag/tagCircle21h7.h>
#include <apriltag/tagStandard41h12.h>
#include <opencv2/aruco.hpp>
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "targets/target_image.h"
#include "targets/target_yaml.h"
#include "util/atomic_file.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {

TargetSpec charuco() {
  TargetSpec s;
  s.kind = TargetKind::charuco;
  s.name = "lab <A>";
  s.squares_x = 11;
  s.squares_y = 8;
  s.square_size_mm = 15;
  s.marker_size_mm = 11;
  s.dictionary = "DICT_5X5_100";
  return s;
}

TargetSpec chessboard() {
  TargetSpec s;
  s.kind = TargetKind::chessboard;
  s.squares_x = 5;
  s.squares_y = 4;
  s.square_size_mm = 10;
  return s;
}

TargetSpec aprilgrid(int first_id) {
  TargetSpec s;
  s.kind = TargetKind::aprilgrid;
  s.squares_x = 6;
  s.squares_y = 6;
  s.square_size_mm = 16;
  s.marker_size_mm = 4;
  s.dictionary = "tag36h11";
  s.first_id = first_id;
  return s;
}

TEST(Render, SizeAndPixelCentreConvention) {
  const TargetSpec s = chessboard();
  const double ppmm = 3.3, margin = 5;  // square edges fall inside pixels
  const TargetRender r = render_target(s, ppmm, margin);
  EXPECT_EQ(r.image.cols, static_cast<int>(std::ceil(60 * ppmm)));
  EXPECT_EQ(r.image.rows, static_cast<int>(std::ceil(50 * ppmm)));
  ASSERT_EQ(r.image.type(), CV_8UC1);
  // The mapping itself: the board's origin is the outer corner of pixel
  // (margin * ppmm) in edge coordinates, i.e. half a pixel before that centre.
  EXPECT_NEAR((r.pixel_from_board(Eigen::Vector2d(0, 0)) - Eigen::Vector2d(margin * ppmm - 0.5, margin * ppmm - 0.5)).norm(),
              0, 1e-12);
  EXPECT_NEAR((r.board_from_pixel(r.pixel_from_board(Eigen::Vector2d(12.3, 4.5))) - Eigen::Vector2d(12.3, 4.5)).norm(),
              0, 1e-12);
  // Ink centroid of the top-left black square (0..10 mm): along the pixel row
  // and column through its middle (no other square's ink there up to the middle
  // of the next square), area sampling puts it exactly at pixel_from_board(5, 5),
  // up to the 8-bit rounding of the two edge pixels (< 0.5/255 of a pixel's
  // weight each: under 1e-3 px). A half-pixel convention error would be 0.5 px.
  const Eigen::Vector2d centre = r.pixel_from_board(Eigen::Vector2d(5, 5));
  const Eigen::Vector2d next = r.pixel_from_board(Eigen::Vector2d(15, 15));
  const int mid_row = static_cast<int>(std::lround(centre.y())), mid_col = static_cast<int>(std::lround(centre.x()));
  double sum_x = 0, moment_x = 0, sum_y = 0, moment_y = 0;
  for (int i = 0; i <= static_cast<int>(next.x()); ++i) {
    const double ink_x = (255.0 - r.image.at<unsigned char>(mid_row, i)) / 255.0;
    const double ink_y = (255.0 - r.image.at<unsigned char>(i, mid_col)) / 255.0;
    sum_x += ink_x, moment_x += ink_x * i;
    sum_y += ink_y, moment_y += ink_y * i;
  }
  EXPECT_NEAR(moment_x / sum_x, centre.x(), 1e-3);
  EXPECT_NEAR(moment_y / sum_y, centre.y(), 1e-3);
  EXPECT_NEAR(sum_x, 10 * ppmm, 2.0 / 255);  // the square's width in px
  EXPECT_NEAR(sum_y, 10 * ppmm, 2.0 / 255);
  // Interior pixels are pure ink or paper.
  const Eigen::Vector2d black = r.pixel_from_board(Eigen::Vector2d(5, 5));
  const Eigen::Vector2d white = r.pixel_from_board(Eigen::Vector2d(15, 5));
  EXPECT_EQ(r.image.at<unsigned char>(static_cast<int>(black.y()), static_cast<int>(black.x())), 0);
  EXPECT_EQ(r.image.at<unsigned char>(static_cast<int>(white.y()), static_cast<int>(white.x())), 255);
  EXPECT_EQ(r.image.at<unsigned char>(0, 0), 255);  // margin
}

TEST(Render, PartialPixelCoverage) {
  // 1.55 px/mm, 1 mm margin: the top-left square spans edge coordinates
  // [1.55, 17.05] in x and y (pixel i covers [i, i + 1]); square (1, 1) starts
  // at 17.05. Each pixel is 255 * (1 - covered area), rounded.
  const TargetRender r = render_target(chessboard(), 1.55, 1);
  auto value = [](double ink) { return static_cast<int>(std::lround(255 * (1 - ink))); };
  EXPECT_EQ(r.image.at<unsigned char>(5, 1), value(0.45));           // left edge
  EXPECT_EQ(r.image.at<unsigned char>(5, 17), value(0.05));          // right edge
  EXPECT_EQ(r.image.at<unsigned char>(1, 1), value(0.45 * 0.45));    // outer corner
  EXPECT_EQ(r.image.at<unsigned char>(17, 17), value(0.05 * 0.05 + 0.95 * 0.95));  // inner corner, two squares
  EXPECT_EQ(r.image.at<unsigned char>(5, 5), 0);
  EXPECT_EQ(r.image.at<unsigned char>(0, 0), 255);
}

TEST(Render, RejectsBadResolution) {
  EXPECT_THROW(render_target(chessboard(), 0, 1), InputError);
  EXPECT_THROW(render_target(chessboard(), -2, 1), InputError);
  EXPECT_THROW(render_target(chessboard(), 1e6, 1), InputError);  // terapixels
  EXPECT_THROW(render_target(chessboard(), 2, -1), InputError);
}

double attribute(const std::string& svg, const std::string& name) {
  const std::smatch m = [&] {
    std::smatch match;
    std::regex_search(svg, match, std::regex(name + "=\"([0-9.]+)(mm)?\""));
    return match;
  }();
  return m.empty() ? -1 : std::stod(m[1]);
}

TEST(Svg, ExactMillimetreScaleAndCaption) {
  const TargetSpec s = charuco();
  const std::string svg = target_svg(s);
  const Eigen::Vector2d page = target_svg_size_mm(s);
  // Half a square of margin around 165 x 120 mm; the caption below.
  EXPECT_DOUBLE_EQ(page.x(), 165 + 15);
  EXPECT_GT(page.y(), 120 + 15);
  EXPECT_DOUBLE_EQ(attribute(svg, "width"), page.x());
  EXPECT_DOUBLE_EQ(attribute(svg, "height"), page.y());
  std::smatch view;
  ASSERT_TRUE(std::regex_search(svg, view, std::regex("viewBox=\"0 0 ([0-9.]+) ([0-9.]+)\"")));
  EXPECT_DOUBLE_EQ(std::stod(view[1]), page.x());  // 1 user unit = 1 mm
  EXPECT_DOUBLE_EQ(std::stod(view[2]), page.y());
  EXPECT_NE(svg.find("width=\"180mm\""), std::string::npos);
  // The first black square: at the margin, one square wide.
  EXPECT_NE(svg.find("<rect x=\"7.5\" y=\"7.5\" width=\"15\" height=\"15\"/>"), std::string::npos);
  // Every black rectangle is there.
  const std::size_t rects = target_black_rects(s).size();
  std::size_t count = 0;
  const std::string pattern = svg.substr(svg.find("<g id=\"pattern\""), svg.find("</g>") - svg.find("<g id=\"pattern\""));
  for (std::size_t at = pattern.find("<rect"); at != std::string::npos; at = pattern.find("<rect", at + 1)) ++count;
  EXPECT_EQ(count, rects);
  // The caption and the 100 mm bar.
  for (const char* text : {"charuco, 11 x 8 squares, square 15 mm, marker 11 mm", "dictionary DICT_5X5_100",
                           "first id 0", "opencv layout", "print at 100% scale; check: this bar is 100 mm",
                           "lab &lt;A&gt;"})
    EXPECT_NE(svg.find(text), std::string::npos) << text;
  EXPECT_NE(svg.find("width=\"100\" height=\"2\""), std::string::npos);
}

TEST(Svg, NarrowBoardsGetRoomForTheBar) {
  TargetSpec s = chessboard();  // 50 mm wide
  EXPECT_GE(target_svg_size_mm(s).x(), 100 + 2 * 5.0);
}

TEST(Png, CarriesItsResolution) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "glasspiv_targets_png_test";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "board.png").string();
  write_target_png(path, chessboard(), 300);
  const cv::Mat back = cv::imread(path, cv::IMREAD_UNCHANGED);
  const TargetRender r = render_target(chessboard(), 300 / 25.4, default_margin_mm(chessboard()));
  ASSERT_EQ(back.size(), r.image.size());
  EXPECT_EQ(cv::norm(back, r.image, cv::NORM_INF), 0);
  const std::string bytes = read_file(path);
  const std::size_t at = bytes.find("pHYs");
  ASSERT_NE(at, std::string::npos);
  const auto u32 = [&](std::size_t i) {
    return (static_cast<unsigned>(static_cast<unsigned char>(bytes[i])) << 24) |
           (static_cast<unsigned>(static_cast<unsigned char>(bytes[i + 1])) << 16) |
           (static_cast<unsigned>(static_cast<unsigned char>(bytes[i + 2])) << 8) |
           static_cast<unsigned>(static_cast<unsigned char>(bytes[i + 3]));
  };
  EXPECT_EQ(u32(at + 4), 11811u);  // 300 dpi = 11811 px/m
  EXPECT_EQ(u32(at + 8), 11811u);
  EXPECT_EQ(bytes[at + 12], 1);    // unit: metre
  std::filesystem::remove_all(dir);
}

TEST(AprilTag, LibapriltagReadsOpenCvTag36h11WithTheSameIds) {
  // The aprilgrid is drawn from OpenCV's DICT_APRILTAG_36h11; libapriltag must
  // decode every tag with the id OpenCV drew, at its place. Ids from the start,
  // the middle and the end of the family (587 codes).
  apriltag_family_t* family = tag36h11_create();
  apriltag_detector_t* detector = apriltag_detector_create();
  apriltag_detector_add_family_bits(detector, family, 0);  // no error correction: codes must match exactly
  detector->quad_decimate = 1;
  for (const int first : {0, 300, 551}) {
    const TargetSpec s = aprilgrid(first);
    TargetRender r = render_target(s, 5, default_margin_mm(s));  // 10 px per bit
    image_u8_t image{r.image.cols, r.image.rows, static_cast<int32_t>(r.image.step[0]), r.image.data};
    zarray_t* detections = apriltag_detector_detect(detector, &image);
    ASSERT_EQ(zarray_size(detections), 36) << "first id " << first;
    for (int i = 0; i < zarray_size(detections); ++i) {
      apriltag_detection_t* d = nullptr;
      zarray_get(detections, i, &d);
      EXPECT_EQ(d->hamming, 0);
      const int index = d->id - first;
      ASSERT_GE(index, 0);
      ASSERT_LT(index, 36);
      // Its centre lies at its tag's centre (libapriltag's corner-of-pixel
      // convention: +0.5 px; 1 px tolerance only checks the place).
      const Eigen::Vector2d centre =
          r.pixel_from_board(Eigen::Vector2d((index % 6) * 20 + 8, (index / 6) * 20 + 8)) + Eigen::Vector2d(0.5, 0.5);
      EXPECT_LT((Eigen::Vector2d(d->c[0], d->c[1]) - centre).norm(), 1.0) << "id " << d->id;
    }
    apriltag_detections_destroy(detections);
  }
  apriltag_detector_destroy(detector);
  tag36h11_destroy(family);
}

TargetSpec single(TargetKind kind, const std::string& dictionary, int id, double size_mm) {
  TargetSpec s;
  s.kind = kind;
  s.dictionary = dictionary;
  s.first_id = id;
  s.marker_size_mm = size_mm;
  return s;
}

TEST(SingleMarker, ArucoIsOpenCvsMarkerBitForBit) {
  // 6 x 6 cells of 5 mm at 2 px/mm: each cell 10 x 10 whole pixels, so the
  // raster must equal OpenCV's drawMarker at 60 px exactly; the default margin
  // is two cells of white.
  for (const int id : {0, 17, 49}) {
    const TargetSpec s = single(TargetKind::aruco_marker, "DICT_4X4_50", id, 30);
    EXPECT_DOUBLE_EQ(default_margin_mm(s), 10);
    const TargetRender r = render_target(s, 2, 0);
    cv::Mat drawn;
    cv::aruco::getPredefinedDictionary(cv::aruco::DICT_4X4_50)->drawMarker(id, 60, drawn, 1);
    ASSERT_EQ(r.image.size(), drawn.size());
    EXPECT_EQ(cv::norm(r.image, drawn, cv::NORM_INF), 0) << "id " << id;
    // OpenCV reads it back with its id.
    const TargetRender framed = render_target(s, 4, default_margin_mm(s));
    std::vector<std::vector<cv::Point2f>> corners;
    std::vector<int> ids;
    cv::aruco::detectMarkers(framed.image, cv::aruco::getPredefinedDictionary(cv::aruco::DICT_4X4_50), corners, ids);
    ASSERT_EQ(ids, std::vector<int>{id});
  }
}

// libapriltag reads each family's tag as glasspiv draws it with the id drawn, no
// corrected bit, and its corners at board_corners() (libapriltag's
// corner-of-pixel convention: +0.5 px; 0.25 px only checks which corner is which).
TEST(SingleMarker, LibapriltagReadsEveryFamilyAsDrawn) {
  struct Family {
    const char* name;
    apriltag_family_t* (*create)();
    void (*destroy)(apriltag_family_t*);
    std::vector<int> ids;
  };
  const Family families[] = {{"tag16h5", tag16h5_create, tag16h5_destroy, {0, 29}},
                             {"tag25h9", tag25h9_create, tag25h9_destroy, {0, 34}},
                             {"tag36h11", tag36h11_create, tag36h11_destroy, {0, 300, 586}},
                             {"tagCircle21h7", tagCircle21h7_create, tagCircle21h7_destroy, {0, 37}},
                             {"tagStandard41h12", tagStandard41h12_create, tagStandard41h12_destroy, {0, 1000, 2114}}};
  for (const Family& f : families) {
    apriltag_family_t* family = f.create();
    apriltag_detector_t* detector = apriltag_detector_create();
    apriltag_detector_add_family_bits(detector, family, 0);
    detector->quad_decimate = 1;
    for (const int id : f.ids) {
      const TargetSpec s = single(TargetKind::apriltag, f.name, id, 40);
      const double cell = 40.0 / family->width_at_border;
      EXPECT_DOUBLE_EQ(default_margin_mm(s), 2 * cell);
      TargetRender r = render_target(s, 10 / cell, default_margin_mm(s));  // 10 px per bit
      image_u8_t image{r.image.cols, r.image.rows, static_cast<int32_t>(r.image.step[0]), r.image.data};
      zarray_t* detections = apriltag_detector_detect(detector, &image);
      ASSERT_EQ(zarray_size(detections), 1) << f.name << " id " << id;
      apriltag_detection_t* d = nullptr;
      zarray_get(detections, 0, &d);
      EXPECT_EQ(d->id, id) << f.name;
      EXPECT_EQ(d->hamming, 0);
      // libapriltag's own tags, upright: p[0..3] = bottom-left, bottom-right,
      // top-right, top-left (marker_detect.cpp's kAprilTagCorner).
      const std::vector<BoardCorner> corners = board_corners(s);
      const int ours_of_p[4] = {3, 2, 1, 0};
      for (int k = 0; k < 4; ++k) {
        const Eigen::Vector2d expected = r.pixel_from_board(corners[static_cast<std::size_t>(ours_of_p[k])].point_mm.head<2>()) +
                                         Eigen::Vector2d(0.5, 0.5);
        EXPECT_LT((Eigen::Vector2d(d->p[k][0], d->p[k][1]) - expected).norm(), 0.25) << f.name << " p" << k;
      }
      apriltag_detections_destroy(detections);
    }
    apriltag_detector_destroy(detector);
    f.destroy(family);
  }
}

TEST(SingleMarker, OpenCvTag36h11IsLibapriltagsTurnedBy180Degrees) {
  // Why an aprilgrid's tag and a single apriltag of the same id have their
  // corner 0 at opposite corners: OpenCV's DICT_APRILTAG_36h11 draws the codes
  // turned by 180 degrees from libapriltag's own pictures.
  for (const int id : {0, 5, 586}) {
    const TargetRender own = render_target(single(TargetKind::apriltag, "tag36h11", id, 40), 1, 0);
    const TargetRender opencv = render_target(single(TargetKind::aruco_marker, "DICT_APRILTAG_36h11", id, 40), 1, 0);
    cv::Mat turned;
    cv::rotate(opencv.image, turned, cv::ROTATE_180);
    // 8 bits of 40 mm at 1 px/mm: whole 5 px cells.
    EXPECT_EQ(cv::norm(own.image, turned, cv::NORM_INF), 0) << "id " << id;
    EXPECT_GT(cv::norm(own.image, opencv.image, cv::NORM_INF), 0) << "id " << id;
  }
}

TEST(SingleMarker, SvgAndCaption) {
  const TargetSpec m = single(TargetKind::aruco_marker, "DICT_4X4_50", 7, 30);
  const std::string svg = target_svg(m);
  for (const char* text : {"ArUco marker DICT_4X4_50 id 7, marker 30 mm (its black border)",
                           "print at 100% scale; check: this bar is 100 mm"})
    EXPECT_NE(svg.find(text), std::string::npos) << text;
  // The top-left cell of the border at the 10 mm margin: a row of 6 black cells.
  EXPECT_NE(svg.find("<rect x=\"10\" y=\"10\" width=\"30\" height=\"5\"/>"), std::string::npos);
  const TargetSpec t = single(TargetKind::apriltag, "tagStandard41h12", 12, 25);
  const std::string tag = target_svg(t);
  EXPECT_NE(tag.find("AprilTag tagStandard41h12 id 12, tag size 25 mm (inside the black ring: the detected square, "
                     "5 bits)"),
            std::string::npos);
  // The 9-bit pattern with its 2-bit margin: 45 + 2 * 10 mm across.
  EXPECT_DOUBLE_EQ(default_margin_mm(t), 10);
  EXPECT_EQ(board_size_mm(t), Eigen::Vector2d(45, 45));
  // Every black rectangle lies on the pattern, none overlap its neighbours' rows.
  for (const TargetSpec& s : {m, t}) {
    const Eigen::Vector2d size = board_size_mm(s);
    for (const BoardRect& r : target_black_rects(s)) {
      EXPECT_GE(r.x0, 0);
      EXPECT_GE(r.y0, 0);
      EXPECT_LE(r.x1, size.x() + 1e-9);
      EXPECT_LE(r.y1, size.y() + 1e-9);
    }
  }
}

}  // namespace
}  // namespace glasspiv
