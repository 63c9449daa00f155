// Detectors on synthetic photos with known truth (render_pinhole_target_photo,
// sim/target_photo.h): each detector's pixel convention and accuracy,
// orientation and ids, the two ChArUco layouts, and what "not found" looks like.
//
// Tolerances. A corner's truth is the board point mapped by the exact
// homography of the synthetic camera; the photos are area-sampled, blurred by a
// symmetric 0.7 px Gaussian and carry 2 grey levels of seeded noise, so a
// detector in glasspiv's convention has no systematic error. bias (the mean
// error vector over all corners of four poses) < 0.05 px: a tenth of the
// half-pixel convention error this must catch, and 5 to 10 times what the
// detectors measure (docs/targets.md); RMS < 0.15 px: 3 to 4 times what they
// measure, the noise alone gives about 0.03 px.
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>
#include <opencv2/aruco/charuco.hpp>
#include <opencv2/imgproc.hpp>

#include "sim/calibration_views.h"
#include "sim/target_photo.h"
#include "targets/target_detect.h"
#include "targets/target_image.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {

TargetSpec charuco(CharucoLayout layout, int squares_y = 8) {
  TargetSpec s;
  s.kind = TargetKind::charuco;
  s.squares_x = 11;
  s.squares_y = squares_y;
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
  s.square_size_mm = 20;
  return s;
}

TargetSpec aprilgrid() {
  TargetSpec s;
  s.kind = TargetKind::aprilgrid;
  s.squares_x = 6;
  s.squares_y = 6;
  s.square_size_mm = 20;
  s.marker_size_mm = 6;
  s.dictionary = "tag36h11";
  return s;
}

struct Pose {
  double tilt_x, tilt_y, roll;
  Eigen::Vector2d offset_px;
};
// Sub-pixel offsets, tilts up to 0.5 rad, and one pose upside down (roll 3.3 rad)
// so that orientation and id assignment are tested too.
const Pose kPoses[] = {{0.12, -0.08, 0.04, {0.3, -0.2}},
                       {-0.45, 0.25, 0.35, {-20.4, 10.7}},
                       {0.3, 0.5, -0.6, {15.1, -12.3}},
                       {0.2, -0.3, 3.3, {5.25, 3.75}}};

// The photos' pinhole camera: 1280 x 960 px, f = 1400 px, the principal point
// at the image centre.
CameraModel photo_camera() { return CameraModel(1280, 960, 1400, 1400, 639.5, 479.5); }

// The board's centre `distance_mm` deep, seen at the image centre plus `p.offset_px`.
PinholeTargetPhoto photo_of(const TargetSpec& spec, const Pose& p, std::uint64_t seed, double distance_mm = 420,
                            int supersample = 4) {
  const CameraModel camera = photo_camera();
  const Eigen::Vector3d centre_camera_mm(p.offset_px.x() * distance_mm / camera.fx_px(),
                                         p.offset_px.y() * distance_mm / camera.fy_px(), distance_mm);
  PinholePhotoOptions options;
  options.seed = seed;
  options.supersample = supersample;
  return render_pinhole_target_photo(
      camera, board_pose_facing(centre_camera_mm, board_size_mm(spec), p.tilt_x, p.tilt_y, p.roll), spec, options);
}

struct Accuracy {
  Eigen::Vector2d bias = Eigen::Vector2d::Zero();
  double rms = 0;
  int found = 0, expected = 0;
};

// Errors against the truth over all poses; `shift_px` is added to every
// detection (to show a half-pixel convention error fails the test).
Accuracy accuracy(const TargetSpec& spec, DetectOptions options = {}, double shift_px = 0,
                  double distance_mm = 420) {
  const TargetDetector detector(spec, options);
  Accuracy a;
  double squares = 0;
  std::uint64_t seed = 1;
  for (const Pose& p : kPoses) {
    const PinholeTargetPhoto photo = photo_of(spec, p, seed++, distance_mm);
    const DetectionResult r = detector.detect(photo.image, "synthetic");
    a.expected += static_cast<int>(board_corner_count(spec));
    EXPECT_TRUE(r.note.empty()) << r.note;
    for (const CornerObservation& c : r.view.corners) {
      const Eigen::Vector2d e = c.pixel_px + Eigen::Vector2d(shift_px, shift_px) - photo.project(c.board_point_mm);
      // A wrong id would be a whole square (> 30 px) off.
      if (shift_px == 0) {
        EXPECT_LT(e.norm(), 0.5) << "corner " << c.id;
      }
      a.bias += e;
      squares += e.squaredNorm();
      ++a.found;
    }
  }
  if (a.found > 0) {
    a.bias /= a.found;
    a.rms = std::sqrt(squares / a.found);
  }
  std::printf("%-100s %d/%d corners, bias (%+.4f, %+.4f) px, RMS %.4f px\n", describe_target(spec).c_str(), a.found,
              a.expected, a.bias.x(), a.bias.y(), a.rms);
  return a;
}

