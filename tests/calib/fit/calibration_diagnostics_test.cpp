// Diagnostics of the intrinsic fit: residual field, coverage, the predicted
// projection uncertainty against the spread of repeated fits, cross-validation.
// Noise: independent Gaussian, sigma = 0.1 px per axis.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>

#include <Eigen/Eigenvalues>

#include "calib/fit/calibration_diagnostics.h"
#include "calib/fit/intrinsic_fit.h"
#include "calib/lens_maps.h"
#include "sim/calibration_views.h"
#include "truth_cameras.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {

using testing::truth_opencv5;
using testing::truth_opencv8;

constexpr double kNoisePx = 0.1;

TEST(CalibrationDiagnostics, CoverageCountsEveryCorner) {
  const CameraModel truth = truth_opencv5();
  std::mt19937 rng(21);
  const Observations obs = observe_board(truth, {}, plan_views(truth, {}, {}, rng), kNoisePx, rng);
  const Coverage cov = coverage(obs, truth.width_px(), truth.height_px(), 128);
  long total = 0;
  for (int n : cov.count) total += n;
  EXPECT_EQ(total, static_cast<long>(obs.corner_count()));  // every corner lies on the sensor
  EXPECT_EQ(cov.grid.cols, 17);                             // 2047 / 128 -> 16 steps
  EXPECT_GT(cov.covered_fraction, 0.9) << "the synthetic views should reach the whole sensor";
}

TEST(CalibrationDiagnostics, ResidualFieldShowsAPoorModel) {
  std::mt19937 rng(22);
  const CameraModel truth = truth_opencv8();
  const Observations obs = observe_board(truth, {}, plan_views(truth, {}, {}, rng), kNoisePx, rng);

  IntrinsicFitOptions right;
  right.lens_model = LensModel::OpenCV8;
  const IntrinsicFit good = fit_intrinsics(obs, right);
  const GridValues good_field = residual_field(good, obs, 256);
  IntrinsicFitOptions poor;
  poor.lens_model = LensModel::OpenCV4;
  poor.outlier_k = 0;  // keep every corner, so both fields average the same ones
  const IntrinsicFit bad = fit_intrinsics(obs, poor);
  const GridValues bad_field = residual_field(bad, obs, 256);
  std::cout << "residual field RMS: opencv8 fit " << good_field.rms_px << " px, opencv4 fit " << bad_field.rms_px
            << " px (fit rms " << good.rms_px << " / " << bad.rms_px << ")\n";
  // Cells hold ~20-60 corners: the mean of pure noise is ~0.1 * sqrt(2) / 5 px.
  EXPECT_LT(good_field.rms_px, 0.05);
  EXPECT_GT(bad_field.rms_px, 5 * good_field.rms_px);

  Observations other = obs;
  other.views[0].corners.erase(other.views[0].corners.begin());
  EXPECT_THROW(residual_field(good, other, 256), InputError);
}

// Bounds on s / sigma for the sample standard deviation s of n independent
// Gaussian draws of standard deviation sigma: (n - 1) s^2 / sigma^2 is
// chi-square with n - 1 degrees of freedom; its quantiles by Wilson-Hilferty
// (accurate to ~1e-3 at 39 degrees of freedom), z the normal quantile.
double chi_std_ratio_bound(int n, double z) {
  const double nu = n - 1, a = 2.0 / (9.0 * nu);
  return std::sqrt(std::pow(1 - a + z * std::sqrt(a), 3));
}

// The sample variance of q along a unit direction.
double spread_along(const std::vector<Eigen::Vector2d>& q, const Eigen::Vector2d& direction) {
  double mean = 0, sum = 0;
  for (const auto& x : q) mean += direction.dot(x) / q.size();
  for (const auto& x : q) sum += std::pow(direction.dot(x) - mean, 2);
  return std::sqrt(sum / (q.size() - 1));
}

