#pragma once
// The reprojection residual of one observed board corner, as a Ceres cost
// functor (the COLMAP / Ceres-example shape: the functor holds only the
// observation, operator() is templated, Create() wraps it for autodiff).
//
//   residual = project_point(intrinsics, R(rvec) * board_point + t) - observed pixel   [px]
//
// Parameter blocks:
//   intrinsics        fx, fy, cx, cy, then the model's DistortionCount coefficients
//                     in OpenCV order (4 + DistortionCount values; the functor pads
//                     the rest of project_point's 4 + 14 block with zeros, so the
//                     Jets carry only the derivatives the model has);
//   camera_from_board 6 values: the angle-axis rotation (rad, ceres/rotation.h)
//                     then the translation (mm), p_camera = R p_board + t.
//
// Fixing the aspect ratio (OpenCV's CALIB_FIX_ASPECT_RATIO) is a parameterisation
// inside the functor: with aspect_ratio > 0 it uses fy = aspect_ratio * fx and
// ignores the fy slot of the block (which the fit then holds constant).
//
// Only calib/fit/reprojection_cost.cpp instantiates the Jets (autodiff is slow to
// compile): other files use create_reprojection_cost() and
// project_with_intrinsics_jacobian().
#include <Eigen/Core>
#include <ceres/autodiff_cost_function.h>
#include <ceres/rotation.h>

#include "calib/camera_model.h"
#include "calib/distortion.h"

namespace glasspiv {

constexpr int kPoseParameterCount = 6;  // angle-axis (3) + translation (3)

template <int DistortionCount>
class ReprojectionCost {
 public:
  static constexpr int kIntrinsicCount = 4 + DistortionCount;

  ReprojectionCost(const Eigen::Vector2d& observed_px, const Eigen::Vector3d& board_point_mm, double aspect_ratio)
      : observed_px_(observed_px), board_point_mm_(board_point_mm), aspect_ratio_(aspect_ratio) {}

  template <typename T>
  bool operator()(const T* intrinsics, const T* camera_from_board, T* residual) const {
    const T board[3] = {T(board_point_mm_.x()), T(board_point_mm_.y()), T(board_point_mm_.z())};
    T point[3];
    ceres::AngleAxisRotatePoint(camera_from_board, board, point);
    for (int i = 0; i < 3; ++i) point[i] += camera_from_board[3 + i];

    T all[4 + kMaxDistortionCoefficients];
    for (int i = 0; i < kIntrinsicCount; ++i) all[i] = intrinsics[i];
    for (int i = kIntrinsicCount; i < 4 + kMaxDistortionCoefficients; ++i) all[i] = T(0);
    if (aspect_ratio_ > 0) all[1] = T(aspect_ratio_) * intrinsics[0];

    T pixel[2];
    if (!project_point(all, DistortionCount, point, pixel)) return false;  // behind the camera
    residual[0] = pixel[0] - T(observed_px_.x());
    residual[1] = pixel[1] - T(observed_px_.y());
    return true;
  }

  static ceres::CostFunction* Create(const Eigen::Vector2d& observed_px, const Eigen::Vector3d& board_point_mm,
                                     double aspect_ratio = 0) {
    return new ceres::AutoDiffCostFunction<ReprojectionCost, 2, kIntrinsicCount, kPoseParameterCount>(
        new ReprojectionCost(observed_px, board_point_mm, aspect_ratio));
  }

 private:
  Eigen::Vector2d observed_px_;
  Eigen::Vector3d board_point_mm_;
  double aspect_ratio_;  // fy / fx when tied, 0 when fy is free
};

// ReprojectionCost<distortion count of `lens_model`>::Create (the caller owns it,
// or hands it to a ceres::Problem).
ceres::CostFunction* create_reprojection_cost(LensModel lens_model, const Eigen::Vector2d& observed_px,
                                              const Eigen::Vector3d& board_point_mm, double aspect_ratio = 0);

// The pixel of a camera-frame point and its derivative with respect to the
// intrinsics block (2 x (4 + distortion count), the functor's first block), with
// the same aspect-ratio tie, and (if asked) with respect to the point. Returns
// false if the point is not in front of the camera. `intrinsics` holds 4 +
// distortion count values.
bool project_with_intrinsics_jacobian(LensModel lens_model, const double* intrinsics, double aspect_ratio,
                                      const Eigen::Vector3d& point_camera, Eigen::Vector2d* pixel,
                                      Eigen::MatrixXd* d_pixel_d_intrinsics,
                                      Eigen::Matrix<double, 2, 3>* d_pixel_d_point = nullptr);

}  // namespace glasspiv
