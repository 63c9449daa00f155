// Tests of calib/rigid_transform.h: rotation vectors against cv::Rodrigues,
// composition and inverse, and DaVis's Z-Y-X Euler angles.
#include "calib/rigid_transform.h"

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>

namespace glasspiv {
namespace {

double uniform(std::mt19937& rng, double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }

Eigen::Vector3d random_unit(std::mt19937& rng) {
  std::normal_distribution<double> normal;
  return Eigen::Vector3d(normal(rng), normal(rng), normal(rng)).normalized();
}

double max_abs(const Eigen::MatrixXd& m) { return m.cwiseAbs().maxCoeff(); }

// Entries of rotation matrices are O(1) and every operation here is a handful
// of flops, so double rounding leaves ~1e-15; 1e-12 is the bound unless stated.
constexpr double kTol = 1e-12;

TEST(RigidTransform, RvecMatchesRodriguesAndRoundTrips) {
  std::mt19937 rng(42);
  std::vector<Eigen::Vector3d> rvecs = {Eigen::Vector3d::Zero(), Eigen::Vector3d(1e-9, 0, 0),
                                        Eigen::Vector3d(0, 1e-6, -1e-6), Eigen::Vector3d(0, 0, M_PI / 2),
                                        Eigen::Vector3d(3.0, 0, 0)};
  for (int i = 0; i < 500; ++i) rvecs.push_back(random_unit(rng) * uniform(rng, 0.0, M_PI - 1e-3));
  double worst_matrix = 0, worst_rvec = 0;
  for (const Eigen::Vector3d& rvec : rvecs) {
    const Eigen::Vector3d t(uniform(rng, -500, 500), uniform(rng, -500, 500), uniform(rng, -500, 500));
    const RigidTransform x = RigidTransform::from_rvec_tvec(rvec, t);
    cv::Matx33d r_cv;
    cv::Rodrigues(cv::Vec3d(rvec.x(), rvec.y(), rvec.z()), r_cv);
    Eigen::Matrix3d r_expected;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) r_expected(i, j) = r_cv(i, j);
    worst_matrix = std::max(worst_matrix, max_abs(x.rotation - r_expected));
    EXPECT_LT(max_abs(x.rotation - r_expected), kTol) << rvec.transpose();
    EXPECT_EQ(x.translation_mm, t);
    // Rotation vector back, also against cv::Rodrigues's inverse. Near angle 0
    // the axis is ill-defined but the vector is not: compare vectors.
    const Eigen::Vector3d back = x.rvec();
    worst_rvec = std::max(worst_rvec, (back - rvec).norm());
    EXPECT_LT((back - rvec).norm(), kTol) << rvec.transpose() << " -> " << back.transpose();
    // cv::Rodrigues's own inverse returns 0 once sin(angle) < 1e-5, so compare
    // with it only above that.
    if (rvec.norm() > 1e-4) {
      cv::Vec3d rvec_cv;
      cv::Rodrigues(r_cv, rvec_cv);
      EXPECT_LT((back - Eigen::Vector3d(rvec_cv[0], rvec_cv[1], rvec_cv[2])).norm(), 1e-9) << rvec.transpose();
    }
    // apply() = R p + t, as cv::projectPoints would move the point.
    const Eigen::Vector3d p(uniform(rng, -100, 100), uniform(rng, -100, 100), uniform(rng, -100, 100));
    EXPECT_LT((x.apply(p) - (r_expected * p + t)).norm(), 1e-9);
  }
  std::printf("rvec: max |R - cv::Rodrigues| %.3g, max |rvec round trip| %.3g\n", worst_matrix, worst_rvec);
  // |rvec| stays in [0, pi]: a rotation by 3pi/2 about z comes back as pi/2 about -z.
  const Eigen::Vector3d back = RigidTransform::from_rvec_tvec({0, 0, 1.5 * M_PI}, Eigen::Vector3d::Zero()).rvec();
  EXPECT_LT((back - Eigen::Vector3d(0, 0, -M_PI / 2)).norm(), kTol) << back.transpose();
  // Angle pi: the axis is defined up to sign; the rotation must be reproduced.
  const Eigen::Vector3d half_turn = Eigen::Vector3d(1, 2, 2) / 3 * M_PI;
  const RigidTransform h = RigidTransform::from_rvec_tvec(half_turn, Eigen::Vector3d::Zero());
  EXPECT_NEAR(h.rvec().norm(), M_PI, 1e-9);
  EXPECT_LT(max_abs(RigidTransform::from_rvec_tvec(h.rvec(), Eigen::Vector3d::Zero()).rotation - h.rotation), 1e-9);
}

TEST(RigidTransform, CompositionAndInverse) {
  std::mt19937 rng(5);
  for (int i = 0; i < 200; ++i) {
    const auto random_transform = [&] {
      return RigidTransform::from_rvec_tvec(random_unit(rng) * uniform(rng, 0, M_PI),
                                            Eigen::Vector3d(uniform(rng, -1e3, 1e3), uniform(rng, -1e3, 1e3),
                                                            uniform(rng, -1e3, 1e3)));
    };
    const RigidTransform a_from_b = random_transform(), b_from_c = random_transform();
    const Eigen::Vector3d p(uniform(rng, -1e3, 1e3), uniform(rng, -1e3, 1e3), uniform(rng, -1e3, 1e3));
    // Coordinates up to ~3e3 mm: rounding ~1e-12 mm, bound 1e-9 mm.
    const RigidTransform a_from_c = a_from_b * b_from_c;
    EXPECT_LT((a_from_c.apply(p) - a_from_b.apply(b_from_c.apply(p))).norm(), 1e-9);
    EXPECT_LT((a_from_b.inverse().apply(a_from_b.apply(p)) - p).norm(), 1e-9);
    EXPECT_LT((a_from_b.apply(a_from_b.inverse().apply(p)) - p).norm(), 1e-9);
    const RigidTransform identity = a_from_b * a_from_b.inverse();
    EXPECT_LT(max_abs(identity.rotation - Eigen::Matrix3d::Identity()), kTol);
    EXPECT_LT(identity.translation_mm.norm(), 1e-9);
    // (a_from_b b_from_c)^-1 = b_from_c^-1 a_from_b^-1
    const RigidTransform c_from_a = b_from_c.inverse() * a_from_b.inverse();
    EXPECT_LT(max_abs(c_from_a.rotation - a_from_c.inverse().rotation), kTol);
    EXPECT_LT((c_from_a.translation_mm - a_from_c.inverse().translation_mm).norm(), 1e-9);
    // The rotation stays orthonormal with determinant +1.
    EXPECT_LT(max_abs(a_from_c.rotation * a_from_c.rotation.transpose() - Eigen::Matrix3d::Identity()), kTol);
    EXPECT_NEAR(a_from_c.rotation.determinant(), 1.0, kTol);
  }
}

// The product written out by hand: Rx, Ry, Rz are the right-handed rotations
// about the axes, R = Rz(rz) Ry(ry) Rx(rx).
Eigen::Matrix3d explicit_zyx(double rx, double ry, double rz) {
  Eigen::Matrix3d x, y, z;
  x << 1, 0, 0, 0, std::cos(rx), -std::sin(rx), 0, std::sin(rx), std::cos(rx);
  y << std::cos(ry), 0, std::sin(ry), 0, 1, 0, -std::sin(ry), 0, std::cos(ry);
  z << std::cos(rz), -std::sin(rz), 0, std::sin(rz), std::cos(rz), 0, 0, 0, 1;
  return z * y * x;
}

TEST(RigidTransform, EulerZyxMatchesExplicitProductAndRoundTrips) {
  std::mt19937 rng(11);
  double worst_angles = 0;
  for (int i = 0; i < 1000; ++i) {
    const double rx = uniform(rng, -M_PI, M_PI), ry = uniform(rng, -M_PI / 2 + 1e-3, M_PI / 2 - 1e-3),
                 rz = uniform(rng, -M_PI, M_PI);
    const Eigen::Matrix3d r = rotation_from_euler_zyx(rx, ry, rz);
    EXPECT_LT(max_abs(r - explicit_zyx(rx, ry, rz)), kTol);
    const Eigen::Vector3d angles = euler_zyx_from_rotation(r);
    // 1e-3 rad away from gimbal lock the angles are recovered to ~eps/cos(ry) ~ 1e-13.
    worst_angles = std::max(worst_angles, (angles - Eigen::Vector3d(rx, ry, rz)).cwiseAbs().maxCoeff());
    EXPECT_LT((angles - Eigen::Vector3d(rx, ry, rz)).cwiseAbs().maxCoeff(), 1e-11)
        << rx << " " << ry << " " << rz << " -> " << angles.transpose();
  }
  std::printf("euler zyx: max angle round-trip error %.3g rad\n", worst_angles);
  // Single-axis sanity: a rotation about z by +90 deg takes x to y.
  EXPECT_LT((rotation_from_euler_zyx(0, 0, M_PI / 2) * Eigen::Vector3d::UnitX() - Eigen::Vector3d::UnitY()).norm(),
            kTol);
  EXPECT_LT((rotation_from_euler_zyx(M_PI / 2, 0, 0) * Eigen::Vector3d::UnitY() - Eigen::Vector3d::UnitZ()).norm(),
            kTol);
  EXPECT_LT((rotation_from_euler_zyx(0, M_PI / 2, 0) * Eigen::Vector3d::UnitZ() - Eigen::Vector3d::UnitX()).norm(),
            kTol);
}

// At ry = +-pi/2 only rx - rz (ry = +pi/2) or rx + rz (ry = -pi/2) is
// defined: the angles returned must reproduce the rotation, with ry = +-pi/2.
// A well-conditioned formula (ry = atan2(-r20, hypot(r00, r10)), rz from row
// 0/1, rx from (Rz Ry)^T R) reproduces every rotation to ~3e-15, so 1e-12.
// KNOWN DEFECT (reported to the lead, calib/rigid_transform.cpp): this test and
// EulerZyxNearGimbalLock FAIL. ry = asin(-r20) loses sqrt(eps) near |r20| = 1
// (at ry = pi/2 exactly, r20 = -(1 - 1 ulp) gives ry = pi/2 - 2.1e-8), and the
// gimbal branch, taken for |r20| > 1 - 1e-12 (cos ry < 1.4e-6), drops rz: the
// rotation comes back wrong by up to ~3e-8 at the lock and ~7e-7 rad just off it.
TEST(RigidTransform, EulerZyxGimbalLock) {
  std::mt19937 rng(3);
  double worst_ry = 0, worst_rotation = 0, worst_combined = 0;
  for (const double ry : {M_PI / 2, -M_PI / 2}) {
    for (int i = 0; i < 50; ++i) {
      const double rx = uniform(rng, -M_PI / 2, M_PI / 2), rz = uniform(rng, -M_PI / 2, M_PI / 2);
      const Eigen::Matrix3d r = rotation_from_euler_zyx(rx, ry, rz);
      const Eigen::Vector3d angles = euler_zyx_from_rotation(r);
      ASSERT_TRUE(angles.allFinite());
      worst_ry = std::max(worst_ry, std::abs(angles.y() - ry));
      worst_rotation =
          std::max(worst_rotation, max_abs(rotation_from_euler_zyx(angles.x(), angles.y(), angles.z()) - r));
      const double combined = ry > 0 ? rx - rz : rx + rz;
      const double combined_back = ry > 0 ? angles.x() - angles.z() : angles.x() + angles.z();
      worst_combined = std::max(worst_combined, std::abs(std::remainder(combined_back - combined, 2 * M_PI)));
    }
  }
  std::printf("gimbal lock (ry = +-pi/2): ry recovered to %.3g, rx -+ rz to %.3g, rotation reproduced to %.3g\n",
              worst_ry, worst_combined, worst_rotation);
  EXPECT_LT(worst_ry, kTol);
  EXPECT_LT(worst_combined, kTol);
  EXPECT_LT(worst_rotation, kTol);
}

TEST(RigidTransform, EulerZyxNearGimbalLock) {
  std::mt19937 rng(8);
  double worst = 0;
  for (int exponent = 1; exponent <= 16; ++exponent) {
    double worst_here = 0;
    for (const double sign : {1.0, -1.0}) {
      for (int i = 0; i < 20; ++i) {
        const double ry = sign * (M_PI / 2 - std::pow(10.0, -exponent));
        const Eigen::Matrix3d r = rotation_from_euler_zyx(uniform(rng, -M_PI, M_PI), ry, uniform(rng, -M_PI, M_PI));
        const Eigen::Vector3d angles = euler_zyx_from_rotation(r);
        ASSERT_TRUE(angles.allFinite());
        worst_here = std::max(worst_here, max_abs(rotation_from_euler_zyx(angles.x(), angles.y(), angles.z()) - r));
      }
    }
    std::printf("ry = +-(pi/2 - 1e-%02d): rotation reproduced to %.3g\n", exponent, worst_here);
    worst = std::max(worst, worst_here);
  }
  EXPECT_LT(worst, kTol);
}

}  // namespace
}  // namespace glasspiv
