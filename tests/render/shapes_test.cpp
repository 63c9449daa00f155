// Tests of render/shapes.h: intersections against closed forms (line-sphere
// chord, slab planes, cylinder radius), tangent rays, and the self-intersection
// rule (spawn_origin) on grazing hits where a naive offset fails.
#include "render/shapes.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <optional>
#include <random>

#include "render/optics.h"

namespace glasspiv {
namespace {

using Eigen::Vector3d;

TEST(Sphere, AxialRayHitsAtClosedForm) {
  // Ray along +z at height x towards a sphere of radius R at the origin:
  // entry t = z0 - sqrt(R^2 - x^2) from z0 before the centre.
  const Sphere s{Vector3d(0, 0, 0), 20.0};
  for (double x : {0.0, 5.0, 19.0}) {
    const auto h = intersect(s, Vector3d(x, 0, -100), Vector3d(0, 0, 1), 0.0);
    ASSERT_TRUE(h);
    EXPECT_NEAR(h->t, 100 - std::sqrt(400 - x * x), 1e-12);
    EXPECT_NEAR(h->normal.norm(), 1.0, 1e-15);
    EXPECT_LT(h->normal.dot(Vector3d(0, 0, 1)), 0);  // entering: outward normal faces the ray
    EXPECT_NEAR((h->point - s.centre_mm).norm(), 20.0, 1e-13);
  }
  // From inside: the exit, normal along the ray.
  const auto h = intersect(s, Vector3d(0, 0, 0), Vector3d(0, 0, 1), 0.0);
  ASSERT_TRUE(h);
  EXPECT_NEAR(h->t, 20.0, 1e-13);
  EXPECT_GT(h->normal.z(), 0);
}

TEST(Sphere, TangentRayIsAMissAndNeverNaN) {
  const Sphere s{Vector3d(0, 0, 0), 20.0};
  EXPECT_FALSE(intersect(s, Vector3d(20, 0, -100), Vector3d(0, 0, 1), 0.0));  // exactly tangent
  EXPECT_FALSE(intersect(s, Vector3d(20.000001, 0, -100), Vector3d(0, 0, 1), 0.0));
  // Grazing, impact parameter R (1 - 1e-12): two hits 2 R sqrt(2e-12) apart
  // (half chord sqrt(R^2 - b^2)); the stable roots keep them to ~1e-16 R / sqrt(2e-12).
  const double b = 20.0 * (1 - 1e-12);
  const auto h = intersect(s, Vector3d(b, 0, -100), Vector3d(0, 0, 1), 0.0);
  ASSERT_TRUE(h);
  const double half_chord = std::sqrt((20.0 - b) * (20.0 + b));
  EXPECT_TRUE(h->point.allFinite());
  EXPECT_NEAR(h->t, 100 - half_chord, 1e-11);
  const auto h2 = intersect(s, h->point + 1e-9 * Vector3d(0, 0, 1), Vector3d(0, 0, 1), 0.0);
  ASSERT_TRUE(h2);
  EXPECT_NEAR(h2->point.z(), half_chord, 1e-11);
}

TEST(Sphere, FarFromOriginStillAccurate) {
  // Centre 1e4 mm away, ray origin 1e4 mm away on the other side: the hit is
  // reprojected onto the sphere, |p - c| = R to a few ulp of 1e4.
  const Sphere s{Vector3d(1e4, -3e3, 2e3), 0.5};
  const Vector3d o(-1e4, 1e3, 0);
  const Vector3d d = (s.centre_mm + Vector3d(0.1, 0.2, -0.3) - o).normalized();
  const auto h = intersect(s, o, d, 0.0);
  ASSERT_TRUE(h);
  EXPECT_NEAR((h->point - s.centre_mm).norm(), 0.5, 1e-11);
  EXPECT_LT(h->error_mm, 1e-9);
}

// The self-intersection rule: from a hit, the reflected ray spawned outside a
// convex solid never meets it again, and the refracted (or internally
// reflected) ray spawned inside meets it next at the far end of its chord,
// 2 R |d . n| away, never at t ~ 0. Spheres far from the origin, hit at
// grazing angles down to impact parameters R (1 - 1e-12).
// sphere_hit_t skips the division where the root it gives cannot be the
// answer; the answer stays that of both roots sorted, to the bit, from inside,
// outside, moving away, grazing, and with t_min 0 and above.
TEST(Sphere, HitTIsTheNearestRootAboveTMinToTheBit) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  const Sphere s{Vector3d(3, -2, 40), 20};
  int hits = 0, inside = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vector3d o = s.centre_mm + Vector3d(u(rng), u(rng), u(rng)) * (i % 2 ? 25.0 : 19.0);
    const Vector3d d = Vector3d(u(rng), u(rng), u(rng)).normalized();
    const double t_min = i % 3 == 0 ? 0.0 : std::abs(u(rng)) * 5;
    // The reference: both roots of sphere_roots' form, the nearer one above t_min.
    const Vector3d f = o - s.centre_mm;
    const double b = f.dot(d), l = (f - b * d).norm(), disc = (s.radius_mm - l) * (s.radius_mm + l);
    std::optional<double> expected;
    if (disc > 0) {
      const double q = -(b + std::copysign(std::sqrt(disc), b));
      const double c = f.squaredNorm() - s.radius_mm * s.radius_mm;
      double t0 = q, t1 = q != 0 ? c / q : -q;
      if (t0 > t1) std::swap(t0, t1);
      const double t = t0 > t_min ? t0 : t1;
      if (t > t_min) expected = t;
    }
    const std::optional<double> got = sphere_hit_t(s, o, d, t_min);
    ASSERT_EQ(got.has_value(), expected.has_value()) << i;
    if (!got) continue;
    EXPECT_EQ(*got, *expected) << i;
    ++hits;
    inside += f.norm() < s.radius_mm;
  }
  EXPECT_GT(hits, 5000);
  EXPECT_GT(inside, 2000);
}

