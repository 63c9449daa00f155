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

// The predicted 1-sigma at the centre against the spread of 20 refits with new
// noise (same poses). The slowest test here (~20 fits).
TEST(CalibrationDiagnostics, PredictedUncertaintyMatchesSpreadOfRefits) {
  const CameraModel truth = truth_opencv5();
  std::mt19937 pose_rng(23);
  const std::vector<RigidTransform> poses = plan_views(truth, {}, {}, pose_rng);
  const Eigen::Vector2d centre((truth.width_px() - 1) / 2.0, (truth.height_px() - 1) / 2.0);
  const Eigen::Vector2d corner(0, 0);
  const Eigen::Vector3d p_centre = truth.unproject(centre).ray_camera * 1000;
  const Eigen::Vector3d p_corner = truth.unproject(corner).ray_camera * 1000;
  constexpr int kRealisations = 20;
  std::vector<Eigen::Vector2d> q_centre, q_corner;
  double predicted_centre = 0, predicted_corner = 0;
  for (int i = 0; i < kRealisations; ++i) {
    std::mt19937 rng(1000 + i);
    const IntrinsicFit fit = fit_intrinsics(observe_board(truth, {}, poses, kNoisePx, rng));
    q_centre.push_back(*fit.camera.project(p_centre));
    q_corner.push_back(*fit.camera.project(p_corner));
    predicted_centre += projection_uncertainty_at(fit, centre, 1000) / kRealisations;
    predicted_corner += projection_uncertainty_at(fit, corner, 1000) / kRealisations;
  }
  const auto worst_sigma = [](const std::vector<Eigen::Vector2d>& q) {
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (const auto& x : q) mean += x / q.size();
    Eigen::Matrix2d c = Eigen::Matrix2d::Zero();
    for (const auto& x : q) c += (x - mean) * (x - mean).transpose() / (q.size() - 1);
    return std::sqrt(Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(c).eigenvalues()(1));
  };
  const double empirical_centre = worst_sigma(q_centre), empirical_corner = worst_sigma(q_corner);
  std::cout << "1-sigma projection uncertainty, predicted / empirical over " << kRealisations << " refits: centre "
            << predicted_centre << " / " << empirical_centre << " px, top-left corner " << predicted_corner << " / "
            << empirical_corner << " px\n";
  // The brief's factor 2. The sample sigma of 20 draws scatters by ~16%
  // (1 / sqrt(2 * 19)); the largest eigenvalue of a 2x2 sample covariance is
  // biased up by a few percent more.
  EXPECT_GT(predicted_centre / empirical_centre, 0.5);
  EXPECT_LT(predicted_centre / empirical_centre, 2.0);
  EXPECT_GT(predicted_corner / empirical_corner, 0.5);
  EXPECT_LT(predicted_corner / empirical_corner, 2.0);
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
  EXPECT_NEAR(projection_uncertainty_at(fit, {100, 200}, 300), projection_uncertainty_at(fit, {100, 200}, 30000), 1e-9);

  IntrinsicFitOptions no_uncertainty;
  no_uncertainty.compute_uncertainty = false;
  std::mt19937 rng2(24);
  const IntrinsicFit bare =
      fit_intrinsics(observe_board(truth, {}, plan_views(truth, {}, {}, rng2), kNoisePx, rng2), no_uncertainty);
  EXPECT_EQ(bare.intrinsics_covariance.size(), 0);
  EXPECT_THROW(projection_uncertainty_at(bare, {0, 0}, 1000), InputError);
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
