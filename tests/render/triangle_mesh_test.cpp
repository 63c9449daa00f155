// Tests of render/triangle_mesh.h: hits lie on their triangles and agree with a
// brute-force search, outward orientation (also of inside-out input and of
// cavities), watertightness at shared edges and vertices (exactly one entry
// and one exit, never none, never two), h^2 convergence to the analytic sphere
// of hit points and smooth shading normals, contains(), the spawn rule, thread
// safety, and the refusal of open, inconsistent and degenerate meshes.
#include "render/shapes.h"
#include "render/triangle_mesh.h"
#include "tests/render/test_meshes.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>

namespace glasspiv {
namespace {

using Eigen::Vector3d;

// ---------------------------------------------------------------------------
// Test meshes.

MeshArrays reversed(MeshArrays a) {
  for (MeshTriangle& t : a.triangles) std::swap(t[1], t[2]);
  return a;
}

MeshArrays merged(const MeshArrays& a, const MeshArrays& b) {
  MeshArrays m = a;
  const auto offset = static_cast<std::uint32_t>(a.vertices_mm.size());
  m.vertices_mm.insert(m.vertices_mm.end(), b.vertices_mm.begin(), b.vertices_mm.end());
  m.normals.insert(m.normals.end(), b.normals.begin(), b.normals.end());
  for (MeshTriangle t : b.triangles) m.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  return m;
}

TriangleMesh flat(MeshArrays a) {
  a.normals.clear();
  return build_triangle_mesh(std::move(a), {MeshShading::flat, 60});
}

Vector3d random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0, 1);
  Vector3d v;
  do v = Vector3d(n(rng), n(rng), n(rng));
  while (v.norm() < 1e-6);
  return v.normalized();
}

// The nearest hit over every triangle, without the BVH.
std::optional<MeshHit> brute_force(const TriangleMesh& m, const Vector3d& o, const Vector3d& d, double t_min) {
  std::optional<MeshHit> best;
  for (std::uint32_t k = 0; k < m.triangle_count(); ++k) {
    auto h = intersect_triangle(m, k, o, d, t_min);
    if (h && (!best || h->hit.t < best->hit.t)) best = h;
  }
  return best;
}

// ---------------------------------------------------------------------------

TEST(TriangleMesh, FlatHitsLieOnTheirTrianglesAndMatchBruteForce) {
  const Vector3d centre(3, -2, 5);
  const TriangleMesh m = flat(icosphere(3, 20, centre));
  ASSERT_EQ(m.triangle_count(), 20u * 64);
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(-1, 1);
  int hits = 0;
  double worst_plane = 0;
  for (int i = 0; i < 4000; ++i) {
    // Origins near (60 mm), at camera distance (600 mm) and far (1e5 mm): the
    // float BVH must not lose a candidate the double test accepts.
    const double distance = i % 3 == 0 ? 60 : (i % 3 == 1 ? 600 : 1e5);
    const Vector3d o = centre + distance * random_unit(rng);
    const Vector3d target = centre + 21 * Vector3d(u(rng), u(rng), u(rng));
    const Vector3d d = (target - o).normalized();
    const auto h = intersect_mesh(m, o, d, 0);
    const auto b = brute_force(m, o, d, 0);
    ASSERT_EQ(h.has_value(), b.has_value()) << i;
    if (!h) continue;
    ++hits;
    EXPECT_EQ(h->triangle, b->triangle) << i;
    EXPECT_EQ(h->hit.t, b->hit.t) << i;
    const MeshTriangle& t = m.triangles()[h->triangle];
    const Vector3d& a = m.vertices_mm()[t[0]];
    const double plane = std::fabs(m.triangle_normal(h->triangle).dot(h->hit.point - a));
    worst_plane = std::max(worst_plane, plane);
    // 1e-12 mm: the point is interpolated from vertices of magnitude ~30 mm
    // (a few ulp, ~1e-14 mm), independent of the 1e5 mm the ray travelled.
    EXPECT_LT(plane, 1e-12) << i;
    EXPECT_LT(plane, h->hit.error_mm) << i;  // the bound spawn_origin relies on
    EXPECT_GE(h->barycentric.minCoeff(), 0) << i;
    EXPECT_NEAR(h->barycentric.sum(), 1, 1e-15) << i;
    EXPECT_FALSE(h->hit.shading_normal.has_value()) << "flat";
    EXPECT_TRUE(h->hit.dnormal_dpoint.isZero()) << "flat";
    EXPECT_NEAR((o + h->hit.t * d - h->hit.point).norm(), 0, 1e-9 * (1 + distance));
  }
  EXPECT_GT(hits, 1000);
  std::printf("flat icosphere: worst distance of a hit to its triangle's plane %.2e mm\n", worst_plane);
}