void expect_accurate(const Accuracy& a) {
  EXPECT_EQ(a.found, a.expected);  // the whole board is in view in every pose
  EXPECT_LT(a.bias.norm(), 0.05);
  EXPECT_LT(a.rms, 0.15);
}

TEST(DetectorAccuracy, ChessboardSectorBased) {
  expect_accurate(accuracy(chessboard(), {DetectOptions::ChessboardMethod::sector_based, true}));
}

TEST(DetectorAccuracy, ChessboardClassic) {
  expect_accurate(accuracy(chessboard(), {DetectOptions::ChessboardMethod::classic, true}));
}

TEST(DetectorAccuracy, CharucoOpenCvLayout) { expect_accurate(accuracy(charuco(CharucoLayout::opencv))); }

TEST(DetectorAccuracy, CharucoLegacyLayout) { expect_accurate(accuracy(charuco(CharucoLayout::legacy))); }

TEST(DetectorAccuracy, Aprilgrid) { expect_accurate(accuracy(aprilgrid())); }

TEST(DetectorAccuracy, SmallSquares) {
  // 700 mm away: 30 px squares, 3 px marker bits, 4 px of white between a
  // ChArUco marker and its square's corners. OpenCV 4.6's own ChArUco
  // refinement put a tenth of these corners onto marker corners (4 px off).
  for (const TargetSpec& spec : {chessboard(), charuco(CharucoLayout::opencv), aprilgrid()})
    expect_accurate(accuracy(spec, {}, 0, 700));
}

TEST(DetectorAccuracy, OpenCvCharucoCornersAreHalfAPixelOff) {
  // What glasspiv's ChArUco interpolation replaces: OpenCV 4.6's
  // interpolateCornersCharuco on the same photos, measured, not relied on.
  const TargetSpec spec = charuco(CharucoLayout::opencv);
  const auto dictionary = cv::aruco::getPredefinedDictionary(cv::aruco::DICT_5X5_100);
  const auto board = cv::aruco::CharucoBoard::create(11, 8, 15.f, 11.f, dictionary);
  Eigen::Vector2d bias = Eigen::Vector2d::Zero();
  int n = 0;
  std::uint64_t seed = 1;
  for (const Pose& p : kPoses) {
    const PinholeTargetPhoto photo = photo_of(spec, p, seed++);
    std::vector<std::vector<cv::Point2f>> markers;
    std::vector<int> ids, corner_ids;
    std::vector<cv::Point2f> corners;
    cv::aruco::detectMarkers(photo.image, dictionary, markers, ids);
    cv::aruco::interpolateCornersCharuco(markers, ids, photo.image, board, corners, corner_ids);
    for (std::size_t i = 0; i < corner_ids.size(); ++i) {
      const cv::Point3f b = board->chessboardCorners[static_cast<std::size_t>(corner_ids[i])];
      const Eigen::Vector2d e = Eigen::Vector2d(corners[i].x, corners[i].y) - photo.project(Eigen::Vector3d(b.x, b.y, 0));
      if (e.norm() < 2) bias += e, ++n;
    }
  }
  bias /= n;
  std::printf("OpenCV %s interpolateCornersCharuco: %d corners, bias (%+.4f, %+.4f) px\n", CV_VERSION, n, bias.x(),
              bias.y());
  EXPECT_GT(n, 200);
}

TEST(DetectorAccuracy, HalfPixelConventionErrorWouldFail) {
  // The same measurement with every detection moved by half a pixel (the
  // libapriltag or OpenCV 4.6 ChArUco offset left in) fails the bias bound.
  for (const TargetSpec& spec : {aprilgrid(), charuco(CharucoLayout::opencv)}) {
    const Accuracy shifted = accuracy(spec, {}, 0.5);
    EXPECT_GT(shifted.bias.norm(), 0.05 * 10);
  }
}

// ------------------------------------------------------------ charuco layouts

TEST(CharucoLayouts, AWrongLayoutIsRefusedNotMisread) {
  // A legacy board (top-left square white) looked for as an opencv-layout board,
  // and the other way round: no corners, and a note that names the right layout.
  for (const CharucoLayout printed : {CharucoLayout::legacy, CharucoLayout::opencv}) {
    const CharucoLayout requested = printed == CharucoLayout::legacy ? CharucoLayout::opencv : CharucoLayout::legacy;
    std::uint64_t seed = 10;
    for (const Pose& p : kPoses) {
      const PinholeTargetPhoto photo = photo_of(charuco(printed), p, seed++);
      const DetectionResult r = TargetDetector(charuco(requested)).detect(photo.image, "wrong");
      EXPECT_TRUE(r.view.corners.empty()) << r.view.corners.size() << " corners";
      EXPECT_NE(r.note.find("match the " + charuco_layout_name(printed) + " layout"), std::string::npos) << r.note;
      EXPECT_GT(r.markers_found, 30);
    }
  }
}

