// Tests of render/path_tracer.h against closed forms: energy bookkeeping, the
// plane-parallel slab shift and its ghost images, the ball-lens focal length,
// the critical angle, Fresnel transmittance products, Beer-Lambert, and the
// edge cases of the geometry (grazing and tangent rays, origins on surfaces,
// touching spheres, the sheet cutting through a solid).
#include "render/path_tracer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>

namespace glasspiv {
namespace {

using Eigen::Vector3d;
constexpr double kPi = 3.14159265358979323846;
constexpr double kNBk7 = 1.5195;  // N-BK7 at 532 nm (relative to air), the brief's figure

// Normal-incidence Fresnel reflectance ((n1 - n2) / (n1 + n2))^2.
double r_normal(double n1, double n2) { return std::pow((n1 - n2) / (n1 + n2), 2); }

// Unpolarised Fresnel reflectance from the textbook (Hecht) angle forms,
// evaluated independently of render/optics: theta_i from the normal.
double r_unpolarized(double theta_i, double n1, double n2) {
  const double st = n1 / n2 * std::sin(theta_i);
  const double ci = std::cos(theta_i), ct = std::sqrt(1 - st * st);
  const double rs = (n1 * ci - n2 * ct) / (n1 * ci + n2 * ct);
  const double rp = (n2 * ci - n1 * ct) / (n2 * ci + n1 * ct);
  return 0.5 * (rs * rs + rp * rp);
}

// A sheet in the plane z = z0 (s = x, t = y), wide enough to catch everything.
SheetPlane sheet_z(double z0, double extent = 1e7) {
  SheetPlane s;
  s.origin_mm = Vector3d(0, 0, z0);
  s.s_axis = Vector3d::UnitX();
  s.t_axis = Vector3d::UnitY();
  s.extent_s_mm = s.extent_t_mm = extent;
  return s;
}

TraceSolid glass(const Shape& shape, double n, double alpha = 0) { return {shape, TraceMaterial::glass(n, alpha)}; }

// Invariants of every result: finite numbers, unit weight accounted for.
void expect_sane(const TraceResult& r, double tol = 1e-12) {
  EXPECT_NEAR(r.terminal_weight_sum(), 1.0, tol);
  for (const auto& c : r.crossings) {
    EXPECT_TRUE(std::isfinite(c.s_mm) && std::isfinite(c.t_mm) && std::isfinite(c.weight));
    EXPECT_TRUE(c.point_mm.allFinite() && c.direction.allFinite());
    EXPECT_GE(c.weight, 0);
  }
  for (const auto& b : r.background) EXPECT_TRUE(b.direction.allFinite() && std::isfinite(b.weight));
}

// With the sheet beyond every solid, each branch that escapes towards it and
// meets it inside its extent crosses it exactly once, and no other branch does:
// a crossing lost or counted twice shows up as a difference between these
// sums. (A branch leaving nearly parallel to the sheet meets its plane far
// outside even a 1e7 mm sheet: it is background, not a crossing.)
double forward_background_weight(const TraceResult& r, const SheetPlane& sheet) {
  const Vector3d n = sheet.normal();
  double w = 0;
  for (const auto& b : r.background) {
    const double dn = b.direction.dot(n);
    if (!(dn > 0)) continue;
    const Vector3d x = b.from_mm + ((sheet.origin_mm - b.from_mm).dot(n) / dn) * b.direction;
    const Vector3d rel = x - sheet.origin_mm;
    if (std::abs(rel.dot(sheet.s_axis)) <= 0.5 * sheet.extent_s_mm &&
        std::abs(rel.dot(sheet.t_axis)) <= 0.5 * sheet.extent_t_mm)
      w += b.weight;
  }
  return w;
}
double crossing_weight(const TraceResult& r) {
  double w = 0;
  for (const auto& c : r.crossings) w += c.weight;
  return w;
}

TEST(PathTracer, LosslessSceneConservesWeight) {
  // Touching spheres (a packing row), a slab and a cylinder, all lossless; the
  // sheet at z = 500 beyond them. Random camera rays from z = -300.
  TraceScene scene;
  scene.fluid_index = 1.3334;  // water
  for (int i = -2; i <= 2; ++i) scene.solids.push_back(glass(Sphere{Vector3d(20.0 * i, 0, 0), 10}, kNBk7));
  scene.solids.push_back(glass(make_slab(Vector3d(0, 0, 60), Vector3d(0.1, 0, 1).normalized(), 8, 200), kNBk7));
  Cylinder cyl;
  cyl.centre_mm = Vector3d(0, 30, 20);
  cyl.axis = Vector3d(1, 0, 0);
  cyl.radius_mm = 6;
  cyl.half_length_mm = 50;
  scene.solids.push_back(glass(cyl, 1.49));
  scene.sheet = sheet_z(500);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  double max_sum_err = 0, max_cross_err = 0;
  long branches = 0;
  for (int k = 0; k < 400; ++k) {
    // One draw per statement: the order of a call's arguments is unspecified
    // (GCC and clang differ), and the rays must not depend on the compiler.
    const double ox = u(rng), oy = u(rng);
    const double tx = u(rng), ty = u(rng), tz = u(rng);
    const Vector3d o(ox * 5, oy * 5, -300);
    const Vector3d target(tx * 55, ty * 40, tz * 15);
    TraceOptions opt;
    opt.min_weight = 1e-6;
    const TraceResult r = trace_ray(scene, o, target - o, opt);
    expect_sane(r);
    branches += r.counts.branches_traced;
    max_sum_err = std::max(max_sum_err, std::abs(r.terminal_weight_sum() - 1));
    const double cross_err = std::abs(crossing_weight(r) - forward_background_weight(r, scene.sheet));
    max_cross_err = std::max(max_cross_err, cross_err);
    EXPECT_LT(cross_err, 1e-12);
    EXPECT_EQ(r.absorbed_weight, 0);
    EXPECT_LT(r.cut_by_weight_weight + r.cut_by_depth_weight, 1e-3);
  }
  std::printf("[ figures  ] weight sum: max |sum - 1| = %.3g; max |crossings - forward background| = %.3g; "
              "%ld branches for 400 rays\n",
              max_sum_err, max_cross_err, branches);
}

TEST(PathTracer, SlabLateralShiftClosedForm) {
  // Plane-parallel plate of thickness d, relative index n: the emergent ray is
  // parallel to the incident one and displaced by
  //   delta = d sin(theta) (1 - cos(theta) / sqrt(n^2 - sin^2(theta)))
  // perpendicular to the rays; on the sheet z = 50 that is delta / cos(theta)
  // in s. Round-off of ~1e3 mm coordinates is ~1e-13 mm; 1e-9 mm is the brief's bound.
  const double d = 10, n = 1.5;
  TraceScene scene;
  scene.solids.push_back(glass(make_slab(Vector3d(0, 0, 0), Vector3d(0, 0, 1), d, 1e4), n));
  scene.sheet = sheet_z(50);
  TraceOptions opt;
  opt.reflections = false;
  double max_err = 0;
  for (double deg : {0.0, 1.0, 10.0, 30.0, 45.0, 60.0, 70.0, 75.0, 80.0}) {
    const double th = deg * kPi / 180;
    const Vector3d o(-3, 2, -100), dir(std::sin(th), 0, std::cos(th));
    const TraceResult r = trace_ray(scene, o, dir, opt);
    expect_sane(r);
    ASSERT_EQ(r.crossings.size(), 1u) << deg;
    const auto& c = r.crossings[0];
    EXPECT_EQ(c.tag, CrossingTag::refracted_only);
    EXPECT_EQ(c.depth, 2);
    const double s_straight = o.x() + 150 * std::tan(th);
    const double shift = (s_straight - c.s_mm) * std::cos(th);
    const double expected = d * std::sin(th) * (1 - std::cos(th) / std::sqrt(n * n - std::sin(th) * std::sin(th)));
    EXPECT_NEAR(shift, expected, 1e-9) << deg;
    EXPECT_NEAR(c.t_mm, 2.0, 1e-12);
    max_err = std::max(max_err, std::abs(shift - expected));
    // Weight: two transmissions at the same angle pair, (1 - R)^2.
    const double R = r_unpolarized(th, 1.0, n);
    EXPECT_NEAR(c.weight, (1 - R) * (1 - R), 1e-14);
  }
  std::printf("[ figures  ] slab shift: max error %.3g mm over 0..80 deg\n", max_err);
}

TEST(PathTracer, SlabGhostImagesClosedForm) {
  // With reflections, each extra double reflection inside the plate adds a
  // ghost shifted by 2 d tan(theta_t) along the plate (that is 2 d tan(theta_t)
  // cos... in s: the ghost exits 2 d tan(theta_t) further in x and travels
  // parallel), with weight (1 - R)^2 R^(2k) (Stokes: R is the same from either side).
  const double d = 10, n = 1.5, th = 45 * kPi / 180;
  TraceScene scene;
  scene.solids.push_back(glass(make_slab(Vector3d(0, 0, 0), Vector3d(0, 0, 1), d, 1e4), n));
  scene.sheet = sheet_z(50);
  TraceOptions opt;
  opt.min_weight = 1e-12;
  const TraceResult r = trace_ray(scene, Vector3d(0, 0, -100), Vector3d(std::sin(th), 0, std::cos(th)), opt);
  expect_sane(r);
  const double R = r_unpolarized(th, 1.0, n);
  const double th_t = std::asin(std::sin(th) / n);
  const SheetCrossing* main = nullptr;
  for (const auto& c : r.crossings)
    if (c.tag == CrossingTag::refracted_only) {
      ASSERT_EQ(main, nullptr) << "the direct transmitted path crosses once";
      main = &c;
    }
  ASSERT_NE(main, nullptr);
  for (int k = 1; k <= 2; ++k) {
    int found = 0;
    for (const auto& c : r.crossings) {
      if (c.tag != CrossingTag::with_reflections || c.depth != 2 + 2 * k) continue;
      EXPECT_NEAR(c.s_mm - main->s_mm, 2 * k * d * std::tan(th_t), 1e-9);
      EXPECT_NEAR(c.weight, (1 - R) * (1 - R) * std::pow(R, 2 * k), 1e-15);
      ++found;
    }
    EXPECT_EQ(found, 1) << k;
  }
}

TEST(PathTracer, ReflectedCutOffStopsGhostsOnly) {
  // The slab's ghosts again, with reflected branches cut below 1e-4: at 45
  // degrees R = 0.050, so the first ghost (weight (1 - R)^2 R^2 = 2.3e-3, its
  // parent (1 - R) R^2) is kept and the second (its parent (1 - R) R^4 = 6e-6)
  // is not; the transmitted path and the bookkeeping are untouched.
  const double d = 10, n = 1.5, th = 45 * kPi / 180;
  TraceScene scene;
  scene.solids.push_back(glass(make_slab(Vector3d(0, 0, 0), Vector3d(0, 0, 1), d, 1e4), n));
  scene.sheet = sheet_z(50);
  const Vector3d origin(0, 0, -100), dir(std::sin(th), 0, std::cos(th));
  TraceOptions all;
  all.min_weight = 1e-12;
  TraceOptions cut = all;
  cut.min_weight_reflected = 1e-4;
  const TraceResult full = trace_ray(scene, origin, dir, all);
  const TraceResult r = trace_ray(scene, origin, dir, cut);
  expect_sane(r);
  const double R = r_unpolarized(th, 1.0, n);
  auto find = [](const TraceResult& res, CrossingTag tag, int depth) -> const SheetCrossing* {
    for (const auto& c : res.crossings)
      if (c.tag == tag && c.depth == depth) return &c;
    return nullptr;
  };
  const SheetCrossing* main = find(r, CrossingTag::refracted_only, 2);
  const SheetCrossing* main_full = find(full, CrossingTag::refracted_only, 2);
  ASSERT_TRUE(main && main_full);
  EXPECT_EQ(main->s_mm, main_full->s_mm);
  EXPECT_EQ(main->weight, main_full->weight);
  const SheetCrossing* ghost1 = find(r, CrossingTag::with_reflections, 4);
  ASSERT_NE(ghost1, nullptr);
  EXPECT_NEAR(ghost1->weight, (1 - R) * (1 - R) * R * R, 1e-15);
  EXPECT_EQ(find(r, CrossingTag::with_reflections, 6), nullptr);
  ASSERT_NE(find(full, CrossingTag::with_reflections, 6), nullptr);
  EXPECT_LT(r.counts.branches_traced, full.counts.branches_traced);
  EXPECT_GT(r.counts.cut_by_weight, 0);
  // Everything below the reflected cut-off is in the cut bin.
  EXPECT_GE(r.cut_by_weight_weight, (1 - R) * std::pow(R, 4) * (1 - 1e-9));
  // At or below min_weight it changes nothing.
  TraceOptions same = all;
  same.min_weight_reflected = all.min_weight;
  const TraceResult r_same = trace_ray(scene, origin, dir, same);
  ASSERT_EQ(r_same.crossings.size(), full.crossings.size());
  for (std::size_t i = 0; i < full.crossings.size(); ++i) {
    EXPECT_EQ(r_same.crossings[i].s_mm, full.crossings[i].s_mm);
    EXPECT_EQ(r_same.crossings[i].weight, full.crossings[i].weight);
  }
  EXPECT_EQ(r_same.counts.branches_traced, full.counts.branches_traced);
}

TEST(PathTracer, BallLensFocalLength) {
  // Ball lens of diameter D and index n in air: EFL = n D / (4 (n - 1)) from
  // the centre. Rays parallel to the axis at height h cross it at EFL minus the
  // spherical aberration, which grows as h^2: at h = 0.01 R the relative
  // difference is ~1e-5; Richardson extrapolation from h and 2h removes the
  // h^2 term. The sheet is the plane x = 0, which contains the axis.
  const double D = 40, n = kNBk7;
  TraceScene scene;
  scene.solids.push_back(glass(Sphere{Vector3d(0, 0, 0), D / 2}, n));
  scene.sheet.origin_mm = Vector3d::Zero();
  scene.sheet.s_axis = Vector3d::UnitZ();
  scene.sheet.t_axis = Vector3d::UnitY();
  scene.sheet.extent_s_mm = scene.sheet.extent_t_mm = 1e4;
  TraceOptions opt;
  opt.reflections = false;
  auto focus = [&](double h) {
    const TraceResult r = trace_ray(scene, Vector3d(h, 0, -100), Vector3d(0, 0, 1), opt);
    expect_sane(r);
    EXPECT_EQ(r.crossings.size(), 1u);
    EXPECT_EQ(r.crossings.at(0).tag, CrossingTag::refracted_only);
    return r.crossings.at(0).s_mm;
  };
  const double efl = n * D / (4 * (n - 1));
  const double h = 0.01 * D / 2;
  const double f1 = focus(h), f2 = focus(2 * h);
  const double f0 = (4 * f1 - f2) / 3;
  EXPECT_NEAR(f1, efl, 5e-3 * efl);
  EXPECT_NEAR(f1, efl, 1e-4 * efl);
  EXPECT_NEAR(f0, efl, 1e-8 * efl);
  std::printf("[ figures  ] ball lens: EFL %.12f mm, traced at h=0.01R %.12f (rel err %.3g), "
              "Richardson h->0 %.12f (rel err %.3g); BFL %.6f mm\n",
              efl, f1, (f1 - efl) / efl, f0, (f0 - efl) / efl, f1 - D / 2);
}

TEST(PathTracer, TotalInternalReflectionSwitchesAtTheCriticalAngle) {
  // Ray inside a glass plate (n = 1.5, air outside) meeting the top face at
  // theta: beyond asin(1/n) all of it is reflected; 1e-9 rad below, a grazing
  // refracted branch leaves with weight 1 - R(theta) (Fresnel, Hecht's forms).
  const double n = 1.5, thc = std::asin(1 / n);
  TraceScene scene;
  scene.solids.push_back(glass(make_slab(Vector3d(0, 0, 0), Vector3d(0, 0, 1), 10, 1e4), n));
  scene.sheet = sheet_z(1e3, 1);  // out of the way
  TraceOptions opt;
  opt.min_weight = 0;
  opt.max_depth = 1;  // the first event and the branches it spawns
  for (double th : {thc + 1e-9, thc + 1e-3, 1.2}) {
    const TraceResult r = trace_ray(scene, Vector3d(0, 0, 0), Vector3d(std::sin(th), 0, std::cos(th)), opt);
    expect_sane(r, 1e-15);
    EXPECT_EQ(r.counts.tir_events, 2);  // top face, then bottom face (same angle)
    EXPECT_EQ(r.background_weight, 0);  // nothing refracted out
    EXPECT_EQ(r.counts.cut_by_depth, 1);  // the single reflected branch of the second event
    EXPECT_EQ(r.cut_by_depth_weight, 1.0);
  }
  for (double th : {thc - 1e-9, thc - 1e-3, 0.3}) {
    const TraceResult r = trace_ray(scene, Vector3d(0, 0, 0), Vector3d(std::sin(th), 0, std::cos(th)), opt);
    expect_sane(r, 1e-15);
    EXPECT_EQ(r.counts.tir_events, 0);
    ASSERT_EQ(r.background.size(), 1u);
    EXPECT_EQ(r.background[0].tag, CrossingTag::refracted_only);
    const double R = r_unpolarized(th, n, 1.0);
    // Near the critical angle R is ill-conditioned in theta (dR/dtheta ~ 1 /
    // sqrt(theta_c - theta) ~ 3e4): 1e-9 rad rounds to ~1e-15 rad, so ~1e-10 in R.
    EXPECT_NEAR(r.background[0].weight, 1 - R, 1e-9) << th;
    EXPECT_GT(r.background[0].direction.z(), 0);
  }
}

TEST(PathTracer, GrazingAndTangentRaysOnASphere) {
  const double R = 20;
  TraceScene scene;
  scene.solids.push_back(glass(Sphere{Vector3d(0, 0, 0), R}, kNBk7));
  scene.sheet = sheet_z(1000);
  TraceOptions opt;
  opt.min_weight = 1e-9;
  for (double eps : {1e-2, 1e-6, 1e-10, 1e-12, 0.0, -1e-12}) {
    for (const Vector3d& side : {Vector3d(1, 0, 0), Vector3d(0.6, 0.8, 0)}) {
      const Vector3d o = R * (1 - eps) * side + Vector3d(0, 0, -100);
      const TraceResult r = trace_ray(scene, o, Vector3d(0, 0, 1), opt);
      expect_sane(r);
      EXPECT_NEAR(crossing_weight(r), forward_background_weight(r, scene.sheet), 1e-12) << eps;
      EXPECT_GE(r.crossings.size(), 1u);
      if (eps <= 0) {  // tangent or outside: a miss, the direct ray crosses once
        ASSERT_EQ(r.crossings.size(), 1u);
        EXPECT_EQ(r.crossings[0].tag, CrossingTag::direct);
        EXPECT_EQ(r.crossings[0].weight, 1.0);
      }
      for (const auto& c : r.crossings) EXPECT_FALSE(contains(scene.solids[0].shape, c.point_mm, 1e-9));
    }
  }
}

TEST(PathTracer, OriginOnTheSurfaceStartsOnTheSideItTravelsTo) {
  // Normal incidence: only the exit interface remains, weight 1 - R0 with
  // R0 = ((n - 1) / (n + 1))^2, or no interface at all going outwards.
  const double R = 20, n = kNBk7, R0 = r_normal(1.0, n);
  TraceScene scene;
  scene.solids.push_back(glass(Sphere{Vector3d(0, 0, 0), R}, n));
  scene.sheet = sheet_z(1000);
  TraceOptions opt;
  opt.reflections = false;
  for (const Vector3d& dir : {Vector3d(0, 0, 1), Vector3d(1, 2, 3).normalized()}) {
    const Vector3d on_surface = -R * dir;
    TraceResult r = trace_ray(scene, on_surface, dir, opt);  // inwards, through the centre
    expect_sane(r, 1e-15);
    ASSERT_EQ(r.background.size(), 1u);
    EXPECT_NEAR(r.background[0].weight, 1 - R0, 1e-15);
    EXPECT_NEAR((r.background[0].from_mm - R * dir).norm(), 0, 1e-12);
    EXPECT_EQ(r.background[0].depth, 1);
    r = trace_ray(scene, on_surface, -dir, opt);  // outwards
    expect_sane(r, 1e-15);
    ASSERT_EQ(r.background.size(), 1u);
    EXPECT_EQ(r.background[0].weight, 1.0);
    EXPECT_EQ(r.background[0].tag, CrossingTag::direct);
    EXPECT_EQ(r.counts.branches_traced, 1);
  }
}

TEST(PathTracer, TouchingSpheresNoLeakNoStall) {
  // Spheres of radius 10 with centres 20 mm apart on x touch at (10, 0, 0).
  // The sheet is the contact plane x = 10. Rays along x through and near the
  // contact: finite, conserved, terminating, and no crossing recorded inside a
  // solid. Along the axis itself the path runs glass-contact-glass: the contact
  // is a point, the ray is split on leaving the first sphere and enters the
  // second without a second split (docs/tracer.md: contact rule), so the
  // straight-through weight is (1 - R0)^3 and no fluid crossing exists at x = 10.
  const double R = 10, n = kNBk7, R0 = r_normal(1.0, n);
  TraceScene scene;
  scene.solids.push_back(glass(Sphere{Vector3d(0, 0, 0), R}, n));
  scene.solids.push_back(glass(Sphere{Vector3d(2 * R, 0, 0), R}, n));
  scene.sheet.origin_mm = Vector3d(R, 0, 0);
  scene.sheet.s_axis = Vector3d::UnitY();
  scene.sheet.t_axis = Vector3d::UnitZ();
  scene.sheet.extent_s_mm = scene.sheet.extent_t_mm = 1e4;
  for (double y : {0.0, 1e-12, 1e-9, 1e-6, 1e-3, 0.1, 3.0}) {
    for (bool refl : {false, true}) {
      TraceOptions opt;
      opt.reflections = refl;
      opt.min_weight = 1e-9;
      const TraceResult r = trace_ray(scene, Vector3d(-100, y, 0), Vector3d(1, 0, 0), opt);
      expect_sane(r);
      EXPECT_LT(r.counts.branches_traced, 10000);
      EXPECT_EQ(r.counts.cut_by_depth, 0);
      for (const auto& c : r.crossings)
        for (const auto& s : scene.solids) EXPECT_FALSE(contains(s.shape, c.point_mm, 1e-9)) << y;
      if (y == 0) {
        EXPECT_TRUE(r.crossings.empty());
        if (!refl) {
          ASSERT_EQ(r.background.size(), 1u);
          EXPECT_NEAR(r.background[0].weight, std::pow(1 - R0, 3), 1e-15);
          EXPECT_NEAR(r.background[0].from_mm.x(), 3 * R, 1e-12);
        }
      }
    }
  }
}

TEST(PathTracer, SheetInsideASolidIsNotRecorded) {
  // The sheet z = 0 cuts a sphere of radius 20 through its centre: a ray
  // through the sphere crosses z = 0 inside the glass (not recorded), a ray
  // beside it crosses in the fluid (recorded).
  TraceScene scene;
  scene.solids.push_back(glass(Sphere{Vector3d(0, 0, 0), 20}, kNBk7));
  scene.sheet = sheet_z(0, 1000);
  TraceOptions opt;
  opt.reflections = false;
  TraceResult r = trace_ray(scene, Vector3d(5, 0, -100), Vector3d(0, 0, 1), opt);
  expect_sane(r, 1e-15);
  EXPECT_TRUE(r.crossings.empty());
  r = trace_ray(scene, Vector3d(25, 0, -100), Vector3d(0, 0, 1), opt);
  ASSERT_EQ(r.crossings.size(), 1u);
  EXPECT_EQ(r.crossings[0].tag, CrossingTag::direct);
  EXPECT_NEAR(r.crossings[0].s_mm, 25, 1e-13);
  // With reflections: whatever crosses is outside the sphere.
  opt.reflections = true;
  opt.min_weight = 1e-12;
  for (double x : {5.0, 15.0, 19.9}) {
    r = trace_ray(scene, Vector3d(x, 0, -100), Vector3d(0.1, 0, 1), opt);
    expect_sane(r);
    for (const auto& c : r.crossings) EXPECT_FALSE(contains(scene.solids[0].shape, c.point_mm, 1e-9));
  }
}

TEST(PathTracer, NoReflectionsGivesFresnelTransmittanceProduct) {
  // Normal incidence through the centre of a sphere: two transmissions,
  // weight (1 - R0)^2; the skipped reflections carry R0 + (1 - R0) R0.
  // With absorption alpha the chord 2R multiplies by exp(-2 alpha R).
  const double R = 20, n = kNBk7, R0 = r_normal(1.0, n);
  for (double alpha : {0.0, 0.01}) {
    TraceScene scene;
    scene.solids.push_back(glass(Sphere{Vector3d(0, 0, 0), R}, n, alpha));
    scene.sheet = sheet_z(100);
    TraceOptions opt;
    opt.reflections = false;
    const TraceResult r = trace_ray(scene, Vector3d(0, 0, -100), Vector3d(0, 0, 1), opt);
    expect_sane(r, 1e-15);
    ASSERT_EQ(r.crossings.size(), 1u);
    const double T = std::exp(-alpha * 2 * R);
    EXPECT_NEAR(r.crossings[0].weight, (1 - R0) * (1 - R0) * T, 1e-15);
    EXPECT_EQ(r.crossings[0].tag, CrossingTag::refracted_only);
    EXPECT_EQ(r.crossings[0].depth, 2);
    EXPECT_NEAR(r.skipped_reflection_weight, R0 + (1 - R0) * T * R0, 1e-15);
    EXPECT_NEAR(r.absorbed_weight, (1 - R0) * (1 - T), 1e-15);
    EXPECT_EQ(r.counts.reflections_skipped, 2);
    EXPECT_EQ(r.counts.branches_traced, 3);
  }
  // Generic rays through a packing: every crossing is direct or refracted_only.
  TraceScene scene;
  for (int i = 0; i < 3; ++i) scene.solids.push_back(glass(Sphere{Vector3d(20.0 * i, 0, 0), 10}, n));
  scene.sheet = sheet_z(200);
  TraceOptions opt;
  opt.reflections = false;
  for (double x = -15; x < 55; x += 1.7) {
    const TraceResult r = trace_ray(scene, Vector3d(x, 0.3, -100), Vector3d(0.05, 0, 1), opt);
    expect_sane(r);
    for (const auto& c : r.crossings) EXPECT_NE(c.tag, CrossingTag::with_reflections);
  }
}

TEST(PathTracer, OpaqueEndsBranchesAndCutsAreRecorded) {
  TraceScene scene;
  Box wall;
  wall.centre_mm = Vector3d(0, 0, 50);
  wall.half_extent_mm = Vector3d(100, 100, 1);
  scene.solids.push_back({wall, TraceMaterial::opaque()});
  scene.solids.push_back(glass(Sphere{Vector3d(0, 0, 0), 10}, kNBk7));
  scene.sheet = sheet_z(25);
  TraceResult r = trace_ray(scene, Vector3d(30, 0, -100), Vector3d(0, 0, 1));
  ASSERT_EQ(r.opaque_hits.size(), 1u);
  EXPECT_EQ(r.opaque_hits[0].solid_index, 0);
  EXPECT_EQ(r.opaque_weight, 1.0);
  EXPECT_EQ(r.crossings.size(), 1u);
  // Depth cut-off: max_depth 0 stops at the first interface with all its weight.
  TraceOptions opt;
  opt.max_depth = 0;
  r = trace_ray(scene, Vector3d(0, 0, -100), Vector3d(0, 0, 1), opt);
  expect_sane(r, 1e-15);
  EXPECT_EQ(r.cut_by_depth_weight, 1.0);
  EXPECT_EQ(r.counts.cut_by_depth, 2);
  // Weight cut-off: the normal-incidence reflection R0 ~ 0.043 is below 0.05.
  opt.max_depth = 32;
  opt.min_weight = 0.05;
  r = trace_ray(scene, Vector3d(0, 0, -100), Vector3d(0, 0, 1), opt);
  expect_sane(r, 1e-15);
  EXPECT_EQ(r.counts.cut_by_weight, 2);
  EXPECT_NEAR(r.cut_by_weight_weight, r_normal(1, kNBk7) * (2 - r_normal(1, kNBk7)), 1e-15);
  // Deterministic, and bad input is refused.
  const TraceResult r2 = trace_ray(scene, Vector3d(0, 0, -100), Vector3d(0, 0, 1), opt);
  EXPECT_EQ(r2.crossings.size(), r.crossings.size());
  EXPECT_EQ(r2.terminal_weight_sum(), r.terminal_weight_sum());
  EXPECT_THROW(trace_ray(scene, Vector3d(0, 0, 0), Vector3d(0, 0, 0)), std::invalid_argument);
}

}  // namespace
}  // namespace glasspiv