TEST(TriangleMesh, NormalsPointOutwardWhateverTheInputWinding) {
  const Vector3d centre(1, 2, 3);
  for (bool inside_out : {false, true}) {
    SCOPED_TRACE(inside_out);
    MeshArrays a = icosphere(2, 20, centre);
    if (inside_out) a = reversed(a);
    const TriangleMesh m = flat(a);
    EXPECT_EQ(m.flipped_part_count(), inside_out ? 1 : 0);
    EXPECT_EQ(m.part_count(), 1);
    for (std::size_t k = 0; k < m.triangle_count(); ++k) {
      const MeshTriangle& t = m.triangles()[k];
      const Vector3d mid = (m.vertices_mm()[t[0]] + m.vertices_mm()[t[1]] + m.vertices_mm()[t[2]]) / 3;
      EXPECT_GT(m.triangle_normal(k).dot((mid - centre).normalized()), 0.9) << k;
    }
    // Inscribed polyhedron: a little less than the sphere's volume.
    EXPECT_GT(m.volume_mm3(), 0.9 * 4 / 3.0 * M_PI * 8000);
    EXPECT_LT(m.volume_mm3(), 4 / 3.0 * M_PI * 8000);
    const auto in = intersect(m, centre - Vector3d(0, 0, 100), Vector3d::UnitZ(), 0);
    ASSERT_TRUE(in);
    EXPECT_LT(in->normal.z(), 0) << "entering: the outward normal faces the ray";
    const auto out = intersect(m, centre - Vector3d(0, 0, 100), Vector3d::UnitZ(), in->t);
    ASSERT_TRUE(out);
    EXPECT_GT(out->normal.z(), 0) << "leaving";
  }
}

TEST(TriangleMesh, CavitiesAreOrientedIntoTheCavity) {
  // A hollow ball: outer shell r 20, inner shell r 10, both given wound outward
  // (as a CAD program may write them). The inner one bounds the cavity, so its
  // normals must point to the centre (out of the glass).
  const MeshArrays outer = icosphere(3, 20), inner = icosphere(3, 10);
  const TriangleMesh m = flat(merged(outer, inner));
  EXPECT_EQ(m.part_count(), 2);
  EXPECT_EQ(m.flipped_part_count(), 1);
  const double expected = signed_volume(outer) - signed_volume(inner);
  EXPECT_NEAR(m.volume_mm3(), expected, 1e-9 * expected);
  const Vector3d o(0.1, 0.2, -100), d = Vector3d::UnitZ();
  const std::vector<MeshHit> all = intersect_all(m, o, d, 0);
  ASSERT_EQ(all.size(), 4u);
  const double signs[4] = {-1, 1, -1, 1};  // enter glass, leave into the cavity, enter glass, leave
  for (int k = 0; k < 4; ++k) EXPECT_GT(signs[k] * all[k].hit.normal.dot(d), 0) << k;
  EXPECT_FALSE(contains(m, Vector3d(0, 0, 0)));
  EXPECT_TRUE(contains(m, Vector3d(0, 0, 15)));
  EXPECT_FALSE(contains(m, Vector3d(0, 0, 25)));
  // Same answer with the inner shell given already inward.
  const TriangleMesh same = flat(merged(outer, reversed(inner)));
  EXPECT_EQ(same.flipped_part_count(), 0);
  EXPECT_NEAR(same.volume_mm3(), expected, 1e-9 * expected);
}

