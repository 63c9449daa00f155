// sim/flows.h: each analytic flow against its formula or an independent
// property (no-slip, far field, divergence, circulation), and the solid mask.
#include "sim/flows.h"

#include <cmath>
#include <memory>
#include <random>

#include <gtest/gtest.h>

namespace glasspiv {
namespace {

constexpr double kMmPerM = 1000.0;

TEST(Flows, UniformIsConstant) {
  const UniformFlow flow(Eigen::Vector3d(0.1, -0.2, 0.3));
  EXPECT_EQ(flow.velocity_m_per_s(Eigen::Vector3d(5, 6, 7), 2.0), Eigen::Vector3d(0.1, -0.2, 0.3));
}

// u = U (1 - (y/h)^2) along the flow direction, zero at and beyond the walls;
// the direction is made orthogonal to the wall normal.
TEST(Flows, PoiseuilleIsTheParabolaBetweenTheWalls) {
  const Eigen::Vector3d mid_mm(1, 2, 3);
  const PoiseuilleChannelFlow flow(mid_mm, Eigen::Vector3d(0, 2, 0), Eigen::Vector3d(1, 0.5, 0), 4.0, 0.25);
  for (double y_mm : {-3.9, -2.0, 0.0, 1.0, 3.5}) {
    const Eigen::Vector3d p = mid_mm + Eigen::Vector3d(7, y_mm, -2);
    const Eigen::Vector3d u = flow.velocity_m_per_s(p, 0);
    EXPECT_NEAR(u.x(), 0.25 * (1 - y_mm * y_mm / 16), 1e-15) << y_mm;
    EXPECT_EQ(u.y(), 0);
    EXPECT_EQ(u.z(), 0);
  }
  for (double y_mm : {-4.0, 4.0, 5.0, -100.0})
    EXPECT_EQ(flow.velocity_m_per_s(mid_mm + Eigen::Vector3d(0, y_mm, 0), 0), Eigen::Vector3d::Zero()) << y_mm;
  // Mean over the gap (Simpson's rule is exact for a parabola) = 2/3 of the centreline value.
  const double mean = (0 + 4 * flow.velocity_m_per_s(mid_mm, 0).x() + 0) / 6;
  EXPECT_NEAR(mean, 0.25 * 2 / 3, 1e-15);
  EXPECT_THROW(PoiseuilleChannelFlow(mid_mm, Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitY(), 1, 1),
               std::invalid_argument);
  EXPECT_THROW(PoiseuilleChannelFlow(mid_mm, Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitX(), 0, 1),
               std::invalid_argument);
}

TEST(Flows, SolidBodyRotationIsOmegaCrossR) {
  const SolidBodyRotationFlow flow(Eigen::Vector3d(1, 1, 0), Eigen::Vector3d(0, 0, 3), 2.0);
  // 10 mm from the axis at 2 rad/s: 20 mm/s = 0.02 m/s, counter-clockwise about +z.
  const Eigen::Vector3d u = flow.velocity_m_per_s(Eigen::Vector3d(11, 1, 5), 0);
  EXPECT_NEAR((u - Eigen::Vector3d(0, 0.02, 0)).norm(), 0, 1e-17);
}

// The Lamb-Oseen vortex against its formula written independently in SI
// units, its circulation Gamma (1 - exp(-R^2/rc^2)) by quadrature around a
// circle, its peak at r = 1.12091 rc, and its core diffusing as rc^2 + 4 nu t.
TEST(Flows, LambOseenMatchesItsFormula) {
  const double gamma = 2e-3, rc0_mm = 1.5, nu = 1e-6;
  const Eigen::Vector3d centre_mm(0, 0, 10);
  const LambOseenVortexFlow flow(centre_mm, Eigen::Vector3d::UnitZ(), gamma, rc0_mm, nu);
  const double t_s = 0.25;
  const double rc_m = std::sqrt(rc0_mm * rc0_mm * 1e-6 + 4 * nu * t_s);
  EXPECT_NEAR(flow.core_radius_mm(t_s) / kMmPerM, rc_m, 1e-15);
  for (double r_mm : {0.1, 1.0, 1.5, 3.0, 20.0}) {
    const double r_m = r_mm / kMmPerM;
    const double expected = gamma / (2 * M_PI * r_m) * (1 - std::exp(-r_m * r_m / (rc_m * rc_m)));
    const Eigen::Vector3d u = flow.velocity_m_per_s(centre_mm + Eigen::Vector3d(0, r_mm, 4), t_s);
    // Counter-clockwise about +z: at +y the velocity points along -x.
    EXPECT_NEAR(u.x(), -expected, 1e-13 * std::max(1.0, expected)) << r_mm;
    EXPECT_NEAR(u.y(), 0, 1e-18);
    EXPECT_EQ(u.z(), 0);
  }
  EXPECT_EQ(flow.velocity_m_per_s(centre_mm, t_s), Eigen::Vector3d::Zero());
  // Near the axis the core turns rigidly, u = Gamma r / (2 pi rc^2) (relative error r^2 / 2 rc^2 ~ 1e-13).
  const double r_axis_m = 1e-9;
  EXPECT_NEAR(flow.velocity_m_per_s(centre_mm + Eigen::Vector3d(0, r_axis_m * kMmPerM, 0), t_s).norm(),
              gamma * r_axis_m / (2 * M_PI * rc_m * rc_m), 1e-12 * gamma * r_axis_m / (rc_m * rc_m));

  // Circulation by the midpoint rule (spectrally accurate for a periodic integrand).
  const double radius_mm = 2.0;
  const int n = 64;
  double circulation = 0;
  for (int k = 0; k < n; ++k) {
    const double a = 2 * M_PI * (k + 0.5) / n;
    const Eigen::Vector3d tangent(-std::sin(a), std::cos(a), 0);
    const Eigen::Vector3d p = centre_mm + radius_mm * Eigen::Vector3d(std::cos(a), std::sin(a), 0);
    circulation += flow.velocity_m_per_s(p, t_s).dot(tangent) * (2 * M_PI * radius_mm / kMmPerM / n);
  }
  EXPECT_NEAR(circulation, gamma * (1 - std::exp(-std::pow(radius_mm / kMmPerM / rc_m, 2))), 1e-14);

  // The peak of u_theta lies at r = 1.1209 rc (d/dr = 0: 1 + 2x = exp(x), x = r^2/rc^2 = 1.2564).
  double best_r = 0, best_u = 0;
  for (double r = 0.5; r < 3; r += 1e-4) {
    const double u = flow.velocity_m_per_s(centre_mm + Eigen::Vector3d(r * rc_m * kMmPerM, 0, 0), t_s).norm();
    if (u > best_u) best_u = u, best_r = r;
  }
  EXPECT_NEAR(best_r, 1.12091, 2e-4);
}

// Stokes flow past a sphere: no slip on the surface, the free stream far away,
// zero divergence (central differences), zero inside.
TEST(Flows, StokesSphereHasNoSlipUniformFarFieldAndNoDivergence) {
  const Eigen::Vector3d centre_mm(1, -2, 3);
  const double a_mm = 2;
  const Eigen::Vector3d u_inf(0.3, -0.1, 0.2);
  const StokesSphereFlow flow(centre_mm, a_mm, u_inf);
  std::mt19937_64 engine(7);
  std::normal_distribution<double> normal;  // directions only: any distribution will do here
  for (int k = 0; k < 50; ++k) {
    const Eigen::Vector3d e = Eigen::Vector3d(normal(engine), normal(engine), normal(engine)).normalized();
    // On the surface (just outside, so the formula is evaluated): |u| ~ |U| 1.5 * 1e-12.
    EXPECT_LT(flow.velocity_m_per_s(centre_mm + a_mm * (1 + 1e-12) * e, 0).norm(), 1e-11 * u_inf.norm());
    EXPECT_EQ(flow.velocity_m_per_s(centre_mm + 0.5 * a_mm * e, 0), Eigen::Vector3d::Zero());
    // Far away the disturbance decays as 3a/2r (the Stokeslet): at r = 1e6 a, below 2e-6 |U|.
    EXPECT_LT((flow.velocity_m_per_s(centre_mm + 1e6 * a_mm * e, 0) - u_inf).norm(), 2e-6 * u_inf.norm());
    // Divergence by central differences, h = 1e-4 mm: truncation h^2 |u'''| / 6 ~ 1e-9 |U|/a
    // times the O(10) factors of third derivatives near the sphere, round-off
    // 1e-16 |U| / h ~ 1e-12 |U| per mm; the derivatives themselves are ~ |U| / a = 0.2 per mm.
    for (double r : {1.05, 1.5, 3.0, 10.0}) {
      const Eigen::Vector3d p = centre_mm + r * a_mm * e;
      const double h = 1e-4;
      double divergence = 0;
      for (int axis = 0; axis < 3; ++axis) {
        const Eigen::Vector3d step = h * Eigen::Vector3d::Unit(axis);
        divergence +=
            (flow.velocity_m_per_s(p + step, 0)[axis] - flow.velocity_m_per_s(p - step, 0)[axis]) / (2 * h);
      }
      EXPECT_LT(std::abs(divergence), 1e-7) << r;
    }
  }
}

// FlowOutsideSolids: zero inside a sphere, box and cylinder, the wrapped flow
// elsewhere (rectangles have no inside).
TEST(Flows, NoFlowInsideSolids) {
  TraceScene scene;
  scene.solids.push_back({Sphere{Eigen::Vector3d(0, 0, 0), 1.0}, TraceMaterial::glass(1.5)});
  scene.solids.push_back({Box{Eigen::Vector3d(5, 0, 0), Eigen::Matrix3d::Identity(), Eigen::Vector3d(1, 2, 3)},
                          TraceMaterial::glass(1.5)});
  scene.solids.push_back({Cylinder{Eigen::Vector3d(0, 5, 0), Eigen::Vector3d::UnitX(), 0.5, 2.0},
                          TraceMaterial::opaque()});
  scene.solids.push_back({Rectangle{Eigen::Vector3d(0, 0, 5), Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(),
                                    3, 3},
                          TraceMaterial::opaque()});
  const Eigen::Vector3d u(0.1, 0.2, 0.3);
  const FlowOutsideSolids flow(std::make_shared<UniformFlow>(u), scene);
  for (const Eigen::Vector3d& inside : {Eigen::Vector3d(0.5, 0, 0), Eigen::Vector3d(5.9, 1.9, -2.9),
                                        Eigen::Vector3d(1.9, 5.4, 0)})
    EXPECT_EQ(flow.velocity_m_per_s(inside, 0), Eigen::Vector3d::Zero()) << inside.transpose();
  for (const Eigen::Vector3d& outside : {Eigen::Vector3d(1.01, 0, 0), Eigen::Vector3d(6.1, 0, 0),
                                         Eigen::Vector3d(2.1, 5, 0), Eigen::Vector3d(0, 0, 5),
                                         Eigen::Vector3d(100, 0, 0)})
    EXPECT_EQ(flow.velocity_m_per_s(outside, 0), u) << outside.transpose();
}

// The grid of SolidInteriors answers as a plain loop over contains() does, on a
// packed bed where many points lie near the contacts.
TEST(Flows, SolidInteriorsGridMatchesTheLinearSearch) {
  std::vector<Shape> shapes;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j)
      for (int k = 0; k < 4; ++k) shapes.push_back(Sphere{Eigen::Vector3d(2.0 * i, 2.0 * j, 2.0 * k), 1.0});
  shapes.push_back(Box{Eigen::Vector3d(5, 5, -3), Eigen::Matrix3d::Identity(), Eigen::Vector3d(8, 8, 0.5)});
  const SolidInteriors solids(shapes);
  std::mt19937_64 engine(3);
  std::uniform_real_distribution<double> coordinate(-4.0, 14.0);
  int inside = 0;
  for (int n = 0; n < 20000; ++n) {
    const Eigen::Vector3d p(coordinate(engine), coordinate(engine), coordinate(engine));
    bool expected = false;
    for (const Shape& s : shapes) expected = expected || contains(s, p);
    ASSERT_EQ(solids.inside(p), expected) << p.transpose();
    inside += expected;
  }
  EXPECT_GT(inside, 1000);  // the test saw both answers
}

}  // namespace
}  // namespace glasspiv
