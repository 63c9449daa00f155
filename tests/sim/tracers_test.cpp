// sim/tracers.h: seeding density and exclusion, RK4 against exact
// trajectories, out-of-plane motion, the sheet's intensity profile.
#include "sim/tracers.h"

#include <cmath>
#include <memory>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

namespace glasspiv {
namespace {

Sheet test_sheet() {
  Sheet sheet;
  sheet.origin_mm = Eigen::Vector3d(3, -2, 10);
  // A tilted sheet, so that no axis is special.
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  sheet.s_axis = r.col(0);
  sheet.t_axis = r.col(1);
  sheet.extent_mm = {40, 30};
  sheet.thickness_mm = 2;  // sigma 0.5 mm, slab +-1.5 mm at 3 sigma
  return sheet;
}

// Sheet coordinates (s, t, n) of a point.
Eigen::Vector3d in_sheet(const Sheet& sheet, const Eigen::Vector3d& p) {
  const Eigen::Vector3d d = p - sheet.origin_mm;
  return {d.dot(sheet.s_axis), d.dot(sheet.t_axis), d.dot(sheet.normal())};
}

// Counts in 4 x 3 x 3 equal sub-volumes of the slab (expectation 1000 each at
// 10 per mm^3): each within 4 Poisson sigma (sqrt 1000 = 32) of it, and the total
// within 4 sigma of 36000; every tracer in the slab.
TEST(Tracers, SeedingDensityIsUniformAndRight) {
  const Sheet sheet = test_sheet();
  TracerSeeding seeding;
  seeding.per_mm3 = 10;
  seeding.seed = 9;
  const std::vector<Eigen::Vector3d> tracers = seed_tracers_mm(sheet, seeding, SolidInteriors());
  const double volume_mm3 = 40 * 30 * 3;
  const double expected = seeding.per_mm3 * volume_mm3;
  EXPECT_NEAR(static_cast<double>(tracers.size()), expected, 4 * std::sqrt(expected));
  std::vector<int> counts(36, 0);
  for (const Eigen::Vector3d& p : tracers) {
    const Eigen::Vector3d q = in_sheet(sheet, p);
    ASSERT_LE(std::abs(q[0]), 20 + 1e-9);
    ASSERT_LE(std::abs(q[1]), 15 + 1e-9);
    ASSERT_LE(std::abs(q[2]), 1.5 + 1e-9);
    const int i = std::min(3, static_cast<int>((q[0] + 20) / 10));
    const int j = std::min(2, static_cast<int>((q[1] + 15) / 10));
    const int k = std::min(2, static_cast<int>((q[2] + 1.5) / 1.0));
    ++counts[static_cast<std::size_t>((k * 3 + j) * 4 + i)];
  }
  for (int c : counts) EXPECT_NEAR(c, expected / 36, 4 * std::sqrt(expected / 36));
}

// A cylinder across the slab (radius 8 mm, along the normal) removes
// pi 64 * 3 = 603 mm^3 of 3600: none inside, and the rest at the same density
// (4 sigma), far from the 36000 of an empty slab.
TEST(Tracers, NoneInsideSolidsAndTheRestAtTheSameDensity) {
  const Sheet sheet = test_sheet();
  TraceScene scene;
  scene.solids.push_back({Cylinder{sheet.origin_mm, sheet.normal(), 8.0, 5.0}, TraceMaterial::glass(1.5)});
  scene.solids.push_back({Sphere{sheet.origin_mm + 15 * sheet.s_axis, 1.0}, TraceMaterial::glass(1.5)});
  const SolidInteriors solids(scene.solids);
  TracerSeeding seeding;
  seeding.per_mm3 = 10;
  seeding.seed = 4;
  const std::vector<Eigen::Vector3d> tracers = seed_tracers_mm(sheet, seeding, solids);
  for (const Eigen::Vector3d& p : tracers) {
    ASSERT_FALSE(solids.inside(p));
    ASSERT_GE(in_sheet(sheet, p).head<2>().norm(), 8.0);
    ASSERT_GE((p - (sheet.origin_mm + 15 * sheet.s_axis)).norm(), 1.0);
  }
  const double expected = seeding.per_mm3 * (40 * 30 * 3 - M_PI * 64 * 3 - 4.0 / 3 * M_PI);
  EXPECT_NEAR(static_cast<double>(tracers.size()), expected, 4 * std::sqrt(expected));
}

TEST(Tracers, SameSeedSameTracersOtherSeedOthers) {
  const Sheet sheet = test_sheet();
  TracerSeeding seeding;
  seeding.per_mm3 = 1;
  seeding.margin_mm = 2;
  const std::vector<Eigen::Vector3d> a = seed_tracers_mm(sheet, seeding, SolidInteriors());
  const std::vector<Eigen::Vector3d> b = seed_tracers_mm(sheet, seeding, SolidInteriors());
  seeding.seed = 2;
  const std::vector<Eigen::Vector3d> c = seed_tracers_mm(sheet, seeding, SolidInteriors());
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  // The margin widens the seeded area: some tracers lie beyond the extent.
  int beyond = 0;
  for (const Eigen::Vector3d& p : a) beyond += std::abs(in_sheet(sheet, p)[0]) > 20;
  EXPECT_GT(beyond, 0);
  seeding.per_mm3 = -1;
  EXPECT_THROW(seed_tracers_mm(sheet, seeding, SolidInteriors()), std::invalid_argument);
  seeding.per_mm3 = 1e12;
  EXPECT_THROW(seed_tracers_mm(sheet, seeding, SolidInteriors()), std::invalid_argument);
}

// ppp = C dz (mm/px)^2: 25 per mm^3 in a 2 mm sheet at 0.02 mm/px is 0.02 ppp.
TEST(Tracers, PerPixelConversion) {
  EXPECT_NEAR(tracers_per_pixel(25, 2, 0.02), 0.02, 1e-15);
  EXPECT_NEAR(tracers_per_mm3(0.02, 2, 0.02), 25, 1e-12);
}

// RK4 on solid-body rotation against the exact trajectory (a rotation by
// omega dt about the axis). The step's error is theta^5 / 120 of the radius
// (theta = omega h), so over N sub-steps the error relative to the displacement
// (~ r Theta) is Theta^4 / (120 N^4): at Theta = 0.1 rad, 8e-7 with one step
// and 2e-10 with N = 8 (round-off ~1e-15 of the positions is far below).
TEST(Tracers, Rk4MatchesTheExactSolidBodyRotation) {
  const Eigen::Vector3d axis_point_mm(1, 2, 3);
  const Eigen::Vector3d axis = Eigen::Vector3d(0.2, -0.3, 1).normalized();
  const double omega = 50, dt = 2e-3;  // 0.1 rad
  const SolidBodyRotationFlow flow(axis_point_mm, axis, omega);
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(omega * dt, axis).toRotationMatrix();
  double worst_1 = 0, worst_8 = 0;
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(11, 2, 3), Eigen::Vector3d(-4, 7, 0), Eigen::Vector3d(1, 0, 30)}) {
    const Eigen::Vector3d exact = axis_point_mm + rotation * (p - axis_point_mm);
    const double displacement_mm = (exact - p).norm();
    worst_1 = std::max(worst_1, (advect_rk4_mm(flow, p, 0.7, dt, 1) - exact).norm() / displacement_mm);
    worst_8 = std::max(worst_8, (advect_rk4_mm(flow, p, 0.7, dt, 8) - exact).norm() / displacement_mm);
  }
  EXPECT_LT(worst_8, 1e-9);
  EXPECT_NEAR(worst_1, std::pow(0.1, 4) / 120, 0.05 * std::pow(0.1, 4) / 120);  // the predicted error itself
  // Backwards in time returns to the start.
  const Eigen::Vector3d p(11, 2, 3);
  EXPECT_LT((advect_rk4_mm(flow, advect_rk4_mm(flow, p, 0, dt, 8), dt, -dt, 8) - p).norm(), 1e-9);
}

