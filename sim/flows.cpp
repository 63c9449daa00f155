#include "sim/flows.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace glasspiv {
namespace {

constexpr double kMmPerM = 1000.0;

void require(bool ok, const char* what) {
  if (!ok) throw std::invalid_argument(what);
}

bool finite(const Eigen::Vector3d& v) { return v.allFinite(); }

Eigen::Vector3d unit_axis(const Eigen::Vector3d& axis, const char* what) {
  require(finite(axis) && axis.norm() > 0, what);
  return axis.normalized();
}

}  // namespace

UniformFlow::UniformFlow(const Eigen::Vector3d& value_m_per_s) : value_m_per_s_(value_m_per_s) {
  require(finite(value_m_per_s), "UniformFlow: velocity must be finite");
}

Eigen::Vector3d UniformFlow::velocity_m_per_s(const Eigen::Vector3d&, double) const { return value_m_per_s_; }

PoiseuilleChannelFlow::PoiseuilleChannelFlow(const Eigen::Vector3d& mid_plane_point_mm,
                                             const Eigen::Vector3d& wall_normal,
                                             const Eigen::Vector3d& flow_direction, double half_width_mm,
                                             double centreline_velocity_m_per_s)
    : mid_plane_point_mm_(mid_plane_point_mm),
      wall_normal_(unit_axis(wall_normal, "PoiseuilleChannelFlow: wall_normal must be finite and non-zero")),
      half_width_mm_(half_width_mm),
      centreline_velocity_m_per_s_(centreline_velocity_m_per_s) {
  require(finite(mid_plane_point_mm), "PoiseuilleChannelFlow: mid-plane point must be finite");
  require(std::isfinite(half_width_mm) && half_width_mm > 0, "PoiseuilleChannelFlow: half_width_mm must be > 0");
  require(std::isfinite(centreline_velocity_m_per_s), "PoiseuilleChannelFlow: velocity must be finite");
  require(finite(flow_direction), "PoiseuilleChannelFlow: flow_direction must be finite");
  const Eigen::Vector3d in_plane = flow_direction - flow_direction.dot(wall_normal_) * wall_normal_;
  require(in_plane.norm() > 1e-9 * flow_direction.norm() && in_plane.norm() > 0,
          "PoiseuilleChannelFlow: flow_direction must not be parallel to wall_normal");
  flow_direction_ = in_plane.normalized();
}

Eigen::Vector3d PoiseuilleChannelFlow::velocity_m_per_s(const Eigen::Vector3d& point_mm, double) const {
  const double eta = (point_mm - mid_plane_point_mm_).dot(wall_normal_) / half_width_mm_;
  if (std::abs(eta) >= 1) return Eigen::Vector3d::Zero();
  return centreline_velocity_m_per_s_ * (1 - eta * eta) * flow_direction_;
}

SolidBodyRotationFlow::SolidBodyRotationFlow(const Eigen::Vector3d& axis_point_mm, const Eigen::Vector3d& axis,
                                             double angular_velocity_rad_per_s)
    : axis_point_mm_(axis_point_mm),
      axis_(unit_axis(axis, "SolidBodyRotationFlow: axis must be finite and non-zero")),
      angular_velocity_rad_per_s_(angular_velocity_rad_per_s) {
  require(finite(axis_point_mm), "SolidBodyRotationFlow: axis point must be finite");
  require(std::isfinite(angular_velocity_rad_per_s), "SolidBodyRotationFlow: angular velocity must be finite");
}

Eigen::Vector3d SolidBodyRotationFlow::velocity_m_per_s(const Eigen::Vector3d& point_mm, double) const {
  return (angular_velocity_rad_per_s_ / kMmPerM) * axis_.cross(point_mm - axis_point_mm_);
}

LambOseenVortexFlow::LambOseenVortexFlow(const Eigen::Vector3d& centre_mm, const Eigen::Vector3d& axis,
                                         double circulation_m2_per_s, double core_radius_mm,
                                         double kinematic_viscosity_m2_per_s)
    : centre_mm_(centre_mm),
      axis_(unit_axis(axis, "LambOseenVortexFlow: axis must be finite and non-zero")),
      circulation_m2_per_s_(circulation_m2_per_s),
      core_radius_mm_(core_radius_mm),
      kinematic_viscosity_m2_per_s_(kinematic_viscosity_m2_per_s) {
  require(finite(centre_mm), "LambOseenVortexFlow: centre must be finite");
  require(std::isfinite(circulation_m2_per_s), "LambOseenVortexFlow: circulation must be finite");
  require(std::isfinite(core_radius_mm) && core_radius_mm > 0, "LambOseenVortexFlow: core_radius_mm must be > 0");
  require(std::isfinite(kinematic_viscosity_m2_per_s) && kinematic_viscosity_m2_per_s >= 0,
          "LambOseenVortexFlow: kinematic viscosity must be >= 0");
}

double LambOseenVortexFlow::core_radius_mm(double time_s) const {
  const double rc2_mm2 = core_radius_mm_ * core_radius_mm_ + 4 * kinematic_viscosity_m2_per_s_ * time_s * kMmPerM * kMmPerM;
  return rc2_mm2 > 0 ? std::sqrt(rc2_mm2) : std::nan("");
}

Eigen::Vector3d LambOseenVortexFlow::velocity_m_per_s(const Eigen::Vector3d& point_mm, double time_s) const {
  const Eigen::Vector3d offset_mm = point_mm - centre_mm_;
  const Eigen::Vector3d radial_mm = offset_mm - offset_mm.dot(axis_) * axis_;
  const double r_mm = radial_mm.norm();
  if (r_mm == 0) return Eigen::Vector3d::Zero();
  const double rc_mm = core_radius_mm(time_s);
  // -expm1(-x) = 1 - exp(-x) without cancellation near the axis.
  const double u_theta_m_per_s =
      circulation_m2_per_s_ / (2 * M_PI * r_mm / kMmPerM) * -std::expm1(-(r_mm * r_mm) / (rc_mm * rc_mm));
  return u_theta_m_per_s * axis_.cross(radial_mm / r_mm);
}