// Counts a ray's crossings: exactly one entry then one exit is a pass.
struct Crossings {
  int rays = 0, failures = 0, exact_ties = 0;
  std::string first_failure;
  void check(const TriangleMesh& m, const Vector3d& o, const Vector3d& d, const Vector3d& target) {
    ++rays;
    const std::vector<MeshHit> all = intersect_all(m, o, d, 0);
    bool ok = all.size() == 2 && all[0].hit.normal.dot(d) < 0 && all[1].hit.normal.dot(d) > 0 &&
              (all[0].hit.point - target).norm() < 1e-9;
    // The nearest-hit query agrees, and chaining it by t_min finds the exit and then nothing.
    if (ok) {
      const auto first = intersect_mesh(m, o, d, 0);
      const auto second = first ? intersect_mesh(m, o, d, first->hit.t) : std::nullopt;
      const auto third = second ? intersect_mesh(m, o, d, second->hit.t) : std::nullopt;
      ok = first && first->triangle == all[0].triangle && second && second->triangle == all[1].triangle && !third;
    }
    if (!all.empty() && all[0].barycentric.minCoeff() == 0) ++exact_ties;
    if (!ok && failures++ == 0) {
      char buf[300];
      std::snprintf(buf, sizeof buf, "o (%.17g, %.17g, %.17g) d (%.17g, %.17g, %.17g): %zu hits", o.x(), o.y(), o.z(),
                    d.x(), d.y(), d.z(), all.size());
      first_failure = buf;
    }
  }
};

TEST(TriangleMesh, WatertightRaysThroughVerticesAndEdgesHitExactlyOneTriangle) {
  // (a) An icosphere, rays aimed at every vertex and every edge midpoint from
  // random points outside (within 60 degrees of the outward direction there),
  // 50 mm or 1e5 mm away, with unit directions: the rounded ray passes within
  // ~1e-15 mm (~1e-11 mm from afar) of the vertex or edge, on either side or
  // exactly on it. From afar, a float ray would be ~5e-3 mm off: the BVH must
  // still hand the right triangle to the double test.
  {
    const MeshArrays a = icosphere(2, 20);
    const TriangleMesh m = flat(a);
    std::vector<Vector3d> targets = a.vertices_mm;
    for (const MeshTriangle& t : a.triangles)
      for (int e = 0; e < 3; ++e)
        if (t[e] < t[(e + 1) % 3]) targets.push_back((a.vertices_mm[t[e]] + a.vertices_mm[t[(e + 1) % 3]]) / 2);
    ASSERT_EQ(targets.size(), 162u + 480u);
    std::mt19937_64 rng(7);
    Crossings c;
    for (int round = 0; round < 80; ++round)
      for (const Vector3d& target : targets) {
        Vector3d dir;
        do dir = random_unit(rng);
        while (dir.dot(target.normalized()) < 0.5);
        const Vector3d o = target + (round % 2 ? 1e5 : 50) * dir;
        c.check(m, o, (target - o).normalized(), target);
      }
    EXPECT_EQ(c.failures, 0) << c.first_failure;
    std::printf("icosphere: %d rays at vertices and edge midpoints, %d failures, %d first hits exactly on an edge\n",
                c.rays, c.failures, c.exact_ties);
  }
  // (b) A cube tessellated on an integer grid, rays with small dyadic direction
  // components through interior vertices and edge midpoints of every face: the
  // sheared coordinates are exact, so every ray passes exactly through the
  // vertex or edge and every hit is decided by the tie rule.
  {
    const int n = 8;
    const TriangleMesh m = flat(grid_cube(n));
    Crossings c;
    for (int axis = 0; axis < 3; ++axis)
      for (int side : {0, n}) {
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        for (int i2 = 1; i2 < 2 * n; ++i2)      // half-grid steps: vertices (even, even),
          for (int j2 = 1; j2 < 2 * n; ++j2) {  // edge midpoints (one odd) and diagonal midpoints (both odd)
            Vector3d target;
            target[axis] = side;
            target[u] = i2 / 2.0;
            target[v] = j2 / 2.0;
            for (int a2 = -3; a2 <= 3; ++a2)
              for (int b2 = -3; b2 <= 3; ++b2) {
                Vector3d d;
                d[axis] = side == 0 ? 1 : -1;  // into the cube
                d[u] = a2 / 8.0;
                d[v] = b2 / 8.0;
                const Vector3d o = target - 4 * d;  // exact
                c.check(m, o, d, target);
              }
          }
      }
    EXPECT_EQ(c.failures, 0) << c.first_failure;
    // Every target is a vertex or on an edge (a square's centre is on its
    // diagonal), and the exact rays hit it exactly: the tie rule decided them all.
    EXPECT_EQ(c.exact_ties, c.rays);
    std::printf("grid cube: %d exact rays at vertices and edge midpoints, %d failures, %d first hits exactly on an "
                "edge or vertex\n",
                c.rays, c.failures, c.exact_ties);
  }
}

