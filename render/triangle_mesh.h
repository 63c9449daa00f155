#pragma once
// Triangle-mesh solids (CAD parts) for the ray tracer, with the contract of the
// analytic solids in render/shapes.h: intersect(mesh, o, d, t_min) returns the
// first hit with t > t_min, its outward geometric normal and an error bound;
// tangent rays are misses; contains() and scale_mm() as for the other shapes.
// Double precision, mm, world frame. Files and the scene syntax: render/mesh_file.h,
// docs/scene.md.
//
// - Only closed, consistently oriented meshes are accepted (every edge shared by
//   exactly two triangles running through it in opposite directions); the
//   builder orients every closed part so that its normals point out of the
//   solid (nested shells, i.e. cavities, point into the cavity).
// - An Embree BVH (float) finds the candidate triangles; each candidate is
//   tested in double with the watertight ray-triangle test of Woop, Benthin and
//   Wald (JCGT 2013) whose 2D edge functions are evaluated with exact signs, and
//   rays exactly through an edge or a vertex are resolved by a symbolic
//   perturbation of the ray, so that such a ray meets exactly one of the
//   triangles sharing the edge or vertex: never none, never two. A ray through
//   an edge where the surface folds over (a silhouette edge, seen exactly
//   edge-on) touches the solid without entering it and is a miss.
// - Flat or smooth shading: Hit::normal is always the geometric outward normal
//   of the triangle (the tracer decides entering/leaving with it); smooth
//   meshes also set Hit::shading_normal, the normalised barycentric
//   interpolation of the corner normals, turned to the side of Hit::normal,
//   and Hit::dnormal_dpoint, its derivative along the triangle (zero when flat).
//
// A TriangleMesh is immutable and cheap to copy (it shares its prepared data and
// BVH); intersect, contains and the other queries may be called from any number
// of threads at once.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "render/hit.h"

namespace glasspiv {

using MeshTriangle = std::array<std::uint32_t, 3>;

// The arrays a mesh is built from (world frame, mm).
struct MeshArrays {
  std::vector<Eigen::Vector3d> vertices_mm;
  std::vector<MeshTriangle> triangles;  // indices into vertices_mm
  // Optional shading normals (need not be unit, must be finite and non-zero),
  // indexed as in OBJ: normal_triangles[k][c] is the normal of corner c of
  // triangle k. With normal_triangles empty, the normals are per vertex
  // (normals.size() == vertices_mm.size(), indexed like the vertices).
  std::vector<Eigen::Vector3d> normals;
  std::vector<MeshTriangle> normal_triangles;
};

enum class MeshShading {
  flat,    // geometric normals only; Hit::shading_normal stays empty
  smooth,  // interpolated corner normals: the given ones, else computed ones
};

struct MeshBuildOptions {
  MeshShading shading = MeshShading::smooth;
  // Computed normals (smooth, none given): the normal of a corner is the
  // weighted mean of the normals of the triangles around its vertex whose
  // normal lies within this angle of the corner's triangle's normal, so edges
  // sharper than this stay sharp; 180 smooths across every edge. In (0, 180].
  // The weights are Max's (1999), sin(corner angle) / (|e1| |e2|): exact for
  // vertices on a sphere, second order on smooth surfaces (angle weights are
  // first order on irregular meshes).
  double crease_angle_deg = 60;
};

class TriangleMesh {
 public:
  struct Data;  // the prepared mesh and its BVH (render/triangle_mesh.cpp)

  // An empty mesh: hits nothing, contains nothing.
  TriangleMesh() = default;

  // The prepared mesh (vertices, triangles after orientation, normals).
  const std::vector<Eigen::Vector3d>& vertices_mm() const;
  const std::vector<MeshTriangle>& triangles() const;
  std::size_t triangle_count() const { return triangles().size(); }
  // Outward unit normal of triangle k (std::out_of_range for a bad k).
  const Eigen::Vector3d& triangle_normal(std::size_t k) const;
  // The unit shading normals of the corners of triangle k (smooth meshes; the
  // geometric normal three times for flat ones).
  std::array<Eigen::Vector3d, 3> corner_normals(std::size_t k) const;
  MeshShading shading() const;
  double volume_mm3() const;           // enclosed volume (> 0)
  int part_count() const;              // connected closed parts (shells)
  int flipped_part_count() const;      // parts whose triangles the builder reversed

  const Data* data() const { return data_.get(); }

 private:
  friend TriangleMesh build_triangle_mesh(MeshArrays arrays, const MeshBuildOptions& options);
  std::shared_ptr<const Data> data_;
};

// Checks and prepares a mesh: throws std::invalid_argument with a one-line
// reason for no triangles, a vertex that is not finite, an index out of range,
// a degenerate (zero-area) triangle, an open mesh (an edge of one triangle
// only), an edge shared by more than two triangles, inconsistent orientation
// (two triangles running through an edge in the same direction), a part that
// encloses no volume, or bad normals. Reverses parts that are inside out.
TriangleMesh build_triangle_mesh(MeshArrays arrays, const MeshBuildOptions& options = {});

// A hit with what only a mesh knows.
struct MeshHit {
  Hit hit;
  std::uint32_t triangle = 0;
  Eigen::Vector3d barycentric = Eigen::Vector3d::Zero();  // weights of the triangle's corners 0, 1, 2
};

// The shape contract (render/shapes.h).
std::optional<Hit> intersect(const TriangleMesh& m, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min);
// Whether p lies inside the solid (ray parity, exact for the perturbed ray) and
// farther than margin_mm from its surface; a negative margin also accepts
// points outside within |margin_mm| of the surface.
bool contains(const TriangleMesh& m, const Eigen::Vector3d& p, double margin_mm = 0);
// max |vertex|_inf: the magnitude the rounding error of an interpolated hit point
// scales with besides |p|; Hit::error_mm = kHitRelativeError * (|p|_inf + scale).
double scale_mm(const TriangleMesh& m);
// Axis-aligned world bounds of the vertices.
Eigen::AlignedBox3d bounds_mm(const TriangleMesh& m);

// The first hit with its triangle and barycentric coordinates.
std::optional<MeshHit> intersect_mesh(const TriangleMesh& m, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                                      double t_min);
// Every triangle the ray meets at t > t_min, ordered by t (ties: lower triangle
// index). For a ray that meets the closed surface transversally, entering and
// leaving hits alternate.
std::vector<MeshHit> intersect_all(const TriangleMesh& m, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                                   double t_min);
// The exact test of one triangle, without the BVH (tests, brute-force checks).
std::optional<MeshHit> intersect_triangle(const TriangleMesh& m, std::uint32_t triangle, const Eigen::Vector3d& o,
                                          const Eigen::Vector3d& d, double t_min);

}  // namespace glasspiv
