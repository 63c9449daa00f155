// The pose cost functors (calib/fit/pose_cost.h) against central differences,
// on an OpenCV5 and a tilted OpenCV14 lens; and their residuals against
// CameraModel::project. (Not ceres::GradientChecker: Debian's Ceres and this
// build disagree on the layout of its ProbeResults, which AddressSanitizer
// reports as a heap overflow in its destructor.)
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include <algorithm>
#include <cmath>

#include <ceres/cost_function.h>

#include "calib/fit/pose_cost.h"
#include "calib/rigid_transform.h"
#include "truth_cameras.h"

namespace glasspiv {
namespace {

CameraModel tilted_opencv14() {
  return CameraModel(2048, 1536, 2400, 2401.5, 1030.25, 760.75,
                     {-0.2, 0.1, 1e-4, -1.2e-4, -0.02, 0.01, -0.005, 0.002, 1e-4, -2e-5, 3e-5, 1e-5, 0.01, -0.02});
}

// Every Jacobian entry agrees with central differences to this fraction of its
// block's largest entry. Steps of 1e-6 relative: truncation ~1e-12 relative,
// round-off ~1e-16 x 1e3 px / 1e-6 = 1e-7 px against entries of ~1e3 px per unit.
constexpr double kRelativePrecision = 1e-6;

void expect_gradients(ceres::CostFunction* raw, const std::vector<const double*>& parameters) {
  const std::unique_ptr<ceres::CostFunction> cost(raw);
  const int residuals = cost->num_residuals();
  const std::vector<int32_t>& sizes = cost->parameter_block_sizes();
  ASSERT_EQ(sizes.size(), parameters.size());
  std::vector<std::vector<double>> jacobian_storage(sizes.size());
  std::vector<double*> jacobians(sizes.size());
  for (std::size_t b = 0; b < sizes.size(); ++b) {
    jacobian_storage[b].assign(static_cast<std::size_t>(residuals * sizes[b]), 0.0);
    jacobians[b] = jacobian_storage[b].data();
  }
  std::vector<double> r(static_cast<std::size_t>(residuals)), plus(r), minus(r);
  ASSERT_TRUE(cost->Evaluate(parameters.data(), r.data(), jacobians.data()));
  std::vector<std::vector<double>> values;
  for (std::size_t b = 0; b < sizes.size(); ++b) values.emplace_back(parameters[b], parameters[b] + sizes[b]);
  std::vector<const double*> moved;
  for (const auto& v : values) moved.push_back(v.data());
  for (std::size_t b = 0; b < sizes.size(); ++b) {
    double largest = 0;
    for (double v : jacobian_storage[b]) largest = std::max(largest, std::abs(v));
    ASSERT_GT(largest, 0) << "block " << b << " has a zero Jacobian";
    for (int j = 0; j < sizes[b]; ++j) {
      const double x = values[b][static_cast<std::size_t>(j)], h = 1e-6 * std::max(1.0, std::abs(x));
      values[b][static_cast<std::size_t>(j)] = x + h;
      ASSERT_TRUE(cost->Evaluate(moved.data(), plus.data(), nullptr));
      values[b][static_cast<std::size_t>(j)] = x - h;
      ASSERT_TRUE(cost->Evaluate(moved.data(), minus.data(), nullptr));
      values[b][static_cast<std::size_t>(j)] = x;
      for (int i = 0; i < residuals; ++i) {
        const double numeric = (plus[static_cast<std::size_t>(i)] - minus[static_cast<std::size_t>(i)]) / (2 * h);
        EXPECT_NEAR(jacobian_storage[b][static_cast<std::size_t>(i * sizes[b] + j)], numeric,
                    kRelativePrecision * largest)
            << "block " << b << ", parameter " << j << ", residual " << i;
      }
    }
  }
}

class PoseCost : public ::testing::TestWithParam<int> {
 protected:
  CameraModel camera() const { return GetParam() == 0 ? testing::truth_opencv5() : tilted_opencv14(); }
};

// camera_from_world: a general rotation, the points ~1.2 m ahead, off axis.
const double kCameraFromWorld[6] = {0.3, -0.5, 0.2, 40, -25, 1200};
const Eigen::Vector3d kPointWorldMm(150, -80, 60);
const Eigen::Vector2d kObservedPx(900.5, 640.25);

TEST_P(PoseCost, PoseGradient) {
  expect_gradients(PoseReprojectionCost::Create(camera(), kObservedPx, kPointWorldMm), {kCameraFromWorld});
}

TEST_P(PoseCost, PoseFocalGradient) {
  const double focal_scale[1] = {1.013};
  expect_gradients(PoseFocalReprojectionCost::Create(camera(), kObservedPx, kPointWorldMm),
                   {kCameraFromWorld, focal_scale});
}

TEST_P(PoseCost, RigGradient) {
  const double world_from_fiducial[6] = {-0.1, 0.25, 0.6, 100, 20, -30};
  expect_gradients(RigReprojectionCost::Create(camera(), kObservedPx, Eigen::Vector3d(30, 40, 0)),
                   {kCameraFromWorld, world_from_fiducial});
}

// The residual is CameraModel::project of the moved point minus the observation.
TEST_P(PoseCost, ResidualIsTheModelsProjection) {
  const CameraModel cam = camera();
  const RigidTransform camera_from_world = RigidTransform::from_rvec_tvec(
      Eigen::Vector3d(kCameraFromWorld[0], kCameraFromWorld[1], kCameraFromWorld[2]),
      Eigen::Vector3d(kCameraFromWorld[3], kCameraFromWorld[4], kCameraFromWorld[5]));
  const Eigen::Vector2d expected = *cam.project(camera_from_world.apply(kPointWorldMm)) - kObservedPx;
  double residual[2];
  ASSERT_TRUE(PoseReprojectionCost(cam, kObservedPx, kPointWorldMm)(kCameraFromWorld, residual));
  EXPECT_NEAR(residual[0], expected.x(), 1e-9);
  EXPECT_NEAR(residual[1], expected.y(), 1e-9);

  // The focal scale multiplies fx and fy: at 1 the same residual.
  const double one[1] = {1.0};
  double focal_residual[2];
  ASSERT_TRUE(PoseFocalReprojectionCost(cam, kObservedPx, kPointWorldMm)(kCameraFromWorld, one, focal_residual));
  EXPECT_EQ(focal_residual[0], residual[0]);
  EXPECT_EQ(focal_residual[1], residual[1]);

  // The rig functor with the identity world_from_fiducial is the pose functor.
  const double identity[6] = {0, 0, 0, 0, 0, 0};
  double rig_residual[2];
  ASSERT_TRUE(RigReprojectionCost(cam, kObservedPx, kPointWorldMm)(kCameraFromWorld, identity, rig_residual));
  EXPECT_NEAR(rig_residual[0], residual[0], 1e-9);
  EXPECT_NEAR(rig_residual[1], residual[1], 1e-9);
}

TEST_P(PoseCost, BehindTheCameraHasNoResidual) {
  const double behind[6] = {0, 0, 0, 0, 0, -1200};
  double residual[2];
  EXPECT_FALSE(PoseReprojectionCost(camera(), kObservedPx, kPointWorldMm)(behind, residual));
}

INSTANTIATE_TEST_SUITE_P(Lenses, PoseCost, ::testing::Values(0, 1),
                         [](const auto& info) { return info.param == 0 ? "opencv5" : "opencv14"; });

}  // namespace
}  // namespace glasspiv
