// Alignment by the picture on a synthetic photograph of a marker frame
// (sim/marker_setup.h, blurred, vignetted, noise 0.5 grey levels of 255): from
// a start off by 2 mm and 1 degree the refinement returns to the truth.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "align/align_refine.h"
#include "align/fiducial_detection.h"
#include "align/prepared_scene.h"
#include "render/setup_render.h"
#include "sim/marker_setup.h"
#include "sim/setup_photo.h"
#include "tests/sanitized_build.h"
#include "tests/temp_dir.h"

namespace glasspiv {
namespace {

// A marker setup and its photograph at the truth (3 x 3 samples per pixel, one
// under the sanitizers), through sim/setup_photo.h's blur, vignette and noise.
struct SetupPhoto {
  PreparedScene ps;
  SetupLook look;
  RigidTransform truth;
  cv::Mat photo8, photo;  // CV_8UC1, and CV_32FC1 in [0, 1]
};

SetupPhoto photograph(const std::string& folder, const MarkerSetupOptions& setup) {
  SetupPhoto s;
  s.ps = prepare_scene(write_marker_setup(folder, setup), "cam");
  s.look.background_radiance = s.ps.scene.background.radiance;
  s.look.textures = s.ps.textures_by_solid();
  const CameraModel& model = s.ps.camera().model;
  s.truth = *s.ps.camera().camera_from_world;
  const std::vector<float> radiance =
      render_setup(s.ps.trace, s.look, model, s.truth, TraceOptions{}, kSanitizedBuild ? 1 : 3, 0);
  s.photo8 = photo_from_radiance(radiance, model.width_px(), model.height_px(), PhotoLook{});
  s.photo8.convertTo(s.photo, CV_32F, 1.0 / 255);
  return s;
}

// 2 mm along a skew direction and 1 degree about another, in the camera frame.
RigidTransform start_offset() {
  return RigidTransform::from_rvec_tvec(Eigen::Vector3d(0.6, -0.7, 0.4).normalized() * (M_PI / 180),
                                        Eigen::Vector3d(1.2, 0.9, -1.3).normalized() * 2);
}

TEST(AlignRefine, AStartOffByTwoMillimetresAndOneDegreeReturnsToTheTruth) {
  // Some 700 renders: hours under the sanitizers; the next test runs the same code there.
  if (kSanitizedBuild) GTEST_SKIP() << "too slow under the sanitizers (tests/sanitized_build.h)";
  TempDir dir("align_refine");
  MarkerSetupOptions setup;
  setup.width_px = 640;
  setup.height_px = 512;
  setup.focal_px = 1250;
  setup.marker_size_mm = 12;  // 30 px
  const SetupPhoto s = photograph(dir.file("setup"), setup);
  const RigidTransform& truth = s.truth;
  const RefineResult r = refine_alignment(s.ps.trace, s.look, s.ps.camera().model, start_offset() * truth, s.photo);
  const Eigen::AngleAxisd d(r.camera_from_world.rotation * truth.rotation.transpose());
  const double position_mm = (r.camera_from_world.inverse().translation_mm - truth.inverse().translation_mm).norm();
  const double rotation_deg = std::abs(d.angle()) * 180 / M_PI;
  for (const RefineLevel& l : r.levels)
    std::printf("binning %d: gradient NCC %.4f -> %.4f, %d steps, %d renders, %.2f s\n", l.binning,
                l.gradient_ncc_before, l.gradient_ncc_after, l.iterations, l.renders, l.seconds);
  std::printf("refined: %.4f mm, %.5f deg from the truth (%d renders, %.1f s)\n", position_mm, rotation_deg,
              r.renders, r.seconds);
  // The rotation meets 0.01 degree; the position stays about 0.07 mm off along
  // the direction a lateral shift and a rotation trade (0.0076 degree is 0.066
  // mm at 500 mm): gradient NCC there equals the truth's to 1e-4, so the picture
  // of this narrow view cannot tell them apart. The pose from the markers
  // (align_pose_test) is 0.01 mm. Measured 0.071 mm, 0.0079 degree.
  EXPECT_LT(position_mm, 0.1);
  EXPECT_LT(rotation_deg, 0.01);
  EXPECT_GT(r.levels.back().gradient_ncc_after, r.levels.front().gradient_ncc_before);
  EXPECT_EQ(r.status, RefineStatus::improved);
  EXPECT_GT(r.score_end, r.score_start);
}

TEST(AlignRefine, WithTheFiducialCornersTheStartReturnsWithinFiftyMicrons) {
  TempDir dir("align_refine");
  MarkerSetupOptions setup;  // 1280 x 1024, 40 px markers, as in align_pose_test
  setup.window_thickness_mm = 10;  // the corners are seen through glass: traced projections
  const SetupPhoto s = photograph(dir.file("setup"), setup);
  const RigidTransform& truth = s.truth;
  const std::vector<SceneFiducial> fiducials = scene_fiducials(s.ps.scene);
  const std::vector<RefineCorner> corners =
      refine_corners(detect_fiducials(s.photo8, fiducials, "photo").corners, fiducials, s.ps.info.rectangle_solids);
  ASSERT_EQ(corners.size(), 80u);
  RefineOptions options;
  options.binning_levels = {16, 8, 4, 2};  // the corners pin the pose: full resolution adds little here
  if (kSanitizedBuild) options.binning_levels = {16};  // the same code on one coarse level
  const RefineResult r =
      refine_alignment(s.ps.trace, s.look, s.ps.camera().model, start_offset() * truth, s.photo, {}, options, corners);
  const Eigen::AngleAxisd d(r.camera_from_world.rotation * truth.rotation.transpose());
  const double position_mm = (r.camera_from_world.inverse().translation_mm - truth.inverse().translation_mm).norm();
  const double rotation_deg = std::abs(d.angle()) * 180 / M_PI;
  for (const RefineLevel& l : r.levels)
    std::printf("binning %d: gradient NCC %.4f -> %.4f, corners RMS %.3f px, %d renders, %.2f s\n", l.binning,
                l.gradient_ncc_before, l.gradient_ncc_after, l.corner_rms_px_after, l.renders, l.seconds);
  std::printf("refined with corners behind a 10 mm window: %.4f mm, %.5f deg from the truth (%.1f s)\n", position_mm,
              rotation_deg, r.seconds);
  EXPECT_LT(position_mm, kSanitizedBuild ? 0.5 : 0.05);
  EXPECT_LT(rotation_deg, kSanitizedBuild ? 0.05 : 0.01);
  EXPECT_EQ(r.levels.back().corners_lost, 0);
  EXPECT_EQ(r.status, RefineStatus::improved);
}

// A start that cannot be refined is reported, not returned as a pose: a camera
// turned away from the setup takes no step (its renders show nothing), and a
// start far off ends where the score is lower than at the start.
TEST(AlignRefine, AStartThatCannotBeRefinedIsReportedAsSuch) {
  TempDir dir("align_refine");
  MarkerSetupOptions setup;
  setup.width_px = 320;
  setup.height_px = 256;
  setup.focal_px = 625;
  setup.marker_size_mm = 12;
  const SetupPhoto s = photograph(dir.file("setup"), setup);
  RefineOptions options;
  options.binning_levels = {8, 4};
  options.max_iterations = 10;
  const RigidTransform away =
      RigidTransform::from_rvec_tvec(Eigen::Vector3d(0, M_PI, 0), Eigen::Vector3d::Zero()) * s.truth;
  const RefineResult r = refine_alignment(s.ps.trace, s.look, s.ps.camera().model, away, s.photo, {}, options);
  std::printf("turned away: %d successful steps, score %.4f -> %.4f\n", r.successful_steps, r.score_start,
              r.score_end);
  EXPECT_EQ(r.status, RefineStatus::no_step);
  EXPECT_EQ(r.score_start, 0);  // a render of nothing: no edges to correlate
  // A start 100 mm off across the view: the objective pulls it on to where the
  // score is lower (measured -0.0867 -> -0.0948), which is reported as worse.
  const RigidTransform far =
      RigidTransform::from_rvec_tvec(Eigen::Vector3d::Zero(), Eigen::Vector3d(100, 60, 0)) * s.truth;
  const RefineResult f = refine_alignment(s.ps.trace, s.look, s.ps.camera().model, far, s.photo, {}, options);
  std::printf("100 mm off: %d successful steps, score %.4f -> %.4f\n", f.successful_steps, f.score_start, f.score_end);
  EXPECT_EQ(f.status, RefineStatus::worse);
  EXPECT_LT(f.score_end, f.score_start);
}

}  // namespace
}  // namespace glasspiv