// Monte Carlo: the same board poses, new noise, 40 refits (seeded). What each
// method claims to predict is measured as mrcal's own uncertainty test does:
// - board_frames: the true point, expressed in each true board frame, mapped
//   back by each refit's poses, averaged, projected by the refit's intrinsics
//   (at infinity: the direction, rotations only; and at 350 mm, about the boards'
//   distance);
// - intrinsics_only: the true point held fixed in the camera frame.
// Each spread is tested along both principal directions of the prediction (the
// mean predicted covariance over the refits): for a linear-Gaussian fit the
// sample variance along a fixed direction is sigma^2 chi^2(39) / 39, so s /
// sigma lies in [0.64, 1.39] with probability 99.9 % (z = 3.29 two-sided).
// The intrinsics-only figure predicts 3-5x the board-frames spread at the
// centre, far outside that band: the test tells the methods apart.
TEST(CalibrationDiagnostics, PredictedUncertaintyMatchesSpreadOfRefits) {
  const CameraModel truth = truth_opencv5();
  std::mt19937 pose_rng(23);
  const std::vector<RigidTransform> poses = plan_views(truth, {}, {}, pose_rng);
  constexpr int kRefits = 40;
  const double low = chi_std_ratio_bound(kRefits, -3.29), high = chi_std_ratio_bound(kRefits, 3.29);
  struct Case {
    const char* name;
    Eigen::Vector2d pixel;
    double distance_mm;
    UncertaintyMethod method;
    std::vector<Eigen::Vector2d> q;
    Eigen::Matrix2d predicted = Eigen::Matrix2d::Zero();
  };
  const double w = truth.width_px() - 1.0, h = truth.height_px() - 1.0;
  std::vector<Case> cases = {
      {"board frames, centre, at infinity", {w / 2, h / 2}, kAtInfinity, UncertaintyMethod::board_frames, {}},
      {"board frames, centre, 350 mm", {w / 2, h / 2}, 350, UncertaintyMethod::board_frames, {}},
      {"board frames, top-left corner, at infinity", {0, 0}, kAtInfinity, UncertaintyMethod::board_frames, {}},
      {"intrinsics only, centre", {w / 2, h / 2}, 1000, UncertaintyMethod::intrinsics_only, {}},
      {"intrinsics only, top-left corner", {0, 0}, 1000, UncertaintyMethod::intrinsics_only, {}},
  };
  double intrinsics_only_centre = 0;
  for (int k = 0; k < kRefits; ++k) {
    std::mt19937 rng(1000 + k);
    IntrinsicFitOptions options;
    options.outlier_k = 0;  // the linear-Gaussian case the prediction is for
    const IntrinsicFit fit = fit_intrinsics(observe_board(truth, {}, poses, kNoisePx, rng), options);
    for (Case& c : cases) {
      const bool at_infinity = std::isinf(c.distance_mm);
      const Eigen::Vector3d ray = truth.unproject(c.pixel).ray_camera;
      const Eigen::Vector3d p_true = at_infinity ? ray : Eigen::Vector3d(ray * c.distance_mm);
      Eigen::Vector3d p = p_true;
      if (c.method == UncertaintyMethod::board_frames) {
        p.setZero();
        for (std::size_t v = 0; v < poses.size(); ++v) {
          const RigidTransform& fitted = fit.camera_from_board[v];
          const Eigen::Vector3d p_board =
              at_infinity ? Eigen::Vector3d(poses[v].rotation.transpose() * p_true) : poses[v].inverse().apply(p_true);
          p += (at_infinity ? Eigen::Vector3d(fitted.rotation * p_board) : fitted.apply(p_board)) / poses.size();
        }
      }
      c.q.push_back(*fit.camera.project(p));
      c.predicted += projection_covariance_at(fit, c.pixel, c.distance_mm, c.method) / kRefits;
    }
    intrinsics_only_centre +=
        projection_uncertainty_at(fit, {w / 2, h / 2}, kAtInfinity, UncertaintyMethod::intrinsics_only) / kRefits;
  }
  std::cout << "1-sigma, predicted / spread of " << kRefits << " refits (band " << low << " - " << high << "):\n";
  for (const Case& c : cases) {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(c.predicted);
    for (int axis = 1; axis >= 0; --axis) {
      const double predicted = std::sqrt(eigen.eigenvalues()(axis));
      const double spread = spread_along(c.q, eigen.eigenvectors().col(axis));
      std::cout << "  " << c.name << (axis == 1 ? ", worst" : ", best") << " direction: " << predicted << " / "
                << spread << " px (ratio " << spread / predicted << ")\n";
      EXPECT_GT(spread / predicted, low) << c.name << " axis " << axis;
      EXPECT_LT(spread / predicted, high) << c.name << " axis " << axis;
    }
  }
  const double board_frames_spread = spread_along(
      cases[0].q, Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(cases[0].predicted).eigenvectors().col(1));
  std::cout << "  the intrinsics-only figure at the centre would predict " << intrinsics_only_centre
            << " px for the board-frames spread " << board_frames_spread << " px\n";
  EXPECT_GT(intrinsics_only_centre / board_frames_spread, high);
}

