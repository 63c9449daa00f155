#pragma once
// Reprojection residuals with the intrinsics held constant, as Ceres cost
// functors (the shape of calib/fit/reprojection_cost.h: the functor holds the
// observation and the constants, operator() is templated, Create() wraps it for
// autodiff). One functor per set of free blocks:
//
//   PoseReprojectionCost        camera_from_world (6)
//   PoseFocalReprojectionCost   camera_from_world (6), focal scale (1)
//   RigReprojectionCost         camera_from_world (6), world_from_fiducial (6)
//
//   residual = project_point(intrinsics, camera_from_world * point) - observed   [px]
//
// A pose block is the angle-axis rotation (rad, ceres/rotation.h) then the
// translation (mm): p_destination = R(rvec) p_source + t. The intrinsics are the
// 4 + 14 block of CameraModel::intrinsics() with the model's distortion count.
//
// Only calib/fit/pose_cost.cpp instantiates the Jets: Create() is defined there.
#include <array>

#include <Eigen/Core>
#include <ceres/rotation.h>

#include "calib/camera_model.h"
#include "calib/distortion.h"

namespace ceres {
class CostFunction;
}

namespace glasspiv {

// The point moved by a pose block: out = R(pose[0..2]) in + pose[3..5].
template <typename T>
void apply_pose_block(const T* pose, const T* in, T* out) {
  ceres::AngleAxisRotatePoint(pose, in, out);
  for (int i = 0; i < 3; ++i) out[i] += pose[3 + i];
}

// The intrinsics as the functors store them.
struct ConstantIntrinsics {
  explicit ConstantIntrinsics(const CameraModel& camera)
      : values(camera.intrinsics()), distortion_count(camera.distortion_count()) {}
  std::array<double, 4 + kMaxDistortionCoefficients> values;
  int distortion_count;

  // The pixel of a camera-frame point with fx, fy multiplied by focal_scale;
  // false if the point is not in front of the camera.
  template <typename T>
  bool project(const T* point_camera, const T& focal_scale, T* pixel) const {
    T all[4 + kMaxDistortionCoefficients];
    for (int i = 0; i < 4 + kMaxDistortionCoefficients; ++i) all[i] = T(values[i]);
    all[0] *= focal_scale;
    all[1] *= focal_scale;
    return project_point(all, distortion_count, point_camera, pixel);
  }
};

class PoseReprojectionCost {
 public:
  PoseReprojectionCost(const CameraModel& camera, const Eigen::Vector2d& observed_px,
                       const Eigen::Vector3d& point_world_mm)
      : intrinsics_(camera), observed_px_(observed_px), point_world_mm_(point_world_mm) {}

  template <typename T>
  bool operator()(const T* camera_from_world, T* residual) const {
    const T world[3] = {T(point_world_mm_.x()), T(point_world_mm_.y()), T(point_world_mm_.z())};
    T point[3], pixel[2];
    apply_pose_block(camera_from_world, world, point);
    if (!intrinsics_.project(point, T(1), pixel)) return false;  // behind the camera
    residual[0] = pixel[0] - T(observed_px_.x());
    residual[1] = pixel[1] - T(observed_px_.y());
    return true;
  }

  static ceres::CostFunction* Create(const CameraModel& camera, const Eigen::Vector2d& observed_px,
                                     const Eigen::Vector3d& point_world_mm);

 private:
  ConstantIntrinsics intrinsics_;
  Eigen::Vector2d observed_px_;
  Eigen::Vector3d point_world_mm_;
};

// "Focal length free": fx and fy multiplied by one scale f (the aspect ratio,
// principal point and distortion kept).
class PoseFocalReprojectionCost {
 public:
  PoseFocalReprojectionCost(const CameraModel& camera, const Eigen::Vector2d& observed_px,
                            const Eigen::Vector3d& point_world_mm)
      : intrinsics_(camera), observed_px_(observed_px), point_world_mm_(point_world_mm) {}

  template <typename T>
  bool operator()(const T* camera_from_world, const T* focal_scale, T* residual) const {
    const T world[3] = {T(point_world_mm_.x()), T(point_world_mm_.y()), T(point_world_mm_.z())};
    T point[3], pixel[2];
    apply_pose_block(camera_from_world, world, point);
    if (!intrinsics_.project(point, focal_scale[0], pixel)) return false;
    residual[0] = pixel[0] - T(observed_px_.x());
    residual[1] = pixel[1] - T(observed_px_.y());
    return true;
  }

  static ceres::CostFunction* Create(const CameraModel& camera, const Eigen::Vector2d& observed_px,
                                     const Eigen::Vector3d& point_world_mm);

 private:
  ConstantIntrinsics intrinsics_;
  Eigen::Vector2d observed_px_;
  Eigen::Vector3d point_world_mm_;
};

// A point known in a fiducial's frame, fiducial and camera both posed in the
// world: p_camera = camera_from_world * (world_from_fiducial * p_fiducial).
class RigReprojectionCost {
 public:
  RigReprojectionCost(const CameraModel& camera, const Eigen::Vector2d& observed_px,
                      const Eigen::Vector3d& point_fiducial_mm)
      : intrinsics_(camera), observed_px_(observed_px), point_fiducial_mm_(point_fiducial_mm) {}

  template <typename T>
  bool operator()(const T* camera_from_world, const T* world_from_fiducial, T* residual) const {
    const T fiducial[3] = {T(point_fiducial_mm_.x()), T(point_fiducial_mm_.y()), T(point_fiducial_mm_.z())};
    T world[3], point[3], pixel[2];
    apply_pose_block(world_from_fiducial, fiducial, world);
    apply_pose_block(camera_from_world, world, point);
    if (!intrinsics_.project(point, T(1), pixel)) return false;
    residual[0] = pixel[0] - T(observed_px_.x());
    residual[1] = pixel[1] - T(observed_px_.y());
    return true;
  }

  static ceres::CostFunction* Create(const CameraModel& camera, const Eigen::Vector2d& observed_px,
                                     const Eigen::Vector3d& point_fiducial_mm);

 private:
  ConstantIntrinsics intrinsics_;
  Eigen::Vector2d observed_px_;
  Eigen::Vector3d point_fiducial_mm_;
};

}  // namespace glasspiv
