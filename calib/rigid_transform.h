#pragma once
// A rigid transform named destination_from_source: p_dest = rotation * p_src + translation_mm.
// Rotation vectors (rvec) are axis-angle in radians, as in OpenCV and mrcal.
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace glasspiv {

struct RigidTransform {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation_mm = Eigen::Vector3d::Zero();

  static RigidTransform from_rvec_tvec(const Eigen::Vector3d& rvec, const Eigen::Vector3d& tvec_mm);
  // The axis-angle vector of `rotation` (|rvec| in [0, pi]).
  Eigen::Vector3d rvec() const;
  Eigen::Vector3d apply(const Eigen::Vector3d& p) const { return rotation * p + translation_mm; }
  RigidTransform inverse() const;
  // (this * other)(p) = this(other(p)): a_from_c = a_from_b * b_from_c.
  RigidTransform operator*(const RigidTransform& other) const;
};

// DaVis's Euler convention: R = Rz(rz) * Ry(ry) * Rx(rx), angles in radians.
Eigen::Matrix3d rotation_from_euler_zyx(double rx, double ry, double rz);
// The inverse, with ry in [-pi/2, pi/2].
Eigen::Vector3d euler_zyx_from_rotation(const Eigen::Matrix3d& rotation);

}  // namespace glasspiv