// A sphere's hit gives its shape operator I / R as the scalar 1 / R, and the
// tracer's scaling of a differential by it gives exactly the values of the
// 3 x 3 product it replaces (its other terms are zeros), negative values, tiny
// and huge ones included.
TEST(Sphere, UmbilicCurvatureScalesToTheBitsOfTheMatrix) {
  const Sphere s{Vector3d(1, -2, 3), 7.3};
  const auto h = intersect(s, Vector3d(0.4, 0.2, -50), Vector3d(0, 0, 1), 0.0);
  ASSERT_TRUE(h);
  ASSERT_TRUE(h->umbilic_curvature_per_mm);
  EXPECT_EQ(*h->umbilic_curvature_per_mm, 1.0 / 7.3);
  EXPECT_TRUE(h->dnormal_dpoint.isZero());
  Eigen::Matrix3d as_matrix = Eigen::Matrix3d::Zero();
  as_matrix.diagonal().setConstant(*h->umbilic_curvature_per_mm);
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> mantissa(-1, 1);
  std::uniform_int_distribution<int> exponent(-300, 300);
  for (int trial = 0; trial < 2000; ++trial) {
    Eigen::Matrix<double, 3, 2> dpoint;
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 3; ++i) dpoint(i, j) = std::ldexp(mantissa(rng), exponent(rng));
    const Eigen::Matrix<double, 3, 2> product = as_matrix * dpoint;
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 3; ++i)
        ASSERT_EQ(*h->umbilic_curvature_per_mm * dpoint(i, j), product(i, j)) << trial;
  }
}

TEST(SpawnOrigin, NoSelfHitOnGrazingSphereHits) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  const double n_glass = 1.5195;
  int checked = 0;
  for (const Vector3d& centre : {Vector3d(0, 0, 0), Vector3d(350, -120, 800), Vector3d(-3e3, 2e3, 5e3)}) {
    for (double radius : {0.05, 1.0, 20.0, 300.0}) {
      const Sphere s{centre, radius};
      for (double eps : {1e-1, 1e-4, 1e-8, 1e-10, 1e-12}) {
        for (int k = 0; k < 20; ++k) {
          const Vector3d d = Vector3d(u(rng), u(rng), u(rng)).normalized();
          Vector3d side = d.cross(Vector3d(u(rng), u(rng), u(rng))).normalized();
          const Vector3d o = centre - 1000 * d + radius * (1 - eps) * side;
          const auto h = intersect(s, o, d, 0.0);
          if (!h) continue;  // the impact parameter rounded to >= R: a miss is allowed
          ASSERT_TRUE(h->point.allFinite());
          // Reflection from outside.
          const Vector3d r = reflect(d, h->normal);
          const auto again = intersect(s, spawn_origin(*h, r), r, 0.0);
          EXPECT_FALSE(again) << "reflected ray re-hit at t=" << again->t << " eps=" << eps << " R=" << radius;
          // Refraction into the sphere: next hit is the far end of the chord.
          const auto t_dir = refract(d, h->normal, 1.0 / n_glass);
          ASSERT_TRUE(t_dir);
          const auto inner = intersect(s, spawn_origin(*h, *t_dir), *t_dir, 0.0);
          ASSERT_TRUE(inner);
          const double chord = 2 * radius * std::abs(t_dir->dot(h->normal));
          EXPECT_NEAR(inner->t, chord, 1e-9 * (radius + centre.norm()));
          EXPECT_GT(inner->normal.dot(*t_dir), 0);  // leaving
          // Internal reflection at the exit: again a full chord (sphere symmetry).
          const Vector3d r2 = reflect(*t_dir, inner->normal);
          const auto inner2 = intersect(s, spawn_origin(*inner, r2), r2, 0.0);
          ASSERT_TRUE(inner2);
          EXPECT_NEAR(inner2->t, chord, 1e-9 * (radius + centre.norm()));
          // Refraction out of the sphere: leaves for good.
          const auto out = refract(*t_dir, inner->normal, n_glass);
          ASSERT_TRUE(out);
          EXPECT_FALSE(intersect(s, spawn_origin(*inner, *out), *out, 0.0));
          ++checked;
        }
      }
    }
  }
  EXPECT_GT(checked, 1000);
}