TEST(TriangleMesh, RaysTouchingOnlyAnEdgeOrLyingInAFaceDoNotEnter) {
  const int n = 8;
  const TriangleMesh m = flat(grid_cube(n));
  // Through the cube's edge x = 0, z = 0 at y = 4.5 (mid-edge), from the region
  // x < 0, z > 0 into x > 0, z < 0: it only touches the solid (a tangent ray).
  EXPECT_FALSE(intersect(m, Vector3d(-1, 4.5, 1), Vector3d(1, 0, -1).normalized(), 0));
  EXPECT_TRUE(intersect_all(m, Vector3d(-1, 4.5, 1), Vector3d(1, 0, -1).normalized(), 0).empty());
  // Same through the corner vertex (0, 0, 0) from outside the three faces'
  // quadrant and at the grid vertex (0, 4, 0) of the edge: an even number of
  // crossings (a touch is seen as none or as an entry and an exit at one point).
  for (const auto& [o, d] : {std::pair<Vector3d, Vector3d>{Vector3d(-1, 4, 1), Vector3d(1, 0, -1)},
                             std::pair<Vector3d, Vector3d>{Vector3d(-1, -1, 1), Vector3d(1, 1, -1)}}) {
    const auto all = intersect_all(m, o, d, 0);
    EXPECT_EQ(all.size() % 2, 0u);
    for (std::size_t k = 0; k < all.size(); ++k) EXPECT_EQ(all[k].hit.normal.dot(d) < 0, k % 2 == 0);
  }
  // A ray lying in the bottom face z = 0: the face's own triangles are misses;
  // any crossing of the side faces comes in entry/exit pairs.
  for (double y : {0.25, 1.0, 3.5}) {
    const Vector3d o(-2, y, 0), d = Vector3d(1, 0.125, 0).normalized();
    const auto all = intersect_all(m, o, d, 0);
    EXPECT_EQ(all.size() % 2, 0u) << y;
    for (const MeshHit& h : all) EXPECT_NE(std::fabs(h.hit.normal.z()), 1.0) << "a triangle of the face z = 0";
  }
}

