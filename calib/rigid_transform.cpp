#include "calib/rigid_transform.h"

#include <algorithm>
#include <cmath>

namespace glasspiv {

RigidTransform RigidTransform::from_rvec_tvec(const Eigen::Vector3d& rvec, const Eigen::Vector3d& tvec_mm) {
  RigidTransform t;
  const double angle = rvec.norm();
  t.rotation = angle > 0 ? Eigen::AngleAxisd(angle, rvec / angle).toRotationMatrix() : Eigen::Matrix3d::Identity();
  t.translation_mm = tvec_mm;
  return t;
}

Eigen::Vector3d RigidTransform::rvec() const {
  const Eigen::AngleAxisd aa(rotation);
  return aa.axis() * aa.angle();
}

RigidTransform RigidTransform::inverse() const {
  RigidTransform t;
  t.rotation = rotation.transpose();
  t.translation_mm = -(t.rotation * translation_mm);
  return t;
}

RigidTransform RigidTransform::operator*(const RigidTransform& other) const {
  RigidTransform t;
  t.rotation = rotation * other.rotation;
  t.translation_mm = rotation * other.translation_mm + translation_mm;
  return t;
}

Eigen::Matrix3d rotation_from_euler_zyx(double rx, double ry, double rz) {
  return (Eigen::AngleAxisd(rz, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(ry, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rx, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Vector3d euler_zyx_from_rotation(const Eigen::Matrix3d& r) {
  // R = Rz Ry Rx gives r20 = -sin(ry), (r00, r10) = cos(ry) (cos(rz), sin(rz)).
  // atan2 with the hypot keeps ry exact near +-pi/2, where asin(-r20) is
  // ill-conditioned; rx then follows from Rx = (Rz Ry)^T R, so the rebuilt
  // rotation is exact even at gimbal lock (where rz is set to 0).
  const double c = std::hypot(r(0, 0), r(1, 0));
  const double ry = std::atan2(-r(2, 0), c);
  const double rz = c > 0 ? std::atan2(r(1, 0), r(0, 0)) : 0.0;
  const Eigen::Matrix3d rx_matrix = (Eigen::AngleAxisd(rz, Eigen::Vector3d::UnitZ()) *
                                     Eigen::AngleAxisd(ry, Eigen::Vector3d::UnitY()))
                                        .toRotationMatrix()
                                        .transpose() *
                                    r;
  return {std::atan2(rx_matrix(2, 1), rx_matrix(1, 1)), ry, rz};
}

}  // namespace glasspiv