// Poiseuille streamlines are straight: RK4 is exact, x_B = x_A + u(y) dt
// (m/s * s = m: * 1000 for mm); out-of-plane motion is kept.
TEST(Tracers, FramesCarryTheExactDisplacementOutOfPlaneIncluded) {
  const PoiseuilleChannelFlow flow(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ(), 5.0,
                                   0.4);
  const std::vector<Eigen::Vector3d> a = {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 2.5, -0.1),
                                          Eigen::Vector3d(3, 6, 0)};
  const TracerFrames frames = advect_tracers(flow, a, 0.1, 1e-3, 2);
  ASSERT_EQ(frames.frame_b_mm.size(), 3u);
  EXPECT_EQ(frames.frame_a_mm, a);
  EXPECT_EQ(frames.time_a_s, 0.1);
  EXPECT_EQ(frames.dt_s, 1e-3);
  EXPECT_NEAR((frames.frame_b_mm[0] - Eigen::Vector3d(1, 0, 0.4)).norm(), 0, 1e-15);
  EXPECT_NEAR((frames.frame_b_mm[1] - Eigen::Vector3d(0, 2.5, -0.1 + 0.4 * 0.75)).norm(), 0, 1e-15);
  EXPECT_EQ(frames.frame_b_mm[2], a[2]);  // beyond the wall
  EXPECT_THROW(advect_tracers(flow, a, 0, 1e-3, 0), std::invalid_argument);
}

// The sheet's profile: 1 on the plane, 1/e^2 at +-thickness/2, 1/2 at +-FWHM/2,
// exp(-2 z^2 / w^2) with w = thickness/2 everywhere; in-plane offsets do not matter.
TEST(Tracers, SheetIntensityIsTheGaussianProfile) {
  const Sheet sheet = test_sheet();
  const Eigen::Vector3d n = sheet.normal();
  const Eigen::Vector3d in_plane = 7 * sheet.s_axis - 3 * sheet.t_axis;
  EXPECT_NEAR(sheet_relative_intensity(sheet, sheet.origin_mm + in_plane), 1, 1e-15);
  EXPECT_NEAR(sheet_relative_intensity(sheet, sheet.origin_mm + in_plane + 1.0 * n), std::exp(-2.0), 1e-15);
  EXPECT_NEAR(sheet_relative_intensity(sheet, sheet.origin_mm - 0.5 * sheet.fwhm_mm() * n), 0.5, 1e-14);
  std::vector<Eigen::Vector3d> points;
  for (double z = -2; z <= 2; z += 0.125) points.push_back(sheet.origin_mm + in_plane + z * n);
  const std::vector<double> intensities = sheet_relative_intensities(sheet, points);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double z = (points[i] - sheet.origin_mm).dot(n);
    EXPECT_NEAR(intensities[i], std::exp(-2 * z * z / (1.0 * 1.0)), 1e-14) << z;
  }
}

}  // namespace
}  // namespace glasspiv