TEST(TriangleMesh, ConvergesToTheSphereLikeHSquared) {
  // Rays parallel to z at impact parameter below 0.9 R: the mesh hit against
  // the analytic sphere hit (shapes.h), and the smooth shading normal (exact
  // radial vertex normals, interpolated) against the sphere's normal there.
  // Both errors are second order in the edge length h: the mesh lies within a
  // sagitta ~h^2 / (8 R) of the sphere, and the interpolated radial normal is
  // the direction of the mesh point from the centre. Each level halves h, so
  // successive ratios tend to 4. The band [3.5, 4.6] allows for the sampled
  // maximum (20000 rays) and for the irregular triangles of the coarse levels.
  const double r = 20;
  const Sphere sphere{Vector3d::Zero(), r};
  std::printf("level  triangles  edge_mm  max|p_mesh - p_sphere| mm  ratio  max angle(shading, exact) rad  ratio"
              "  [flat normal rad]  [computed smooth rad]\n");
  double previous_point = 0, previous_angle = 0;
  std::vector<double> point_error, angle_error, computed_error;
  for (int level = 2; level <= 6; ++level) {
    const MeshArrays a = icosphere(level, r);
    MeshArrays computed = a;
    computed.normals.clear();
    const TriangleMesh smooth = build_triangle_mesh(a, {MeshShading::smooth, 60});
    const TriangleMesh own = build_triangle_mesh(computed, {MeshShading::smooth, 60});
    double edge = 0;
    for (const MeshTriangle& t : a.triangles) edge = std::max(edge, (a.vertices_mm[t[0]] - a.vertices_mm[t[1]]).norm());
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(-0.9 * r, 0.9 * r);
    double max_point = 0, max_angle = 0, max_flat = 0, max_own = 0;
    for (int i = 0; i < 20000;) {
      const double x = u(rng), y = u(rng);
      if (x * x + y * y >= 0.81 * r * r) continue;
      ++i;
      const Vector3d o(x, y, -100), d = Vector3d::UnitZ();
      const auto exact = intersect(sphere, o, d, 0);
      const auto mesh = intersect(smooth, o, d, 0);
      const auto mine = intersect(own, o, d, 0);
      ASSERT_TRUE(exact && mesh && mine);
      ASSERT_TRUE(mesh->shading_normal && mine->shading_normal);
      max_point = std::max(max_point, (mesh->point - exact->point).norm());
      auto angle = [](const Vector3d& p, const Vector3d& q) { return std::atan2(p.cross(q).norm(), p.dot(q)); };
      max_angle = std::max(max_angle, angle(*mesh->shading_normal, exact->normal));
      max_flat = std::max(max_flat, angle(mesh->normal, exact->normal));
      max_own = std::max(max_own, angle(*mine->shading_normal, exact->normal));
    }
    std::printf("%5d  %9zu  %7.4f  %26.3e  %5.2f  %30.3e  %5.2f  %17.3e  %21.3e\n", level, a.triangles.size(), edge,
                max_point, previous_point > 0 ? previous_point / max_point : 0.0, max_angle,
                previous_angle > 0 ? previous_angle / max_angle : 0.0, max_flat, max_own);
    point_error.push_back(max_point);
    angle_error.push_back(max_angle);
    computed_error.push_back(max_own);
    previous_point = max_point;
    previous_angle = max_angle;
  }
  for (std::size_t k = 1; k < point_error.size(); ++k) {
    EXPECT_GT(point_error[k - 1] / point_error[k], 3.5) << k + 2;
    EXPECT_LT(point_error[k - 1] / point_error[k], 4.6) << k + 2;
    EXPECT_GT(angle_error[k - 1] / angle_error[k], 3.5) << k + 2;
    EXPECT_LT(angle_error[k - 1] / angle_error[k], 4.6) << k + 2;
  }
  // Level 6 (81920 triangles, longest edge h = 0.41 mm): the mesh is at most a
  // sagitta h^2 / (8 R) = 1.1e-3 mm inside the sphere, which a ray at impact
  // parameter 0.9 R (cosine of incidence 0.44) sees as up to 2.4e-3 mm along
  // itself (measured 3.1e-3: the sagitta bound is for the centre of an
  // equilateral triangle of edge h, the largest icosphere triangles are not
  // equilateral); the normal error is that displacement seen from the centre,
  // 3.1e-3 * 0.9 / 20 = 1.4e-4 rad (measured 1.4e-4). Bounds ~1.3x the measured values.
  EXPECT_LT(point_error.back(), 4e-3);
  EXPECT_LT(angle_error.back(), 2e-4);
  // Computed smooth normals (Max's weights) converge in the same way: exact for
  // vertices on a sphere, so within rounding of the exact-normal column.
  for (std::size_t k = 0; k < computed_error.size(); ++k)
    EXPECT_NEAR(computed_error[k], angle_error[k], 1e-9 + 1e-6 * angle_error[k]) << k + 2;
}

