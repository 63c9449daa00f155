// Synthetic target photos: the board lands where the camera model says it does.
#include "sim/target_photo.h"

#include <cstdio>

#include <gtest/gtest.h>

#include "sim/calibration_views.h"
#include "targets/target_detect.h"

namespace glasspiv {
namespace {

TargetSpec charuco_board() {
  TargetSpec spec;
  spec.kind = TargetKind::charuco;
  spec.squares_x = 11;
  spec.squares_y = 8;
  spec.square_size_mm = 15;
  spec.marker_size_mm = 11;
  spec.dictionary = "DICT_5X5_100";
  return spec;
}

// The detected corners of a rendered photo match the projections of the true
// board corners: an unbiased renderer and detector give a mean error (bias)
// well under 0.05 px; 0.1 px RMS allows for the detector's own noise on a clean,
// noise-free 8-bit image with distortion.
TEST(TargetPhoto, DetectedCornersMatchTheProjectedTruth) {
  const CameraModel camera(1280, 1024, 1400, 1400, 645.3, 508.9, {-0.18, 0.09, 2e-4, -1e-4, -0.01});
  const TargetSpec spec = charuco_board();
  const TargetRender board = render_target(spec, 12.0, default_margin_mm(spec));
  const auto poses = calibration_view_poses(camera, {165, 120}, 4, 350, 450, 30, 7);
  SensorOptions sensor;
  sensor.read_noise = 0;
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  double sum_sq = 0;
  int n = 0;
  for (std::size_t v = 0; v < poses.size(); ++v) {
    const cv::Mat photo = render_target_photo(camera, poses[v], board, sensor);
    const ViewObservations seen = detect_target(photo, spec, "view" + std::to_string(v));
    ASSERT_GT(seen.corners.size(), 30u) << "view " << v;
    for (const CornerObservation& c : seen.corners) {
      const auto truth = camera.project(poses[v].apply(c.board_point_mm));
      ASSERT_TRUE(truth.has_value());
      const Eigen::Vector2d error = c.pixel_px - *truth;
      sum += error;
      sum_sq += error.squaredNorm();
      ++n;
    }
  }
  const Eigen::Vector2d bias = sum / n;
  const double rms = std::sqrt(sum_sq / n);
  std::printf("detection vs truth over %d corners: bias (%.4f, %.4f) px, RMS %.4f px\n", n, bias.x(), bias.y(), rms);
  EXPECT_LT(bias.norm(), 0.05) << "bias (" << bias.transpose() << ") px over " << n << " corners";
  EXPECT_LT(rms, 0.1) << "RMS px over " << n << " corners";
}

TEST(TargetPhoto, SameSeedSamePhotoOtherSeedOtherNoise) {
  const CameraModel camera(320, 240, 400, 400, 159.5, 119.5);
  const TargetSpec spec = charuco_board();
  const TargetRender board = render_target(spec, 4.0, default_margin_mm(spec));
  const RigidTransform pose = RigidTransform::from_rvec_tvec({0.1, -0.2, 0}, {-80, -60, 400});
  SensorOptions a, b;
  b.seed = 2;
  const cv::Mat p1 = render_target_photo(camera, pose, board, a);
  const cv::Mat p2 = render_target_photo(camera, pose, board, a);
  const cv::Mat p3 = render_target_photo(camera, pose, board, b);
  EXPECT_EQ(cv::norm(p1, p2, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(p1, p3, cv::NORM_INF), 0.0);
}

}  // namespace
}  // namespace glasspiv
