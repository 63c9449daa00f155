// Tests of render/optics.h against the laws the functions implement, each
// evaluated independently here (angle forms, Hecht's Fresnel equations).
#include "render/optics.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <vector>

#include "render/material.h"

namespace glasspiv {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

// N-BK7 at 532 nm relative to air from the SCHOTT Sellmeier fit (material.h),
// so that "air" is 1 here, and a fixed water index: realistic index pairs.
double n_bk7_532() { return material_from_name("N-BK7").index_relative_to_air(532.0); }
constexpr double kWater = 1.3334;

struct IndexPair {
  double n1, n2;
};
std::vector<IndexPair> index_pairs() {
  const double g = n_bk7_532();
  return {{1.0, g}, {g, 1.0}, {kWater, g}, {g, kWater}, {1.0, kWater}, {kWater, 1.0}, {1.0, 1.0}};
}

// A generic frame, so that no component of the vectors is exactly zero.
Eigen::Matrix3d tilted_frame() {
  return (Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(-0.7, Eigen::Vector3d::UnitX()) *
          Eigen::AngleAxisd(1.1, Eigen::Vector3d::UnitY()))
      .toRotationMatrix();
}

// Incident direction at angle theta to the surface normal (0, 0, 1), travelling
// downwards (towards -z), then rotated by R.
Eigen::Vector3d incident(double theta, const Eigen::Matrix3d& r) {
  return r * Eigen::Vector3d(std::sin(theta), 0.0, -std::cos(theta));
}

std::vector<double> angles_deg() {
  std::vector<double> a;
  for (double t = 0.0; t < 89.0; t += 0.25) a.push_back(t);
  for (double t : {89.0, 89.5, 89.9, 89.99, 89.999}) a.push_back(t);
  return a;
}

TEST(Reflect, MirrorLawBothNormalOrientations) {
  const Eigen::Matrix3d r = tilted_frame();
  const Eigen::Vector3d n = r * Eigen::Vector3d::UnitZ();
  for (double deg : angles_deg()) {
    const Eigen::Vector3d d = incident(deg * kDeg, r);
    for (const Eigen::Vector3d& normal : {n, Eigen::Vector3d(-n)}) {
      const Eigen::Vector3d out = reflect(d, normal);
      EXPECT_NEAR(out.norm(), 1.0, 4e-16 * 4);
      EXPECT_NEAR(out.dot(n), -d.dot(n), 1e-15);                               // normal component flips
      EXPECT_LT((out - out.dot(n) * n - (d - d.dot(n) * n)).norm(), 1e-15);  // tangential kept
    }
  }
}

// Snell's law n1 sin(theta1) = n2 sin(theta2), sines from cross products with
// the normal. Both normal orientations, both directions through each interface.
TEST(Refract, ObeysSnellOverAllAngles) {
  const Eigen::Matrix3d r = tilted_frame();
  const Eigen::Vector3d n = r * Eigen::Vector3d::UnitZ();
  double max_snell = 0, max_norm = 0, max_plane = 0;
  int refracted = 0;
  for (const IndexPair& p : index_pairs()) {
    const auto theta_c = critical_angle_rad(p.n1, p.n2);
    for (double deg : angles_deg()) {
      const double theta = deg * kDeg;
      if (theta_c && theta > *theta_c) continue;  // TIR, tested separately
      const Eigen::Vector3d d = incident(theta, r);
      for (const Eigen::Vector3d& normal : {n, Eigen::Vector3d(-n)}) {
        const auto t = refract(d, normal, p.n1 / p.n2);
        ASSERT_TRUE(t.has_value()) << p.n1 << "->" << p.n2 << " at " << deg << " deg";
        ASSERT_TRUE(t->allFinite());
        ++refracted;
        const double sin1 = d.cross(n).norm(), sin2 = t->cross(n).norm();
        max_snell = std::max(max_snell, std::abs(p.n1 * sin1 - p.n2 * sin2));
        max_norm = std::max(max_norm, std::abs(t->norm() - 1.0));
        max_plane = std::max(max_plane, std::abs(d.cross(n).dot(*t)));  // t in the plane of incidence
        EXPECT_LT(t->dot(n), 0.0);  // it goes on through the surface (downwards)
      }
    }
  }
  RecordProperty("max_snell_error", std::to_string(max_snell));
  std::printf("refractions %d: max |n1 sin1 - n2 sin2| = %.3g, max | |t| - 1 | = %.3g, max out-of-plane = %.3g\n",
              refracted, max_snell, max_norm, max_plane);
  EXPECT_LT(max_snell, 1e-14);
  EXPECT_LT(max_norm, 1e-15);
  EXPECT_LT(max_plane, 1e-15);
}

// Reversibility of light paths: refracting the transmitted ray, reversed, back
// through the same interface returns the reversed incident ray. The reverse
// step is ill-conditioned when the reversed ray arrives near the critical angle
// (cos_t = sqrt(1 - sin^2) amplifies a rounding error e in sin^2 to
// e / (2 cos_t), e ~ 2e-16), so the tolerance grows as 1 / cos(theta1) there;
// measured: |back - d| cos(theta1) <= 4e-16.
TEST(Refract, RefractBackReturnsOriginal) {
  const Eigen::Matrix3d r = tilted_frame();
  const Eigen::Vector3d n = r * Eigen::Vector3d::UnitZ();
  double max_err = 0;
  for (const IndexPair& p : index_pairs()) {
    const auto theta_c = critical_angle_rad(p.n1, p.n2);
    for (double deg : angles_deg()) {
      const double theta = deg * kDeg;
      if (theta_c && theta > *theta_c) continue;
      const Eigen::Vector3d d = incident(theta, r);
      const auto t = refract(d, n, p.n1 / p.n2);
      ASSERT_TRUE(t);
      const auto back = refract(-*t, n, p.n2 / p.n1);
      ASSERT_TRUE(back) << p.n1 << "->" << p.n2 << " at " << deg << " deg";
      const double err = (-*back - d).norm();
      max_err = std::max(max_err, err * std::cos(theta));
      EXPECT_LT(err, 1e-15 + 5e-16 / std::cos(theta)) << p.n1 << "->" << p.n2 << " at " << deg << " deg";
    }
  }
  std::printf("round trip: max |back - d| cos(theta1) = %.3g\n", max_err);
}

// Total internal reflection exactly beyond theta_c = asin(n2/n1), not before.
TEST(Refract, TotalInternalReflectionAtCriticalAngle) {
  const Eigen::Matrix3d r = tilted_frame();
  const Eigen::Vector3d n = r * Eigen::Vector3d::UnitZ();
  for (const IndexPair& p : {IndexPair{n_bk7_532(), 1.0}, IndexPair{n_bk7_532(), kWater}, IndexPair{kWater, 1.0}}) {
    const double theta_c = *critical_angle_rad(p.n1, p.n2);
    EXPECT_DOUBLE_EQ(theta_c, std::asin(p.n2 / p.n1));
    for (const Eigen::Vector3d& normal : {n, Eigen::Vector3d(-n)}) {
      const auto below = refract(incident(theta_c - 1e-9, r), normal, p.n1 / p.n2);
      ASSERT_TRUE(below);
      EXPECT_TRUE(below->allFinite());
      EXPECT_NEAR(below->norm(), 1.0, 1e-15);
      // Just below theta_c the transmitted ray is nearly grazing (cos_t ~ 7e-5).
      EXPECT_LT(std::abs(below->dot(n)), 1e-3);
      EXPECT_FALSE(refract(incident(theta_c + 1e-9, r), normal, p.n1 / p.n2));
      EXPECT_FALSE(refract(incident(89.999 * kDeg, r), normal, p.n1 / p.n2));
    }
    EXPECT_FALSE(fresnel_dielectric(std::cos(theta_c - 1e-9), p.n1, p.n2).total_internal_reflection);
    EXPECT_TRUE(fresnel_dielectric(std::cos(theta_c + 1e-9), p.n1, p.n2).total_internal_reflection);
  }
}

TEST(Refract, GrazingIncidenceIsFinite) {
  const double g = n_bk7_532();
  const Eigen::Vector3d n(0, 0, 1);
  // Exactly grazing (d perpendicular to n), and d pointing marginally *away*
  // from the surface (round-off on the wrong side): finite unit vectors.
  for (const Eigen::Vector3d& d : {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(1, 0, 1e-17).normalized(),
                                   Eigen::Vector3d(1, 0, -1e-300).normalized()}) {
    const auto t = refract(d, n, 1.0 / g);
    ASSERT_TRUE(t);
    EXPECT_TRUE(t->allFinite());
    EXPECT_NEAR(t->norm(), 1.0, 1e-15);
    // Grazing entry: the transmitted ray leaves at the critical angle asin(1/g).
    EXPECT_NEAR(std::asin(t->cross(n).norm()), std::asin(1.0 / g), 1e-12);
    const auto s = refract(d, n, 1.0);  // index matched: straight on
    ASSERT_TRUE(s);
    EXPECT_LT((*s - d).norm(), 1e-15);
    const FresnelReflectance f = fresnel_dielectric(0.0, 1.0, g);
    EXPECT_EQ(f.unpolarized, 1.0);  // grazing from the rarer side reflects everything
    const FresnelReflectance m = fresnel_dielectric(0.0, g, g);
    EXPECT_EQ(m.unpolarized, 0.0);  // no interface
  }
  // Unnormalised but slightly inaccurate normals in cosines > 1 are clamped.
  const FresnelReflectance f = fresnel_dielectric(1.0 + 1e-15, 1.0, g);
  EXPECT_TRUE(std::isfinite(f.unpolarized));
}

// Normal incidence: R = ((n1 - n2) / (n1 + n2))^2 for both polarisations.
TEST(Fresnel, NormalIncidence) {
  const double g = n_bk7_532();
  const double expected = std::pow((1.0 - g) / (1.0 + g), 2);
  const FresnelReflectance f = fresnel_dielectric(1.0, 1.0, g);
  EXPECT_NEAR(f.rs, expected, 1e-16);
  EXPECT_NEAR(f.rp, expected, 1e-16);
  EXPECT_NEAR(f.unpolarized, expected, 1e-16);
  EXPECT_NEAR(f.unpolarized, 0.04251, 1e-5);  // air -> N-BK7 at 532 nm, n = 1.51947
  std::printf("air -> N-BK7 (532 nm, n = %.6f) normal-incidence R = %.6f\n", g, f.unpolarized);
  EXPECT_NEAR(fresnel_dielectric(-1.0, g, 1.0).unpolarized, expected, 1e-16);  // sign of cos ignored
}

// Brewster's angle tan(theta_B) = n2 / n1: the p-polarised reflectance vanishes.
TEST(Fresnel, BrewsterAngle) {
  for (const IndexPair& p : index_pairs()) {
    if (p.n1 == p.n2) continue;
    const double theta_b = std::atan(p.n2 / p.n1);
    const FresnelReflectance f = fresnel_dielectric(std::cos(theta_b), p.n1, p.n2);
    EXPECT_FALSE(f.total_internal_reflection);
    EXPECT_LT(f.rp, 1e-15) << p.n1 << "->" << p.n2;
    EXPECT_GT(f.rs, 1e-3);
  }
}

// Hecht's angle form: rs = sin^2(ti - tt) / sin^2(ti + tt),
// rp = tan^2(ti - tt) / tan^2(ti + tt), tt = asin(n1 sin(ti) / n2).
// Transmittances with the beam-area and index factors:
// Ts = (n2 cos tt) / (n1 cos ti) ts^2, ts = 2 n1 cos ti / (n1 cos ti + n2 cos tt),
// Tp = (n2 cos tt) / (n1 cos ti) tp^2, tp = 2 n1 cos ti / (n2 cos ti + n1 cos tt).
// Angles from 0.25 deg (the angle form is 0/0 at 0) to 89.999 deg, and up to
// 0.5 deg below the critical angle (asin is ill-conditioned right at it).
TEST(Fresnel, AgreesWithHechtAndConservesEnergy) {
  double max_hecht = 0, max_energy = 0, max_recip = 0;
  for (const IndexPair& p : index_pairs()) {
    if (p.n1 == p.n2) continue;
    const auto theta_c = critical_angle_rad(p.n1, p.n2);
    for (double deg : angles_deg()) {
      const double ti = deg * kDeg;
      if (deg == 0.0 || (theta_c && ti > *theta_c - 0.5 * kDeg)) continue;
      const double tt = std::asin(p.n1 * std::sin(ti) / p.n2);
      const double rs = std::pow(std::sin(ti - tt) / std::sin(ti + tt), 2);
      const double rp = std::pow(std::tan(ti - tt) / std::tan(ti + tt), 2);
      const FresnelReflectance f = fresnel_dielectric(std::cos(ti), p.n1, p.n2);
      ASSERT_FALSE(f.total_internal_reflection);
      max_hecht = std::max({max_hecht, std::abs(f.rs - rs), std::abs(f.rp - rp)});
      EXPECT_NEAR(f.rs, rs, 1e-13) << p.n1 << "->" << p.n2 << " at " << deg;
      EXPECT_NEAR(f.rp, rp, 1e-13) << p.n1 << "->" << p.n2 << " at " << deg;
      EXPECT_DOUBLE_EQ(f.unpolarized, 0.5 * (f.rs + f.rp));

      const double ci = std::cos(ti), ct = std::sqrt(1.0 - std::pow(p.n1 * std::sin(ti) / p.n2, 2));
      const double factor = (p.n2 * ct) / (p.n1 * ci);
      const double ts = 2 * p.n1 * ci / (p.n1 * ci + p.n2 * ct), tp = 2 * p.n1 * ci / (p.n2 * ci + p.n1 * ct);
      max_energy = std::max({max_energy, std::abs(f.rs + factor * ts * ts - 1.0), std::abs(f.rp + factor * tp * tp - 1.0)});
      EXPECT_NEAR(f.rs + factor * ts * ts, 1.0, 1e-14);
      EXPECT_NEAR(f.rp + factor * tp * tp, 1.0, 1e-14);

      // Stokes reciprocity: R(theta_i, n1 -> n2) = R(theta_t, n2 -> n1). The
      // reverse call recomputes cos(theta_i) = sqrt(1 - (n2/n1)^2 (1 - ct^2)),
      // which turns a rounding error e ~ 1e-16 into e / (2 cos(theta_i)); |dR/dcos|
      // stays below ~10, hence the tolerance 1e-14 + 4e-15 / cos(theta_i) (measured:
      // error x cos(theta_i) <= 1.9e-15).
      const FresnelReflectance back = fresnel_dielectric(ct, p.n2, p.n1);
      ASSERT_FALSE(back.total_internal_reflection);
      const double recip = std::max(std::abs(back.rs - f.rs), std::abs(back.rp - f.rp));
      max_recip = std::max(max_recip, recip * ci);
      EXPECT_LT(recip, 1e-14 + 4e-15 / ci) << p.n1 << "->" << p.n2 << " at " << deg;
    }
  }
  std::printf("Fresnel: max |R - Hecht| = %.3g, max |R + T - 1| = %.3g, max reciprocity error x cos(theta_i) = %.3g\n", max_hecht,
              max_energy, max_recip);
}

TEST(Fresnel, TotalInternalReflectionGivesOne) {
  const double g = n_bk7_532();
  for (double deg : {42.0, 60.0, 89.999, 90.0}) {
    const FresnelReflectance f = fresnel_dielectric(std::cos(deg * kDeg), g, 1.0);
    EXPECT_TRUE(f.total_internal_reflection);
    EXPECT_EQ(f.rs, 1.0);
    EXPECT_EQ(f.rp, 1.0);
    EXPECT_EQ(f.unpolarized, 1.0);
  }
}

// The tracer's one call per interface is the two functions to the bit, over
// every angle (grazing and the critical angle included), both orientations of
// the normal and every index pair (TIR and index matching included).
TEST(RefractWithFresnel, IsRefractAndFresnelToTheBit) {
  const Eigen::Matrix3d r = tilted_frame();
  const Eigen::Vector3d n = r * Eigen::Vector3d::UnitZ();
  int tir = 0, refracted = 0;
  for (const IndexPair& p : index_pairs())
    for (double deg : angles_deg())
      for (double sign : {1.0, -1.0}) {
        const Eigen::Vector3d d = incident(deg * kDeg, r), normal = sign * n;
        const Refraction both = refract_with_fresnel(d, normal, p.n1, p.n2);
        const FresnelReflectance f = fresnel_dielectric(d.dot(normal), p.n1, p.n2);
        const std::optional<Eigen::Vector3d> t = refract(d, normal, p.n1 / p.n2);
        EXPECT_EQ(both.reflectance.total_internal_reflection, f.total_internal_reflection);
        EXPECT_EQ(both.reflectance.rs, f.rs);
        EXPECT_EQ(both.reflectance.rp, f.rp);
        EXPECT_EQ(both.reflectance.unpolarized, f.unpolarized);
        ASSERT_EQ(both.direction.has_value(), t.has_value()) << deg << " " << p.n1 << " -> " << p.n2;
        if (t) {
          EXPECT_EQ(*both.direction, *t);
          ++refracted;
        } else {
          ++tir;
        }
      }
  EXPECT_GT(tir, 100);
  EXPECT_GT(refracted, 1000);
}

// theta_c = asin(n_t / n_i): N-BK7 -> air at 532 nm, n = 1.5195, about 41.1 deg.
TEST(CriticalAngle, NBK7ToAir) {
  const double g = n_bk7_532();
  const auto theta_c = critical_angle_rad(g, 1.0);
  ASSERT_TRUE(theta_c);
  EXPECT_DOUBLE_EQ(*theta_c, std::asin(1.0 / g));
  EXPECT_NEAR(*theta_c / kDeg, 41.15, 0.05);
  std::printf("N-BK7 -> air critical angle at 532 nm: %.4f deg\n", *theta_c / kDeg);
  EXPECT_FALSE(critical_angle_rad(1.0, g));
  EXPECT_FALSE(critical_angle_rad(g, g));
}

TEST(BeerLambert, ExponentialAttenuation) {
  EXPECT_EQ(beer_lambert_transmittance(0.0, 100.0), 1.0);
  EXPECT_EQ(beer_lambert_transmittance(0.5, 0.0), 1.0);
  EXPECT_NEAR(beer_lambert_transmittance(0.01, 100.0), std::exp(-1.0), 1e-16);
  // Two path segments multiply: T(a + b) = T(a) T(b).
  EXPECT_NEAR(beer_lambert_transmittance(0.02, 30.0),
              beer_lambert_transmittance(0.02, 10.0) * beer_lambert_transmittance(0.02, 20.0), 1e-16);
}

}  // namespace
}  // namespace glasspiv