TEST(TriangleMesh, SmoothShadingNormalIsOnTheGeometricSideAndDifferentiable) {
  const TriangleMesh m = build_triangle_mesh(reversed(icosphere(3, 20)), {MeshShading::smooth, 60});
  // Inside-out winding with outward radial normals: the builder reverses the
  // winding and keeps every corner normal on the outward side.
  std::mt19937_64 rng(3);
  for (int i = 0; i < 200; ++i) {
    const Vector3d o = 80 * random_unit(rng), d = (10 * random_unit(rng) - o).normalized();
    const auto h = intersect_mesh(m, o, d, 0);
    ASSERT_TRUE(h);
    ASSERT_TRUE(h->hit.shading_normal);
    EXPECT_NEAR(h->hit.shading_normal->norm(), 1, 1e-15);
    EXPECT_GT(h->hit.shading_normal->dot(h->hit.normal), 0.99);
    EXPECT_GT(h->hit.shading_normal->dot(h->hit.point.normalized()), 1 - 1e-6);
    // d(shading normal)/d(point) against a finite difference along the triangle:
    // the interpolated normal is smooth inside a triangle, so a step of 1e-4 of
    // the edge gives ~1e-8 relative agreement; a sphere's shape operator is
    // (I - n n^T) / R, which the mesh approximates to O(h).
    const MeshTriangle& t = m.triangles()[h->triangle];
    const Vector3d step = 1e-6 * (m.vertices_mm()[t[1]] - m.vertices_mm()[t[0]]);
    const Vector3d b = h->barycentric;
    const auto cn = m.corner_normals(h->triangle);
    auto shading_at = [&](const Vector3d& bary) { return (bary[0] * cn[0] + bary[1] * cn[1] + bary[2] * cn[2]).normalized(); };
    const Vector3d moved = shading_at(b + Vector3d(-1e-6, 1e-6, 0));
    const Vector3d predicted = h->hit.shading_normal.value() + h->hit.dnormal_dpoint * step;
    EXPECT_LT((moved - predicted).norm(), 1e-8 * step.norm() + 1e-15);
    const Eigen::Matrix3d sphere_operator =
        (Eigen::Matrix3d::Identity() - h->hit.normal * h->hit.normal.transpose()) / 20.0;
    EXPECT_LT(((h->hit.dnormal_dpoint - sphere_operator) * step.normalized()).norm(), 0.2 / 20);
  }
}

TEST(TriangleMesh, ComputedNormalsKeepCreasesSharp) {
  // A cube (8 x 8 grid per face): computed smooth normals with the default 60
  // degree crease equal the face normals everywhere (the 90 degree edges stay
  // sharp); with a 180 degree crease the corners are bent.
  const TriangleMesh sharp = build_triangle_mesh(grid_cube(8), {MeshShading::smooth, 60});
  const TriangleMesh round = build_triangle_mesh(grid_cube(8), {MeshShading::smooth, 180});
  double worst_sharp = 0, worst_round = 0;
  for (std::size_t k = 0; k < sharp.triangle_count(); ++k)
    for (int c = 0; c < 3; ++c) {
      worst_sharp = std::max(worst_sharp, (sharp.corner_normals(k)[c] - sharp.triangle_normal(k)).norm());
      worst_round = std::max(worst_round, (round.corner_normals(k)[c] - round.triangle_normal(k)).norm());
    }
  EXPECT_EQ(worst_sharp, 0);
  EXPECT_GT(worst_round, 0.5);
  // Flat faces: the shading normal of a hit in the middle of a face is the face normal.
  const auto h = intersect(round, Vector3d(4.3, 3.7, -10), Vector3d::UnitZ(), 0);
  ASSERT_TRUE(h && h->shading_normal);
  EXPECT_NEAR(h->shading_normal->z(), -1, 1e-15);
}