TEST(CharucoLayouts, OpenCvAloneMisreadsALegacyBoard) {
  // Why the check above exists: OpenCV 4.6's interpolateCornersCharuco, given a
  // photo of a legacy board and its own (opencv layout) board, returns corners
  // under wrong ids, most of them a whole square away from their id's place.
  const PinholeTargetPhoto photo = photo_of(charuco(CharucoLayout::legacy), kPoses[0], 20);
  const auto dictionary = cv::aruco::getPredefinedDictionary(cv::aruco::DICT_5X5_100);
  const auto board = cv::aruco::CharucoBoard::create(11, 8, 15.f, 11.f, dictionary);
  std::vector<std::vector<cv::Point2f>> markers;
  std::vector<int> ids;
  cv::aruco::detectMarkers(photo.image, dictionary, markers, ids);
  std::vector<cv::Point2f> corners;
  std::vector<int> corner_ids;
  cv::aruco::interpolateCornersCharuco(markers, ids, photo.image, board, corners, corner_ids);
  int misplaced = 0;
  for (std::size_t i = 0; i < corner_ids.size(); ++i) {
    const cv::Point3f b = board->chessboardCorners[static_cast<std::size_t>(corner_ids[i])];
    const Eigen::Vector2d truth = photo.project(Eigen::Vector3d(b.x, b.y, 0));
    if ((Eigen::Vector2d(corners[i].x, corners[i].y) - truth).norm() > 10) ++misplaced;
  }
  std::printf("OpenCV 4.6 alone on a legacy board: %zu corners, %d of them under a wrong id\n", corner_ids.size(),
              misplaced);
  EXPECT_GT(misplaced, 0);
}

TEST(CharucoLayouts, ACloseUpCannotTellTheLayoutsApart) {
  // Away from its left and right edges a legacy board is an opencv board moved
  // by one column with the same marker ids: a close-up of the middle is refused
  // unless the caller accepts views without layout evidence.
  const TargetSpec legacy = charuco(CharucoLayout::legacy);
  // 150 mm away the photo shows about 137 x 103 mm of the 165 x 120 mm board.
  const Pose close_up{0.05, -0.05, 0.05, Eigen::Vector2d::Zero()};
  const PinholeTargetPhoto photo = photo_of(legacy, close_up, 30, 150, 3);  // 3x: the board is big in this photo
  const DetectionResult strict = TargetDetector(legacy).detect(photo.image, "close-up");
  EXPECT_TRUE(strict.view.corners.empty());
  EXPECT_NE(strict.note.find("cannot tell"), std::string::npos) << strict.note;
  DetectOptions lenient;
  lenient.require_layout_evidence = false;
  const DetectionResult r = TargetDetector(legacy, lenient).detect(photo.image, "close-up");
  ASSERT_GT(r.view.corners.size(), 20u);
  for (const CornerObservation& c : r.view.corners)
    EXPECT_LT((c.pixel_px - photo.project(c.board_point_mm)).norm(), 0.5) << c.id;
}

TEST(CharucoLayouts, OddRowsAreTheSameBoard) {
  // 7 rows: both layouts print the same board; either spec reads it the same.
  const PinholeTargetPhoto photo = photo_of(charuco(CharucoLayout::opencv, 7), kPoses[1], 40);
  const ViewObservations a = detect_target(photo.image, charuco(CharucoLayout::opencv, 7), "odd");
  const ViewObservations b = detect_target(photo.image, charuco(CharucoLayout::legacy, 7), "odd");
  ASSERT_EQ(a.corners.size(), 60u);
  ASSERT_EQ(b.corners.size(), a.corners.size());
  for (std::size_t i = 0; i < a.corners.size(); ++i) {
    EXPECT_EQ(a.corners[i].id, b.corners[i].id);
    EXPECT_EQ(a.corners[i].pixel_px, b.corners[i].pixel_px);
  }
}

TEST(CharucoLayouts, FirstIdSelectsTheBoard) {
  // Two boards from one dictionary: ids 0..43 and 50..93. Each spec finds only its own.
  TargetSpec second = charuco(CharucoLayout::opencv);
  second.first_id = 50;
  const PinholeTargetPhoto photo = photo_of(second, kPoses[2], 50);
  EXPECT_EQ(detect_target(photo.image, second, "b").corners.size(), 70u);
  const DetectionResult other = TargetDetector(charuco(CharucoLayout::opencv)).detect(photo.image, "b");
  EXPECT_TRUE(other.view.corners.empty());
  EXPECT_EQ(other.markers_found, 0);
}