StokesSphereFlow::StokesSphereFlow(const Eigen::Vector3d& centre_mm, double radius_mm,
                                   const Eigen::Vector3d& free_stream_m_per_s)
    : centre_mm_(centre_mm), radius_mm_(radius_mm), free_stream_m_per_s_(free_stream_m_per_s) {
  require(finite(centre_mm), "StokesSphereFlow: centre must be finite");
  require(std::isfinite(radius_mm) && radius_mm > 0, "StokesSphereFlow: radius_mm must be > 0");
  require(finite(free_stream_m_per_s), "StokesSphereFlow: free stream must be finite");
}

Eigen::Vector3d StokesSphereFlow::velocity_m_per_s(const Eigen::Vector3d& point_mm, double) const {
  const Eigen::Vector3d offset_mm = point_mm - centre_mm_;
  const double r_mm = offset_mm.norm();
  if (r_mm <= radius_mm_) return Eigen::Vector3d::Zero();
  const Eigen::Vector3d e = offset_mm / r_mm;
  const Eigen::Vector3d& u = free_stream_m_per_s_;
  const double ue = u.dot(e);
  const double ar = radius_mm_ / r_mm;
  return u - (0.75 * ar) * (u + ue * e) - (0.25 * ar * ar * ar) * (u - 3 * ue * e);
}

SolidInteriors::SolidInteriors(const std::vector<TraceSolid>& solids) {
  for (const TraceSolid& s : solids) shapes_.push_back(s.shape);
  build_grid();
}

SolidInteriors::SolidInteriors(const std::vector<Shape>& shapes) : shapes_(shapes) { build_grid(); }

void SolidInteriors::build_grid() {
  // Rectangles have no inside: leave them out of the search.
  shapes_.erase(std::remove_if(shapes_.begin(), shapes_.end(),
                               [](const Shape& s) { return std::holds_alternative<Rectangle>(s); }),
                shapes_.end());
  bounds_mm_.clear();
  grid_bounds_mm_.setEmpty();
  for (const Shape& s : shapes_) {
    bounds_mm_.push_back(bounds_mm(s));
    grid_bounds_mm_.extend(bounds_mm_.back());
  }
  cell_shapes_.clear();
  if (shapes_.empty()) return;
  // About two cells per solid, cubic cells, at most 128 along an axis.
  const Eigen::Vector3d extent_mm = grid_bounds_mm_.sizes().cwiseMax(1e-9);
  const double cell_mm = std::cbrt(extent_mm.prod() / (2.0 * static_cast<double>(shapes_.size())));
  for (int a = 0; a < 3; ++a) {
    cells_[a] = static_cast<int>(std::clamp(std::ceil(extent_mm[a] / cell_mm), 1.0, 128.0));
    cell_size_mm_[a] = extent_mm[a] / cells_[a];
  }
  cell_shapes_.assign(static_cast<std::size_t>(cells_.prod()), {});
  const auto cell_of = [&](const Eigen::Vector3d& p, int a) {
    const int i = static_cast<int>(std::floor((p[a] - grid_bounds_mm_.min()[a]) / cell_size_mm_[a]));
    return std::clamp(i, 0, cells_[a] - 1);
  };
  for (int k = 0; k < static_cast<int>(shapes_.size()); ++k) {
    const Eigen::AlignedBox3d& b = bounds_mm_[static_cast<std::size_t>(k)];
    for (int z = cell_of(b.min(), 2); z <= cell_of(b.max(), 2); ++z)
      for (int y = cell_of(b.min(), 1); y <= cell_of(b.max(), 1); ++y)
        for (int x = cell_of(b.min(), 0); x <= cell_of(b.max(), 0); ++x)
          cell_shapes_[static_cast<std::size_t>((z * cells_[1] + y) * cells_[0] + x)].push_back(k);
  }
}

bool SolidInteriors::inside(const Eigen::Vector3d& point_mm) const {
  if (shapes_.empty() || !grid_bounds_mm_.contains(point_mm)) return false;
  int index[3];
  for (int a = 0; a < 3; ++a) {
    const int i = static_cast<int>(std::floor((point_mm[a] - grid_bounds_mm_.min()[a]) / cell_size_mm_[a]));
    index[a] = std::clamp(i, 0, cells_[a] - 1);
  }
  for (int k : cell_shapes_[static_cast<std::size_t>((index[2] * cells_[1] + index[1]) * cells_[0] + index[0])]) {
    if (bounds_mm_[static_cast<std::size_t>(k)].contains(point_mm) &&
        contains(shapes_[static_cast<std::size_t>(k)], point_mm))
      return true;
  }
  return false;
}

FlowOutsideSolids::FlowOutsideSolids(std::shared_ptr<const Flow> flow, const TraceScene& scene)
    : FlowOutsideSolids(std::move(flow), SolidInteriors(scene.solids)) {}

FlowOutsideSolids::FlowOutsideSolids(std::shared_ptr<const Flow> flow, SolidInteriors solids)
    : flow_(std::move(flow)), solids_(std::move(solids)) {
  require(flow_ != nullptr, "FlowOutsideSolids: flow must not be null");
}

Eigen::Vector3d FlowOutsideSolids::velocity_m_per_s(const Eigen::Vector3d& point_mm, double time_s) const {
  if (solids_.inside(point_mm)) return Eigen::Vector3d::Zero();
  return flow_->velocity_m_per_s(point_mm, time_s);
}

}  // namespace glasspiv