TEST(TriangleMesh, ContainsByParityAndMargin) {
  const double r = 20;
  const Vector3d centre(5, 6, 7);
  const TriangleMesh m = flat(icosphere(4, r, centre));
  // The level-4 mesh lies between radii 19.97 and 20 mm (sagitta < 0.03 mm).
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.3 * r, 1.3 * r);
  int inside = 0;
  for (int i = 0; i < 5000; ++i) {
    const Vector3d p = centre + Vector3d(u(rng), u(rng), u(rng));
    const double dist = (p - centre).norm();
    if (std::fabs(dist - r) < 0.05) continue;
    EXPECT_EQ(contains(m, p), dist < r) << i;
    inside += dist < r;
    // Margins: inside by more than 1 mm when the distance to the sphere exceeds 1.05 mm.
    if (r - dist > 1.05) {
      EXPECT_TRUE(contains(m, p, 1.0));
    }
    if (dist < r && r - dist < 0.95) {
      EXPECT_FALSE(contains(m, p, 1.0));
    }
    if (dist > r && dist - r < 0.95) {
      EXPECT_TRUE(contains(m, p, -1.0));
    }
    if (dist > r + 1.05) {
      EXPECT_FALSE(contains(m, p, -1.0));
    }
  }
  EXPECT_GT(inside, 1000);
  // Exact points of the grid cube: on a face (distance 0) is not inside.
  const TriangleMesh cube = flat(grid_cube(8));
  EXPECT_TRUE(contains(cube, Vector3d(4, 4, 4)));
  EXPECT_TRUE(contains(cube, Vector3d(0.5, 0.5, 0.5), 0.49));
  EXPECT_FALSE(contains(cube, Vector3d(0.5, 0.5, 0.5), 0.5));
  EXPECT_FALSE(contains(cube, Vector3d(0, 4, 4)));  // on the face x = 0
  EXPECT_FALSE(contains(cube, Vector3d(3, 3, 0)));  // a grid vertex of the face z = 0
  EXPECT_FALSE(contains(cube, Vector3d(-1e-9, 4, 4)));
  EXPECT_TRUE(contains(cube, Vector3d(1e-9, 4, 4)));
  EXPECT_FALSE(contains(TriangleMesh(), Vector3d::Zero()));
}

TEST(TriangleMesh, SpawnRuleLeavesTheSurfaceOnTheRightSide) {
  // Enter, spawn inside (refraction side) and trace with t_min = 0: the next hit
  // is the exit, not the entry triangle or a neighbour; spawn outside
  // (reflection) and trace: nothing (a convex solid). Grazing rays included.
  const TriangleMesh m = flat(icosphere(4, 20, Vector3d(100, -50, 30)));
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(0, 1);
  for (int i = 0; i < 3000; ++i) {
    const Vector3d c(100, -50, 30);
    const Vector3d dir = random_unit(rng);
    // Impact parameters up to 19.9 mm (grazing on the mesh, whose facets reach 19.97 mm).
    Vector3d side = random_unit(rng);
    side = (side - side.dot(dir) * dir).normalized();
    const Vector3d o = c - 200 * dir + 19.9 * std::sqrt(u(rng)) * side;
    const auto in = intersect(m, o, dir, 0);
    if (!in) continue;
    ASSERT_LT(in->normal.dot(dir), 0);
    const Vector3d reflected = dir - 2 * dir.dot(in->normal) * in->normal;
    EXPECT_FALSE(intersect(m, spawn_origin(*in, reflected), reflected, 0)) << i;
    const auto out = intersect(m, spawn_origin(*in, dir), dir, 0);
    ASSERT_TRUE(out) << i;
    EXPECT_GT(out->normal.dot(dir), 0) << i;
    EXPECT_GT(out->t, 0) << i;
    const auto chained = intersect(m, o, dir, in->t);
    ASSERT_TRUE(chained);
    EXPECT_NEAR((chained->point - out->point).norm(), 0, 1e-9) << i;
  }
}

