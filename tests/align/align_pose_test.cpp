// Pose from fiducials on synthetic photographs of a marker frame (sim/marker_setup.h):
// rendered through the model, blurred, vignetted, noise 0.5 grey levels of 255.
// The truth is the scene's own camera pose.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "align/align_pose.h"
#include "align/fiducial_detection.h"
#include "align/prepared_scene.h"
#include "render/setup_render.h"
#include "sim/marker_setup.h"
#include "sim/setup_photo.h"
#include "tests/sanitized_build.h"
#include "tests/temp_dir.h"
#include "util/atomic_file.h"
#include "util/input_error.h"

#include <opencv2/aruco.hpp>
#include <opencv2/imgproc.hpp>

namespace glasspiv {
namespace {

// Under the sanitizers the photos get one sample per pixel instead of 3 x 3
// (tests/sanitized_build.h) and the accuracy limits are five times wider.
constexpr int kPhotoSamples = kSanitizedBuild ? 1 : 3;
constexpr double kLimitScale = kSanitizedBuild ? 5 : 1;

struct PoseError {
  double position_mm = 0, rotation_deg = 0;
};

PoseError pose_error(const RigidTransform& fitted, const RigidTransform& truth) {
  const Eigen::Vector3d c_fit = fitted.inverse().translation_mm, c_true = truth.inverse().translation_mm;
  const Eigen::AngleAxisd d(fitted.rotation * truth.rotation.transpose());
  return {(c_fit - c_true).norm(), std::abs(d.angle()) * 180 / M_PI};
}

struct MarkerPhoto {
  PreparedScene ps;
  std::vector<SceneFiducial> fiducials;
  std::unique_ptr<SceneIndex> index;
  cv::Mat photo;
};

// The photo of the scene file at `scene_path` from its camera "cam".
MarkerPhoto photograph(const std::string& scene_path, std::uint32_t seed = 1) {
  MarkerPhoto s;
  s.ps = prepare_scene(scene_path, "cam");
  s.fiducials = scene_fiducials(s.ps.scene);
  s.index = make_scene_index(s.ps.trace);
  SetupLook look;
  look.background_radiance = 0.35;
  look.textures = s.ps.textures_by_solid();
  const CameraModel& model = s.ps.camera().model;
  const std::vector<float> radiance =
      render_setup(s.ps.trace, look, model, *s.ps.camera().camera_from_world, TraceOptions{}, kPhotoSamples, 0);
  PhotoLook photo;
  photo.seed = seed;
  s.photo = photo_from_radiance(radiance, model.width_px(), model.height_px(), photo);
  return s;
}

MarkerPhoto make_setup(const std::string& folder, const MarkerSetupOptions& options) {
  return photograph(write_marker_setup(folder, options));
}

std::vector<int> rectangle_solids(const MarkerPhoto& s) { return s.ps.info.rectangle_solids; }

TEST(AlignPose, MarkersInTheOpenGiveThePoseWithinFiftyMicrons) {
  TempDir dir("align_pose");
  const MarkerPhoto s = make_setup(dir.file("setup"), {});
  const FiducialsInPhoto found = detect_fiducials(s.photo, s.fiducials, "photo");
  ASSERT_EQ(found.corners.size(), 80u);  // 20 markers x 4 corners
  EXPECT_TRUE(found.unknown_markers.empty());
  const AlignedPose pose =
      align_pose(s.ps.trace, *s.index, rectangle_solids(s), s.fiducials, s.ps.camera().model, found.corners);
  const PoseError e = pose_error(pose.fit.camera_from_world, *s.ps.camera().camera_from_world);
  std::printf("markers in the open: position error %.4f mm, rotation %.5f deg, RMS %.3f px, sigma %.4f mm\n",
              e.position_mm, e.rotation_deg, pose.fit.rms_px, pose.fit.position_sigma_mm.norm());
  EXPECT_LT(e.position_mm, 0.05 * kLimitScale);
  EXPECT_LT(e.rotation_deg, 0.01 * kLimitScale);
  // Nothing displaces the markers: the traced fit is the pinhole fit.
  EXPECT_LT(pose.glass_displacement_px, 1e-6);
  EXPECT_EQ(pose.fiducials.size(), 20u);
  // The reported uncertainty explains the error (4 sigma).
  EXPECT_LT(e.position_mm, 4 * pose.fit.position_sigma_mm.norm() + 1e-3);
}

TEST(AlignPose, BehindAWindowTheTracedPoseIsTenTimesBetterThanThePinhole) {
  TempDir dir("align_pose");
  MarkerSetupOptions options;
  options.window_thickness_mm = 10;
  const MarkerPhoto s = make_setup(dir.file("setup"), options);
  const FiducialsInPhoto found = detect_fiducials(s.photo, s.fiducials, "photo");
  ASSERT_EQ(found.corners.size(), 80u);
  const AlignedPose pose =
      align_pose(s.ps.trace, *s.index, rectangle_solids(s), s.fiducials, s.ps.camera().model, found.corners);
  const RigidTransform& truth = *s.ps.camera().camera_from_world;
  const PoseError traced = pose_error(pose.fit.camera_from_world, truth);
  const PoseError pinhole = pose_error(pose.pinhole.camera_from_world, truth);
  std::printf("behind a 10 mm window: traced %.4f mm %.5f deg (RMS %.3f px), pinhole %.4f mm %.5f deg "
              "(RMS %.3f px); glass displaces corners by up to %.2f px\n",
              traced.position_mm, traced.rotation_deg, pose.fit.rms_px, pinhole.position_mm, pinhole.rotation_deg,
              pose.pinhole.rms_px, pose.glass_displacement_px);
  EXPECT_LT(traced.position_mm, 0.05 * kLimitScale);
  EXPECT_LT(traced.rotation_deg, 0.01 * kLimitScale);
  EXPECT_LE(traced.position_mm, pinhole.position_mm / 10);
  EXPECT_GT(pose.glass_displacement_px, 1.0);
}

TEST(AlignPose, TooFewCornersAndASingleSmallMarkerAreRefused) {
  TempDir dir("align_pose");
  const MarkerPhoto s = make_setup(dir.file("setup"), {});
  const FiducialsInPhoto found = detect_fiducials(s.photo, s.fiducials, "photo");
  const std::vector<FiducialCorner> three(found.corners.begin(), found.corners.begin() + 3);
  try {
    align_pose(s.ps.trace, *s.index, rectangle_solids(s), s.fiducials, s.ps.camera().model, three);
    FAIL() << "a pose from three corners was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "fiducials");
  }
  // One 40 px marker: its mirrored tilt fits almost as well (the flip a
  // planar target allows; under one sample per pixel the fit once picked it,
  // 269 mm off with a 1-sigma of 4.5 mm): refused with both figures, never a
  // silently flipped pose.
  const std::vector<FiducialCorner> one(found.corners.begin(), found.corners.begin() + 4);
  try {
    const AlignedPose pose =
        align_pose(s.ps.trace, *s.index, rectangle_solids(s), s.fiducials, s.ps.camera().model, one);
    FAIL() << "a pose from one small marker was accepted, mirrored pose RMS " << pose.fit.mirrored_pose_rms_px;
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "fiducials");
    EXPECT_NE(std::string(e.what()).find("mirrored"), std::string::npos) << e.what();
    std::printf("one marker: %s\n", e.what());
  }
  // The ten markers of the front ring are coplanar too, but spread over the
  // image: the mirrored start falls back into the fitted pose (no second
  // minimum, reported as 0) or fits far worse, and the pose stands.
  std::vector<FiducialCorner> front;
  for (const FiducialCorner& c : found.corners)
    if (std::abs(c.world_mm.z()) < 1e-9) front.push_back(c);
  const AlignedPose pose =
      align_pose(s.ps.trace, *s.index, rectangle_solids(s), s.fiducials, s.ps.camera().model, front);
  const PoseError e = pose_error(pose.fit.camera_from_world, *s.ps.camera().camera_from_world);
  std::printf("front ring only (%zu corners): error %.4f mm, mirrored pose RMS %.1f px vs %.3f px\n", front.size(),
              e.position_mm, pose.pinhole.mirrored_pose_rms_px, pose.pinhole.rms_px);
  EXPECT_TRUE(pose.pinhole.mirrored_pose_rms_px == 0 || pose.pinhole.mirrored_pose_rms_px > 10 * pose.pinhole.rms_px);
  EXPECT_LT(e.position_mm, 4 * pose.fit.position_sigma_mm.norm() + 0.01);
}

TEST(AlignPose, DuplicatedAndUnknownIdsAreReportedAndNotUsed) {
  TempDir dir("align_pose");
  const MarkerPhoto s = make_setup(dir.file("setup"), {});
  cv::Mat photo = s.photo.clone();
  const FiducialsInPhoto clean = detect_fiducials(photo, s.fiducials, "photo");
  // Marker 0's bounding box, copied to the image centre (the frame leaves it empty).
  std::vector<cv::Point2f> c0;
  for (const FiducialCorner& c : clean.corners)
    if (c.fiducial == 0) c0.emplace_back(static_cast<float>(c.pixel_px.x()), static_cast<float>(c.pixel_px.y()));
  ASSERT_EQ(c0.size(), 4u);
  cv::Rect box = cv::boundingRect(c0);
  box.x -= 12, box.y -= 12, box.width += 24, box.height += 24;
  photo(box).copyTo(photo(cv::Rect(photo.cols / 2 - box.width / 2, photo.rows / 2 - box.height / 2, box.width, box.height)));
  // An id the scene does not carry, drawn white-framed below the centre.
  cv::Mat stranger;
  cv::aruco::drawMarker(cv::aruco::getPredefinedDictionary(cv::aruco::DICT_4X4_50), 33, 48, stranger);
  cv::Mat framed(72, 72, CV_8UC1, cv::Scalar(235));
  stranger.copyTo(framed(cv::Rect(12, 12, 48, 48)));
  framed.copyTo(photo(cv::Rect(photo.cols / 2 - 36, photo.rows / 2 + 80, 72, 72)));

  const FiducialsInPhoto found = detect_fiducials(photo, s.fiducials, "photo");
  ASSERT_EQ(found.duplicated_markers.size(), 1u);
  EXPECT_EQ(found.duplicated_markers[0], "DICT_4X4_50 id 0");
  ASSERT_EQ(found.unknown_markers.size(), 1u);
  EXPECT_EQ(found.unknown_markers[0], "DICT_4X4_50 id 33");
  EXPECT_EQ(found.corners_per_fiducial[0], 0);
  EXPECT_EQ(found.corners.size(), 76u);
  const AlignedPose pose =
      align_pose(s.ps.trace, *s.index, rectangle_solids(s), s.fiducials, s.ps.camera().model, found.corners);
  const PoseError e = pose_error(pose.fit.camera_from_world, *s.ps.camera().camera_from_world);
  EXPECT_LT(e.position_mm, 0.05 * kLimitScale);
  EXPECT_LT(e.rotation_deg, 0.01 * kLimitScale);
}

// Corners on one line (the top edges of the markers of one side of the frame)
// cannot give a pose: refused as collinear.
TEST(AlignPose, CornersOnOneLineAreRefused) {
  TempDir dir("align_pose");
  const MarkerPhoto s = make_setup(dir.file("setup"), {});
  const FiducialsInPhoto found = detect_fiducials(s.photo, s.fiducials, "photo");
  // The first ring's top side: markers at y = 75 mm, z = 0; corners 0 and 1 lie at y = 75 + 4 mm.
  std::vector<FiducialCorner> line;
  for (const FiducialCorner& c : found.corners)
    if (c.corner_id <= 1 && std::abs(c.world_mm.y() - 79) < 0.1 && std::abs(c.world_mm.z()) < 1e-9) line.push_back(c);
  ASSERT_GE(line.size(), 4u);
  try {
    align_pose(s.ps.trace, *s.index, rectangle_solids(s), s.fiducials, s.ps.camera().model, line);
    FAIL() << "a pose from collinear corners was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "fiducials");
    EXPECT_NE(std::string(e.what()).find("collinear"), std::string::npos) << e.what();
  }
}

// A marker turned almost edge-on (87.5 degrees): it is not decoded or its
// corners are dropped as outliers; the pose from the others stays right.
TEST(AlignPose, AMarkerSeenEdgeOnDoesNotSpoilThePose) {
  TempDir dir("align_pose");
  const std::string scene = write_marker_setup(dir.file("setup"), {});
  std::string text = read_file(scene);
  const std::size_t at = text.find("normal: [0, 0, -1]");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, std::string("normal: [0, 0, -1]").size(), "normal: [0.99905, 0, -0.0436]");
  write_file_atomically(scene, text);
  const MarkerPhoto s = photograph(scene);
  const CameraModel& model = s.ps.camera().model;
  const FiducialsInPhoto found = detect_fiducials(s.photo, s.fiducials, "photo");
  std::printf("edge-on marker: %d corners found on it\n", found.corners_per_fiducial[0]);
  const AlignedPose pose =
      align_pose(s.ps.trace, *s.index, rectangle_solids(s), s.fiducials, model, found.corners);
  const PoseError e = pose_error(pose.fit.camera_from_world, *s.ps.camera().camera_from_world);
  EXPECT_LT(e.position_mm, 0.05 * kLimitScale);
  EXPECT_LT(e.rotation_deg, 0.01 * kLimitScale);
}

TEST(AlignPose, APhotoWithoutMarkersFindsNone) {
  TempDir dir("align_pose");
  const MarkerPhoto s = make_setup(dir.file("setup"), {});
  const cv::Mat blank(s.photo.size(), CV_8UC1, cv::Scalar(90));
  const FiducialsInPhoto found = detect_fiducials(blank, s.fiducials, "blank");
  EXPECT_TRUE(found.corners.empty());
}

}  // namespace
}  // namespace glasspiv
