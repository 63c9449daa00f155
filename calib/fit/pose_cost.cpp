#include "calib/fit/pose_cost.h"

#include <ceres/autodiff_cost_function.h>

#include "calib/fit/reprojection_cost.h"

namespace glasspiv {

ceres::CostFunction* PoseReprojectionCost::Create(const CameraModel& camera, const Eigen::Vector2d& observed_px,
                                                  const Eigen::Vector3d& point_world_mm) {
  return new ceres::AutoDiffCostFunction<PoseReprojectionCost, 2, kPoseParameterCount>(
      new PoseReprojectionCost(camera, observed_px, point_world_mm));
}

ceres::CostFunction* PoseFocalReprojectionCost::Create(const CameraModel& camera, const Eigen::Vector2d& observed_px,
                                                       const Eigen::Vector3d& point_world_mm) {
  return new ceres::AutoDiffCostFunction<PoseFocalReprojectionCost, 2, kPoseParameterCount, 1>(
      new PoseFocalReprojectionCost(camera, observed_px, point_world_mm));
}

ceres::CostFunction* RigReprojectionCost::Create(const CameraModel& camera, const Eigen::Vector2d& observed_px,
                                                 const Eigen::Vector3d& point_fiducial_mm) {
  return new ceres::AutoDiffCostFunction<RigReprojectionCost, 2, kPoseParameterCount, kPoseParameterCount>(
      new RigReprojectionCost(camera, observed_px, point_fiducial_mm));
}

}  // namespace glasspiv