TEST(TriangleMesh, ConcurrentQueriesAgreeWithSerialOnes) {
  const TriangleMesh m = flat(icosphere(4, 20));
  std::vector<Vector3d> origins, directions;
  std::mt19937_64 rng(13);
  for (int i = 0; i < 4000; ++i) {
    origins.push_back(60 * random_unit(rng));
    directions.push_back((15 * random_unit(rng) - origins.back()).normalized());
  }
  std::vector<double> serial(origins.size());
  for (std::size_t i = 0; i < origins.size(); ++i) {
    const auto h = intersect(m, origins[i], directions[i], 0);
    serial[i] = h ? h->t : -1;
  }
  std::vector<double> parallel(origins.size());
  std::vector<std::thread> threads;
  const TriangleMesh copy = m;  // copies share the prepared data
  EXPECT_EQ(copy.data(), m.data());
  for (int w = 0; w < 4; ++w)
    threads.emplace_back([&, w] {
      for (std::size_t i = w; i < origins.size(); i += 4) {
        const auto h = intersect(copy, origins[i], directions[i], 0);
        parallel[i] = h ? h->t : -1;
      }
    });
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(serial, parallel);
}

TEST(TriangleMesh, BoundsScaleAndEmptyMesh) {
  const TriangleMesh m = flat(icosphere(2, 20, Vector3d(-30, 5, 1)));
  const Eigen::AlignedBox3d b = bounds_mm(m);
  EXPECT_NEAR(b.min().x(), -50, 1e-12);
  EXPECT_NEAR(b.max().y(), 25, 1e-12);
  EXPECT_NEAR(scale_mm(m), 50, 1e-12);
  const TriangleMesh none;
  EXPECT_FALSE(intersect(none, Vector3d::Zero(), Vector3d::UnitZ(), 0));
  EXPECT_TRUE(bounds_mm(none).isEmpty());
  EXPECT_EQ(none.triangle_count(), 0u);
}

// Expects std::invalid_argument whose message contains `words`.
void expect_refused(MeshArrays a, const std::string& words, MeshShading shading = MeshShading::flat) {
  try {
    (void)build_triangle_mesh(std::move(a), {shading, 60});
    ADD_FAILURE() << "accepted; expected: " << words;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << "one line";
  }
}

TEST(TriangleMesh, RefusesOpenInconsistentDegenerateAndBadInput) {
  const MeshArrays good = icosphere(1);
  EXPECT_NO_THROW(flat(good));

  MeshArrays open = good;
  open.triangles.pop_back();
  expect_refused(open, "the mesh is open");
  expect_refused(open, "(3 edges of a single triangle)");

  MeshArrays inconsistent = good;
  std::swap(inconsistent.triangles[5][1], inconsistent.triangles[5][2]);
  expect_refused(inconsistent, "inconsistent orientation");

  MeshArrays degenerate = good;  // move a vertex onto the midpoint of two neighbours of one of its triangles
  const MeshTriangle t = degenerate.triangles[0];
  degenerate.vertices_mm[t[0]] = (degenerate.vertices_mm[t[1]] + degenerate.vertices_mm[t[2]]) / 2;
  expect_refused(degenerate, "is degenerate: zero area");
  MeshArrays repeated = good;
  repeated.triangles[3][1] = repeated.triangles[3][0];
  expect_refused(repeated, "triangle 3");

  MeshArrays nan = good;
  nan.vertices_mm[4].y() = NAN;
  expect_refused(nan, "vertex 4 is not finite");
  MeshArrays range = good;
  range.triangles[2][2] = 9999;
  expect_refused(range, "refers to vertex 9999");
  expect_refused(MeshArrays{}, "no triangles");

  // Two tetrahedra glued along one edge: that edge has four triangles.
  MeshArrays glued;
  glued.vertices_mm = {{0, 0, 0}, {0, 0, 1}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
  glued.triangles = {{0, 2, 3}, {0, 1, 2}, {1, 3, 2}, {0, 3, 1}, {0, 4, 5}, {0, 1, 4}, {1, 5, 4}, {0, 5, 1}};
  expect_refused(glued, "not a manifold");

  MeshArrays normals = good;
  normals.normals.pop_back();
  expect_refused(normals, "vertex normals for", MeshShading::smooth);
  normals = good;
  normals.normals[0] = Vector3d::Zero();
  expect_refused(normals, "normal 0 is zero", MeshShading::smooth);
  EXPECT_THROW((void)build_triangle_mesh(good, {MeshShading::smooth, 0}), std::invalid_argument);
}

}  // namespace
}  // namespace glasspiv
