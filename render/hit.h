#pragma once
// A ray's hit on a solid's surface: the record every intersect() of
// render/shapes.h and render/triangle_mesh.h returns, and the error bound that
// places the next ray on the correct side of the surface.
#include <Eigen/Core>
#include <optional>

namespace glasspiv {

struct Hit {
  double t = 0;                                       // ray parameter (mm, d is unit)
  Eigen::Vector3d point = Eigen::Vector3d::Zero();    // on the surface (mm)
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // outward unit normal
  int shape_index = -1;                               // set by first_hit; -1 for a single shape
  double error_mm = 0;                                // bound on |point - exact surface point| along normal
  // The normal that refraction and reflection use where it differs from the
  // geometric one (smooth meshes: interpolated vertex normals, outward, unit);
  // empty for exact solids. The geometric normal alone decides entering/leaving.
  std::optional<Eigen::Vector3d> shading_normal;
  // d(normal)/d(point) along the surface (the shape operator; zero for planes):
  // ray differentials use it to carry footprints through curved interfaces.
  Eigen::Matrix3d dnormal_dpoint = Eigen::Matrix3d::Zero();
  // Where the shape operator is a multiple of the identity (an umbilic point:
  // every point of a sphere, I / r), that multiple in 1/mm; dnormal_dpoint is
  // then left zero: read the shape operator through dnormal().
  std::optional<double> umbilic_curvature_per_mm;

  // The normal's change for a change dpoint of the point along the surface
  // (each column one direction): the shape operator applied, as a scale where
  // it is one (the same values as the 3 x 3 product, whose other terms are
  // zeros, in a fraction of its arithmetic; only a -0 may stay -0 where the
  // product gave +0).
  Eigen::Matrix<double, 3, 2> dnormal(const Eigen::Matrix<double, 3, 2>& dpoint) const {
    if (umbilic_curvature_per_mm) return *umbilic_curvature_per_mm * dpoint;
    return dnormal_dpoint * dpoint;
  }
};

// Relative error bound for hit points and spawned origins: 64 ulp of the
// magnitudes involved. Hit::error_mm = kHitRelativeError * (|p|_inf + scale).
inline constexpr double kHitRelativeError = 64 * 2.220446049250313e-16;

}  // namespace glasspiv
