#pragma once
// Exact analytic solids for the ray tracer: sphere, box (a slab is a thin, wide
// box) and finite capped cylinder, in double precision and mm. See docs/tracer.md.
//
// Conventions:
// - A ray is origin o and a *unit* direction d; intersect(...) returns the first
//   surface point o + t d with t > t_min, or std::nullopt.
// - The returned normal is the *outward* unit normal of the solid at the hit;
//   the sign of d . normal tells entering (< 0) from leaving (> 0).
// - A ray tangent to a surface (zero discriminant, a ray lying in a face plane,
//   touching only an edge or a corner) is a miss: it does not enter the solid.
// - Hit points are projected back onto the exact surface (radius, face plane),
//   so their error is bounded by Hit::error_mm whatever the distance the ray
//   travelled; spawn_origin() uses that bound to start the continuing ray on
//   the correct side (the one place where self-intersection is handled).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <variant>
#include <vector>

#include "render/hit.h"
#include "render/triangle_mesh.h"

namespace glasspiv {


struct Sphere {
  Eigen::Vector3d centre_mm = Eigen::Vector3d::Zero();
  double radius_mm = 1;
};

// Axis-aligned box [-half_extent, +half_extent] in its own frame, placed by a
// rigid transform: p_world = world_from_box * p_box + centre_mm (rotation only
// in world_from_box).
struct Box {
  Eigen::Vector3d centre_mm = Eigen::Vector3d::Zero();
  Eigen::Matrix3d world_from_box = Eigen::Matrix3d::Identity();
  Eigen::Vector3d half_extent_mm = Eigen::Vector3d::Ones();
};

// Finite cylinder with flat caps: axis through centre_mm along the unit vector
// axis, |axial| <= half_length_mm, radial distance <= radius_mm.
struct Cylinder {
  Eigen::Vector3d centre_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  double radius_mm = 1;
  double half_length_mm = 1;
};

// A thin two-sided rectangle (target, marker sheet, backdrop): centre_mm, unit
// in-plane axes right and up, half sizes along them. It has no inside: its
// normal always faces the incoming ray, so a ray meeting it enters it (and the
// tracer only allows rectangles of opaque material).
struct Rectangle {
  Eigen::Vector3d centre_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d right = Eigen::Vector3d::UnitX();
  Eigen::Vector3d up = Eigen::Vector3d::UnitY();
  double half_width_mm = 1, half_height_mm = 1;

  Eigen::Vector3d normal() const { return right.cross(up); }
};

// Triangle meshes (render/triangle_mesh.h) follow the same contract.
using Shape = std::variant<Sphere, Box, Cylinder, Rectangle, TriangleMesh>;

// A slab: a box of the given thickness along the unit normal through centre,
// extending half_extent_mm either way in the plane.
Box make_slab(const Eigen::Vector3d& centre_mm, const Eigen::Vector3d& normal, double thickness_mm,
              double half_extent_mm);

std::optional<Hit> intersect(const Sphere& s, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min);
// The sphere's intersect() in two halves, so that a search over many candidates
// builds the full hit for the winner only: sphere_hit_t is the t intersect()
// returns (nullopt for its misses), sphere_hit the Hit it returns for that t.
std::optional<double> sphere_hit_t(const Sphere& s, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                                   double t_min);
Hit sphere_hit(const Sphere& s, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t);
std::optional<Hit> intersect(const Box& b, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min);
std::optional<Hit> intersect(const Cylinder& c, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min);
std::optional<Hit> intersect(const Rectangle& r, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min);
std::optional<Hit> intersect(const Shape& s, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min);

// The nearest hit over all shapes (ties: the lower index), shape_index set;
// shapes[skip_index] is not tested (-1: every shape is).
std::optional<Hit> first_hit(const std::vector<Shape>& shapes, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                             double t_min, int skip_index = -1);

// Axis-aligned world bounds of the solid (exact for spheres and rectangles,
// tight for boxes and cylinders).
Eigen::AlignedBox3d bounds_mm(const Shape& s);

// Whether p lies strictly inside the solid by more than margin_mm (tests, checks).
bool contains(const Shape& s, const Eigen::Vector3d& p, double margin_mm = 0);

// The magnitude, besides |p|, that the rounding error of a hit point p scales
// with: |centre|_inf + radius (sphere), 2 |centre|_inf + smallest half extent
// (box, whose face coordinate is exact in its own frame), 2 |centre|_inf +
// radius (cylinder), 2 |centre|_inf (rectangle).
double scale_mm(const Shape& s);


// Origin of the ray that continues from `hit` in `direction`: the hit point
// moved by 2 * hit.error_mm along the normal, to the side direction travels to
// (sign of direction . normal). A direction exactly in the tangent plane goes
// outward if tangent_outward, else inward. The spawned ray is then traced with
// t_min = 0 and cannot find the surface it starts on at t ~ 0.
Eigen::Vector3d spawn_origin(const Hit& hit, const Eigen::Vector3d& direction, bool tangent_outward = true);

}  // namespace glasspiv
