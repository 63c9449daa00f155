#include "calib/fit/reprojection_cost.h"

#include <memory>

namespace glasspiv {

ceres::CostFunction* create_reprojection_cost(LensModel lens_model, const Eigen::Vector2d& observed_px,
                                              const Eigen::Vector3d& board_point_mm, double aspect_ratio) {
  switch (lens_model) {
    case LensModel::Pinhole:
      return ReprojectionCost<0>::Create(observed_px, board_point_mm, aspect_ratio);
    case LensModel::OpenCV4:
      return ReprojectionCost<4>::Create(observed_px, board_point_mm, aspect_ratio);
    case LensModel::OpenCV5:
      return ReprojectionCost<5>::Create(observed_px, board_point_mm, aspect_ratio);
    case LensModel::OpenCV8:
      return ReprojectionCost<8>::Create(observed_px, board_point_mm, aspect_ratio);
    case LensModel::OpenCV12:
      return ReprojectionCost<12>::Create(observed_px, board_point_mm, aspect_ratio);
    case LensModel::OpenCV14:
      return ReprojectionCost<14>::Create(observed_px, board_point_mm, aspect_ratio);
  }
  return nullptr;
}

bool project_with_intrinsics_jacobian(LensModel lens_model, const double* intrinsics, double aspect_ratio,
                                      const Eigen::Vector3d& point_camera, Eigen::Vector2d* pixel,
                                      Eigen::MatrixXd* d_pixel_d_intrinsics,
                                      Eigen::Matrix<double, 2, 3>* d_pixel_d_point) {
  // The functor at the identity pose with the point as "board point" and a zero
  // observation: its residual is the pixel, its first Jacobian block the
  // derivative; at the identity pose the translation's columns of the second
  // block are the derivative with respect to the point.
  const std::unique_ptr<ceres::CostFunction> cost(
      create_reprojection_cost(lens_model, Eigen::Vector2d::Zero(), point_camera, aspect_ratio));
  const int n = 4 + static_cast<int>(lens_model);
  const double identity_pose[kPoseParameterCount] = {0, 0, 0, 0, 0, 0};
  const double* parameters[2] = {intrinsics, identity_pose};
  Eigen::Matrix<double, 2, Eigen::Dynamic, Eigen::RowMajor> jacobian(2, n);
  Eigen::Matrix<double, 2, kPoseParameterCount, Eigen::RowMajor> pose_jacobian;
  double* jacobians[2] = {d_pixel_d_intrinsics ? jacobian.data() : nullptr,
                          d_pixel_d_point ? pose_jacobian.data() : nullptr};
  const bool any = d_pixel_d_intrinsics || d_pixel_d_point;
  double residual[2];
  if (!cost->Evaluate(parameters, residual, any ? jacobians : nullptr)) return false;
  *pixel = Eigen::Vector2d(residual[0], residual[1]);
  if (d_pixel_d_intrinsics) *d_pixel_d_intrinsics = jacobian;
  if (d_pixel_d_point) *d_pixel_d_point = pose_jacobian.rightCols<3>();
  return true;
}

}  // namespace glasspiv