TEST(CalibrationDiagnostics, UncertaintyGridAndFigures) {
  const CameraModel truth = truth_opencv5();
  std::mt19937 rng(24);
  const IntrinsicFit fit = fit_intrinsics(observe_board(truth, {}, plan_views(truth, {}, {}, rng), kNoisePx, rng));
  const GridValues grid = projection_uncertainty(fit, 1000, 128);
  const UncertaintyFigures figures = uncertainty_figures(fit, 1000);
  EXPECT_EQ(grid.valid_count, grid.grid.size());
  // The corners are extrapolated more than the centre is.
  for (double corner : figures.corners_px) EXPECT_GT(corner, figures.centre_px);
  EXPECT_NEAR(grid.max_px, *std::max_element(figures.corners_px.begin(), figures.corners_px.end()),
              0.3 * grid.max_px);  // the worst sample is at or next to a corner
  // Scale invariance: the intrinsics-only uncertainty does not depend on distance.
  const auto intrinsics_only = [&](double distance_mm) {
    return projection_uncertainty_at(fit, {100, 200}, distance_mm, UncertaintyMethod::intrinsics_only);
  };
  EXPECT_NEAR(intrinsics_only(300), intrinsics_only(30000), 1e-9);
  // Through the board frames it does: near the boards (~350 mm) the point is
  // pinned by them, far away only their rotations count, and the limit is the
  // figure at infinity.
  const double near = projection_uncertainty_at(fit, {100, 200}, 300),
               far = projection_uncertainty_at(fit, {100, 200}, 1e9),
               infinity = projection_uncertainty_at(fit, {100, 200}, kAtInfinity);
  std::cout << "top-left quarter: board frames at 300 mm " << near << " px, at 1e9 mm " << far << ", at infinity "
            << infinity << " px; intrinsics only " << intrinsics_only(300) << " px\n";
  EXPECT_LT(near, 0.5 * infinity);
  EXPECT_NEAR(far, infinity, 1e-6 * infinity);
  EXPECT_LT(infinity, intrinsics_only(300));

  IntrinsicFitOptions no_uncertainty;
  no_uncertainty.compute_uncertainty = false;
  std::mt19937 rng2(24);
  const IntrinsicFit bare =
      fit_intrinsics(observe_board(truth, {}, plan_views(truth, {}, {}, rng2), kNoisePx, rng2), no_uncertainty);
  EXPECT_EQ(bare.intrinsics_covariance.size(), 0);
  EXPECT_THROW(projection_uncertainty_at(bare, {0, 0}, 1000), InputError);
  EXPECT_THROW(projection_uncertainty_at(bare, {0, 0}, 1000, UncertaintyMethod::intrinsics_only), InputError);
  EXPECT_TRUE(bare.state_covariance.empty());
}

TEST(CalibrationDiagnostics, ImpliedRotationAbsorbsAPrincipalPointShift) {
  const CameraModel a = truth_opencv5();
  const CameraModel b(a.width_px(), a.height_px(), a.fx_px(), a.fy_px(), a.cx_px() + 0.5, a.cy_px() - 0.3,
                      a.distortion());
  const RigidTransform rotation = implied_rotation(a, b, 64);
  const GridValues plain = projection_difference(a, b, 1000, 64);
  const GridValues aligned = projection_difference(a, b, 1000, 64, rotation);
  std::cout << "cx + 0.5, cy - 0.3 px: difference RMS " << plain.rms_px << " px, after the implied rotation "
            << aligned.rms_px << " px\n";
  EXPECT_NEAR(plain.rms_px, std::hypot(0.5, 0.3), 1e-6);  // a pure shift
  // Over a +-23 degree field a rotation moves the edges ~10% more than the
  // centre (1/cos^2), so a 0.58 px shift leaves a few hundredths of a pixel.
  EXPECT_LT(aligned.rms_px, 0.1 * plain.rms_px);
  // Identical models: the identity.
  EXPECT_LT((implied_rotation(a, a, 64).rotation - Eigen::Matrix3d::Identity()).norm(), 1e-12);
}

TEST(CalibrationDiagnostics, CrossValidationSeparatesRightAndWrongModels) {
  {
    const CameraModel truth = truth_opencv5();
    std::mt19937 rng(25);
    const Observations obs = observe_board(truth, {}, plan_views(truth, {}, {}, rng), kNoisePx, rng);
    const CrossValidation cv = cross_validation(obs, {});
    std::cout << "cross-validation, right model (opencv5): difference RMS " << cv.difference.rms_px
              << " px, expected from noise " << cv.expected.rms_px << " px, ratio " << cv.ratio << "\n";
    // Two independent fits differ by ~sqrt(trace) <= sqrt(2) x the worst-direction sigma.
    EXPECT_LT(cv.ratio, 3.0);
  }
  {
    const CameraModel truth = truth_opencv8();
    std::mt19937 rng(26);
    const Observations obs = observe_board(truth, {}, plan_views(truth, {}, {}, rng), kNoisePx, rng);
    IntrinsicFitOptions options;
    options.lens_model = LensModel::OpenCV4;
    options.outlier_k = 0;  // the model error would otherwise be trimmed as "outliers"
    const CrossValidation cv = cross_validation(obs, options);
    std::cout << "cross-validation, opencv4 on a strong opencv8 lens: difference RMS " << cv.difference.rms_px
              << " px, expected from noise " << cv.expected.rms_px << " px, ratio " << cv.ratio << "\n";
    EXPECT_GT(cv.ratio, 3.0);
  }
}

}  // namespace
}  // namespace glasspiv