// ------------------------------------------------------------ partial views, not found

TEST(Detect, AprilgridWithCoveredTagsReportsTheRest) {
  const TargetSpec spec = aprilgrid();
  PinholeTargetPhoto photo = photo_of(spec, kPoses[1], 60);
  // Paint over tags 0 and 14 (mid-grey quadrilaterals over their squares).
  for (const int index : {0, 14}) {
    std::vector<cv::Point> quad;
    const double x = (index % 6) * 26.0 - 1, y = (index / 6) * 26.0 - 1;
    for (const auto& [dx, dy] : {std::pair{0.0, 0.0}, {22.0, 0.0}, {22.0, 22.0}, {0.0, 22.0}}) {
      const Eigen::Vector2d p = photo.project(Eigen::Vector3d(x + dx, y + dy, 0));
      quad.emplace_back(static_cast<int>(p.x()), static_cast<int>(p.y()));
    }
    cv::fillConvexPoly(photo.image, quad, cv::Scalar(128));
  }
  const ViewObservations v = detect_target(photo.image, spec, "covered");
  ASSERT_EQ(v.corners.size(), 4u * 34u);
  for (const CornerObservation& c : v.corners) {
    EXPECT_NE(c.id / 4, 0);
    EXPECT_NE(c.id / 4, 14);
    EXPECT_LT((c.pixel_px - photo.project(c.board_point_mm)).norm(), 0.5);
  }
}

TEST(Detect, NothingToFindIsNoError) {
  const cv::Mat blank(480, 640, CV_8UC1, cv::Scalar(200));
  for (const TargetSpec& spec : {chessboard(), charuco(CharucoLayout::opencv), aprilgrid()}) {
    const DetectionResult r = TargetDetector(spec).detect(blank, "blank.png");
    EXPECT_TRUE(r.view.corners.empty());
    EXPECT_EQ(r.view.source, "blank.png");
    EXPECT_FALSE(r.note.empty());
  }
  // A chessboard photo holds no charuco board.
  const PinholeTargetPhoto photo = photo_of(chessboard(), kPoses[0], 70);
  EXPECT_TRUE(detect_target(photo.image, charuco(CharucoLayout::opencv), "c").corners.empty());
}

TEST(Detect, RejectsImagesItCannotRead) {
  const TargetDetector detector(chessboard());
  try {
    detector.detect(cv::Mat(10, 10, CV_8UC3, cv::Scalar(0)), "colour.png");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "colour.png");
    EXPECT_EQ(e.field(), "image");
  }
  EXPECT_THROW(detector.detect(cv::Mat(), "empty.png"), InputError);
  EXPECT_THROW(detector.detect(cv::Mat(10, 10, CV_16UC1, cv::Scalar(0)), "deep.png"), InputError);
}

TEST(Detect, DetectorRejectsInvalidSpecs) {
  TargetSpec bad = chessboard();
  bad.squares_x = 1;
  EXPECT_THROW(TargetDetector{bad}, InputError);
}

// ------------------------------------------------------------ single markers

TEST(DetectorAccuracy, SingleMarkers) {
  // A 30 mm marker 420 mm away (about 100 px) in the four poses, through
  // TargetDetector: corners 0..3 at board_corners(), the bounds above.
  for (const std::string dictionary : {"DICT_4X4_50", "tag36h11", "tagStandard41h12"}) {
    TargetSpec s;
    s.kind = opencv_dictionary_id(dictionary) >= 0 ? TargetKind::aruco_marker : TargetKind::apriltag;
    s.dictionary = dictionary;
    s.first_id = 7;
    s.marker_size_mm = 30;
    const Accuracy a = accuracy(s);
    expect_accurate(a);
  }
}

TEST(Detect, SingleMarkerOfAnotherIdIsNotFound) {
  TargetSpec s;
  s.kind = TargetKind::aruco_marker;
  s.dictionary = "DICT_4X4_50";
  s.first_id = 7;
  s.marker_size_mm = 30;
  const PinholeTargetPhoto photo = photo_of(s, kPoses[0], 80);
  TargetSpec other = s;
  other.first_id = 8;
  const DetectionResult r = TargetDetector(other).detect(photo.image, "seven.png");
  EXPECT_TRUE(r.view.corners.empty());
  EXPECT_EQ(r.markers_found, 0);
  EXPECT_NE(r.note.find("id 8 not found (1 other"), std::string::npos) << r.note;
  const DetectionResult found = TargetDetector(s).detect(photo.image, "seven.png");
  ASSERT_EQ(found.view.corners.size(), 4u);
  EXPECT_EQ(found.markers_found, 1);
}

}  // namespace
}  // namespace glasspiv
