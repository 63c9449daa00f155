#pragma once
// Analytic flows with exact velocities: the ground truth of simulated PIV
// experiments (docs/simulation.md). Units in every name: positions in mm in the
// world frame, velocities in m/s, times in s (1 m/s moves a tracer 1 mm per ms).
// A flow is an immutable object behind the Flow interface (virtual, so CFD
// fields from files and wrappers compose with the analytic ones); calls are
// const and thread-safe. Constructors throw std::invalid_argument for
// non-finite values, non-positive sizes or zero axes. No I/O.
#include <memory>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "render/path_tracer.h"

namespace glasspiv {

class Flow {
 public:
  virtual ~Flow() = default;
  // Velocity (m/s, world frame) at point_mm (world frame) and time_s.
  virtual Eigen::Vector3d velocity_m_per_s(const Eigen::Vector3d& point_mm, double time_s) const = 0;
};

// u = constant.
class UniformFlow final : public Flow {
 public:
  explicit UniformFlow(const Eigen::Vector3d& value_m_per_s);
  Eigen::Vector3d velocity_m_per_s(const Eigen::Vector3d& point_mm, double time_s) const override;

 private:
  Eigen::Vector3d value_m_per_s_;
};

// Plane Poiseuille flow between two walls at y = +-half_width_mm, where
// y = (p - mid_plane_point_mm) . wall_normal:
//   u = centreline_velocity (1 - (y / h)^2) flow_direction  for |y| <= h, zero beyond.
// The mean over the gap is 2/3 of the centreline velocity. flow_direction is
// made orthogonal to wall_normal; both are normalised.
class PoiseuilleChannelFlow final : public Flow {
 public:
  PoiseuilleChannelFlow(const Eigen::Vector3d& mid_plane_point_mm, const Eigen::Vector3d& wall_normal,
                        const Eigen::Vector3d& flow_direction, double half_width_mm,
                        double centreline_velocity_m_per_s);
  Eigen::Vector3d velocity_m_per_s(const Eigen::Vector3d& point_mm, double time_s) const override;

 private:
  Eigen::Vector3d mid_plane_point_mm_, wall_normal_, flow_direction_;
  double half_width_mm_, centreline_velocity_m_per_s_;
};

// Rigid rotation about the line through axis_point_mm along axis (normalised),
// counter-clockwise seen from +axis for a positive rate: u = omega axis x (p - c).
class SolidBodyRotationFlow final : public Flow {
 public:
  SolidBodyRotationFlow(const Eigen::Vector3d& axis_point_mm, const Eigen::Vector3d& axis,
                        double angular_velocity_rad_per_s);
  Eigen::Vector3d velocity_m_per_s(const Eigen::Vector3d& point_mm, double time_s) const override;

 private:
  Eigen::Vector3d axis_point_mm_, axis_;
  double angular_velocity_rad_per_s_;
};

// The Lamb-Oseen vortex, the diffusing line vortex of the Navier-Stokes
// equations, about the line through centre_mm along axis (normalised):
//   u_theta(r, t) = Gamma / (2 pi r) (1 - exp(-r^2 / rc(t)^2)),  rc(t)^2 = rc0^2 + 4 nu t,
// counter-clockwise about +axis for Gamma > 0; no axial or radial velocity.
// kinematic_viscosity 0 freezes the core (a steady vortex of radius rc0).
class LambOseenVortexFlow final : public Flow {
 public:
  LambOseenVortexFlow(const Eigen::Vector3d& centre_mm, const Eigen::Vector3d& axis, double circulation_m2_per_s,
                      double core_radius_mm, double kinematic_viscosity_m2_per_s = 0);
  Eigen::Vector3d velocity_m_per_s(const Eigen::Vector3d& point_mm, double time_s) const override;
  // rc(t) in mm (time_s >= -rc0^2 / (4 nu), else NaN).
  double core_radius_mm(double time_s) const;

 private:
  Eigen::Vector3d centre_mm_, axis_;
  double circulation_m2_per_s_, core_radius_mm_, kinematic_viscosity_m2_per_s_;
};

// Stokes (creeping, Re -> 0) flow past a fixed sphere of radius a in a uniform
// stream U (Stokes 1851; Batchelor, An Introduction to Fluid Dynamics, 4.9):
//   u = U - (3a / 4r) (U + (U.e) e) - (a^3 / 4r^3) (U - 3 (U.e) e),  e = (p - c) / r,
// zero on the sphere (no slip) and inside it, U far away, divergence-free.
class StokesSphereFlow final : public Flow {
 public:
  StokesSphereFlow(const Eigen::Vector3d& centre_mm, double radius_mm, const Eigen::Vector3d& free_stream_m_per_s);
  Eigen::Vector3d velocity_m_per_s(const Eigen::Vector3d& point_mm, double time_s) const override;

 private:
  Eigen::Vector3d centre_mm_;
  double radius_mm_;
  Eigen::Vector3d free_stream_m_per_s_;
};

// Point-in-solid queries over a scene's solids (render/shapes.h contains(),
// exact for spheres, boxes, cylinders and closed meshes; rectangles have no
// inside), with a uniform grid over their bounds so that packed beds of many
// spheres cost a few tests per point.
class SolidInteriors {
 public:
  SolidInteriors() = default;
  explicit SolidInteriors(const std::vector<TraceSolid>& solids);
  explicit SolidInteriors(const std::vector<Shape>& shapes);
  // Whether point_mm lies strictly inside some solid (its surface counts as outside).
  bool inside(const Eigen::Vector3d& point_mm) const;
  std::size_t size() const { return shapes_.size(); }

 private:
  void build_grid();
  std::vector<Shape> shapes_;
  std::vector<Eigen::AlignedBox3d> bounds_mm_;
  Eigen::AlignedBox3d grid_bounds_mm_;
  Eigen::Vector3i cells_ = Eigen::Vector3i::Zero();
  Eigen::Vector3d cell_size_mm_ = Eigen::Vector3d::Ones();
  std::vector<std::vector<int>> cell_shapes_;  // shape indices overlapping each cell (x fastest)
};

// "No flow inside solids": the wrapped flow outside every solid, zero inside.
// It does not make the flow satisfy no-slip at the surfaces (only the Stokes
// sphere does that exactly); it keeps tracers from moving through glass.
class FlowOutsideSolids final : public Flow {
 public:
  FlowOutsideSolids(std::shared_ptr<const Flow> flow, const TraceScene& scene);
  FlowOutsideSolids(std::shared_ptr<const Flow> flow, SolidInteriors solids);
  Eigen::Vector3d velocity_m_per_s(const Eigen::Vector3d& point_mm, double time_s) const override;

 private:
  std::shared_ptr<const Flow> flow_;
  SolidInteriors solids_;
};

}  // namespace glasspiv