// The same rule on a rotated box and a cylinder far from the origin, hit in the
// middle of a face at grazing angles (1 - cos down to 1e-12 of the tangent):
// the reflected ray never re-hits, the refracted ray leaves through another
// point at least 0.1 mm on (the faces are >= 2 mm from the hit point).
TEST(SpawnOrigin, NoSelfHitOnGrazingBoxAndCylinderHits) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  Box box;
  box.centre_mm = Vector3d(420, -310, 1250);
  box.world_from_box = Eigen::AngleAxisd(0.7, Vector3d(3, -1, 2).normalized()).toRotationMatrix();
  box.half_extent_mm = Vector3d(40, 30, 5);
  Cylinder cyl;
  cyl.centre_mm = Vector3d(-800, 90, 600);
  cyl.axis = Vector3d(1, 1, 1).normalized();
  cyl.radius_mm = 12;
  cyl.half_length_mm = 60;
  int checked = 0;
  for (int which = 0; which < 2; ++which) {
    const Shape shape = which == 0 ? Shape(box) : Shape(cyl);
    for (double eps : {1e-1, 1e-4, 1e-8, 1e-12}) {
      for (int k = 0; k < 50; ++k) {
        Vector3d p, n;
        if (which == 0) {  // a point in the middle of the top face (+z in the box frame)
          p = box.centre_mm + box.world_from_box * Vector3d(20 * u(rng), 15 * u(rng), 5);
          n = box.world_from_box.col(2);
        } else {  // a point in the middle of the side
          const Vector3d radial = cyl.axis.cross(Vector3d(u(rng), u(rng), u(rng))).normalized();
          p = cyl.centre_mm + 30 * u(rng) * cyl.axis + 12 * radial;
          n = radial;
        }
        const Vector3d tangent = n.cross(Vector3d(u(rng), u(rng), u(rng))).normalized();
        const Vector3d d = (tangent - std::sqrt(eps) * n).normalized();  // 1 - cos(angle to tangent) ~ eps / 2
        const auto h = intersect(shape, p - 50 * d, d, 0.0);
        if (!h || (h->point - p).norm() > 1e-6) continue;  // entered elsewhere (a cap or an edge first)
        const Vector3d r = reflect(d, h->normal);
        const auto again = intersect(shape, spawn_origin(*h, r), r, 0.0);
        EXPECT_FALSE(again) << which << " eps=" << eps << " t=" << again->t;
        const auto t_dir = refract(d, h->normal, 1.0 / 1.5);
        ASSERT_TRUE(t_dir);
        const auto inner = intersect(shape, spawn_origin(*h, *t_dir), *t_dir, 0.0);
        ASSERT_TRUE(inner);
        EXPECT_GT(inner->t, 0.1);
        EXPECT_GT(inner->normal.dot(*t_dir), 0);
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 200);
}

TEST(SpawnOrigin, TangentDirectionGoesToTheRequestedSide) {
  Hit h;
  h.point = Vector3d(1, 0, 0);
  h.normal = Vector3d(1, 0, 0);
  h.error_mm = 1e-12;
  EXPECT_GT(spawn_origin(h, Vector3d(0, 1, 0), true).x(), 1.0);
  EXPECT_LT(spawn_origin(h, Vector3d(0, 1, 0), false).x(), 1.0);
  EXPECT_LT(spawn_origin(h, Vector3d(-1, 0, 0)).x(), 1.0);
}

TEST(Box, RotatedBoxHitsItsFaces) {
  Box b;
  b.centre_mm = Vector3d(10, 20, 30);
  b.world_from_box = Eigen::AngleAxisd(0.4, Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  b.half_extent_mm = Vector3d(2, 3, 4);
  // A ray along the box's local -z axis from outside hits the +z face at distance L - 4.
  const Vector3d ez = b.world_from_box.col(2);
  const Vector3d o = b.centre_mm + 50 * ez + 0.5 * b.world_from_box.col(0);
  const auto h = intersect(b, o, -ez, 0.0);
  ASSERT_TRUE(h);
  EXPECT_NEAR(h->t, 46.0, 1e-12);
  EXPECT_NEAR((h->normal - ez).norm(), 0, 1e-15);
  // Continue inside: exit at the -z face, 8 mm on.
  const auto h2 = intersect(b, spawn_origin(*h, -ez), -ez, 0.0);
  ASSERT_TRUE(h2);
  EXPECT_NEAR(h2->t, 8.0, 1e-11);
  EXPECT_NEAR((h2->normal + ez).norm(), 0, 1e-15);
  // A ray touching only an edge, or lying in a face plane, misses.
  Box a;
  a.half_extent_mm = Vector3d(1, 1, 1);
  EXPECT_FALSE(intersect(a, Vector3d(-5, 1, 1), Vector3d(1, 0, 0), 0.0));  // along an edge
  EXPECT_FALSE(intersect(a, Vector3d(-5, 0, 1), Vector3d(1, 0, 0), 0.0));  // in the z = 1 face plane
  EXPECT_FALSE(intersect(a, Vector3d(-3, 0, -1), Vector3d(1, 0, 1).normalized(), 0.0));  // grazing an edge
}

TEST(Box, SlabFaces) {
  // A slab of thickness 6 normal to (0, 0, 1): planes z = +-3.
  const Box slab = make_slab(Vector3d(0, 0, 0), Vector3d(0, 0, 1), 6.0, 1000.0);
  const Vector3d d = Vector3d(std::sin(1.2), 0, std::cos(1.2));
  const auto h = intersect(slab, Vector3d(0, 0, -10), d, 0.0);
  ASSERT_TRUE(h);
  EXPECT_NEAR(h->point.z(), -3.0, 1e-14);
  EXPECT_NEAR(h->point.x(), 7 * std::tan(1.2), 1e-12);
}

TEST(Cylinder, SideCapsAndTangent) {
  Cylinder c;
  c.centre_mm = Vector3d(1, 2, 3);
  c.axis = Vector3d(0, 1, 0);
  c.radius_mm = 5;
  c.half_length_mm = 10;
  // Side: ray along x at axial offset 2, radial offset z = 3: entry at x = 1 - 4.
  auto h = intersect(c, Vector3d(-50, 4, 6), Vector3d(1, 0, 0), 0.0);
  ASSERT_TRUE(h);
  EXPECT_NEAR(h->point.x(), 1 - 4.0, 1e-12);
  EXPECT_NEAR(h->normal.dot(Vector3d(-0.8, 0, 0.6)), 1.0, 1e-12);
  // Cap: ray along -y from above hits the top cap y = 12.
  h = intersect(c, Vector3d(2, 40, 4), Vector3d(0, -1, 0), 0.0);
  ASSERT_TRUE(h);
  EXPECT_NEAR(h->point.y(), 12.0, 1e-13);
  EXPECT_NEAR((h->normal - Vector3d(0, 1, 0)).norm(), 0, 1e-15);
  // From inside along the axis: exits through the bottom cap.
  h = intersect(c, Vector3d(1, 2, 3), Vector3d(0, -1, 0), 0.0);
  ASSERT_TRUE(h);
  EXPECT_NEAR(h->t, 10.0, 1e-13);
  // Tangent to the side: miss; beyond the caps: miss.
  EXPECT_FALSE(intersect(c, Vector3d(-50, 2, 8), Vector3d(1, 0, 0), 0.0));
  EXPECT_FALSE(intersect(c, Vector3d(-50, 12.5, 3), Vector3d(1, 0, 0), 0.0));
}

TEST(FirstHit, NearestOverShapesWithIndex) {
  const std::vector<Shape> shapes = {Sphere{Vector3d(0, 0, 50), 5}, Sphere{Vector3d(0, 0, 20), 5},
                                     make_slab(Vector3d(0, 0, 100), Vector3d(0, 0, 1), 2, 50)};
  const auto h = first_hit(shapes, Vector3d(0, 0, 0), Vector3d(0, 0, 1), 0.0);
  ASSERT_TRUE(h);
  EXPECT_EQ(h->shape_index, 1);
  EXPECT_NEAR(h->t, 15.0, 1e-13);
  EXPECT_FALSE(first_hit(shapes, Vector3d(0, 0, 0), Vector3d(0, 0, -1), 0.0));
  // A skipped shape is not tested: the next one behind it is the nearest.
  const auto behind = first_hit(shapes, Vector3d(0, 0, 0), Vector3d(0, 0, 1), 0.0, 1);
  ASSERT_TRUE(behind);
  EXPECT_EQ(behind->shape_index, 0);
  EXPECT_NEAR(behind->t, 45.0, 1e-13);
  EXPECT_TRUE(contains(shapes[0], Vector3d(0, 0, 52)));
  EXPECT_FALSE(contains(shapes[0], Vector3d(0, 0, 56)));
  EXPECT_TRUE(contains(shapes[2], Vector3d(40, -40, 100.5)));
}

}  // namespace
}  // namespace glasspiv
