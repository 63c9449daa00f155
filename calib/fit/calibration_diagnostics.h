#pragma once
// What a calibration's numbers mean, as pictures over the sensor and as a few
// figures (see docs/intrinsic_fit.md):
// - residual_field: the mean residual vector per cell (systematic patterns show a
//   lens model that cannot follow the lens);
// - coverage: how many corners fell into each cell (empty corners of the image
//   are extrapolated, not measured);
// - projection_uncertainty: mrcal's idea, the 1-sigma pixel error of projecting
//   a fixed point through the fitted model given the intrinsics' covariance;
// - cross_validation: mrcal's cross-validation, the projection difference of the
//   models fitted to the even- and the odd-indexed views.
#include <array>

#include "calib/fit/intrinsic_fit.h"
#include "calib/observations.h"
#include "calib/pixel_grid.h"

namespace glasspiv {

// Per grid sample: the mean residual (projected - observed, px) of the inlier
// corners observed in its cell (the pixels nearer to this sample than to any
// other); NaN for empty cells. `observations` must be the ones `fit` was made from
// (InputError "observations" otherwise).
GridValues residual_field(const IntrinsicFit& fit, const Observations& observations, double approx_step_px);

// Corners per cell over a width x height sensor (cells as in residual_field).
struct Coverage {
  PixelGrid grid;
  std::vector<int> count;  // row-major like GridValues::vector_px
  int covered_cells = 0;   // cells with at least one corner
  double covered_fraction = 0;
};
Coverage coverage(const Observations& observations, int width_px, int height_px, double approx_step_px);

// The 2x2 covariance (px^2) of the projection of the point at `distance_mm`
// along the fitted model's ray through `pixel`, from the free intrinsics'
// covariance: J Sigma J^T with J = d(pixel)/d(free intrinsics) (autodiff through
// project_point). Intrinsics only: the board poses enter as marginalised in
// fit.intrinsics_covariance, and since projection is scale invariant the
// distance has no effect (mrcal's pose-aware variant would use it). NaN where the
// pixel has no ray. InputError "intrinsics_covariance" if the fit has none.
Eigen::Matrix2d projection_covariance_at(const IntrinsicFit& fit, const Eigen::Vector2d& pixel, double distance_mm);

// Worst-direction 1-sigma, sqrt(largest eigenvalue of the 2x2 covariance), as
// mrcal reports it.
double projection_uncertainty_at(const IntrinsicFit& fit, const Eigen::Vector2d& pixel, double distance_mm);

// Per grid sample: the worst direction of the projection covariance scaled to
// its 1-sigma length (px), so |vector| = projection_uncertainty_at and rms_px /
// max_px summarise the 1-sigma over the image. NaN where no ray.
GridValues projection_uncertainty(const IntrinsicFit& fit, double distance_mm, double approx_step_px);

// projection_uncertainty_at the image centre and the four corner pixels.
struct UncertaintyFigures {
  double centre_px = 0;
  std::array<double, 4> corners_px{};  // top-left, top-right, bottom-left, bottom-right
};
UncertaintyFigures uncertainty_figures(const IntrinsicFit& fit, double distance_mm);

// The rotation b_from_a that best aligns b's rays with a's over the image (the
// Kabsch / Wahba solution on the unit rays of both models through the grid
// pixels). A camera rotation and a principal-point shift look almost alike
// through a board calibration, so two fits of the same lens differ mostly by
// such a rotation; mrcal's projection-difference tool fits this "implied
// transform" (a rotation, for points at infinity) before comparing. Pass it to
// projection_difference as b_from_a. Identity if fewer than 3 samples have rays.
RigidTransform implied_rotation(const CameraModel& a, const CameraModel& b, double approx_step_px);

struct CrossValidation {
  IntrinsicFit even, odd;  // fitted to views 0, 2, 4, ... and to 1, 3, 5, ...
  // projection_difference(even.camera, odd.camera): odd's pixel minus even's for
  // the same ray (identity pose: the distance does not matter).
  GridValues difference;
  // Per sample the worst-direction 1-sigma of that difference expected from the
  // noise alone: sqrt(largest eigenvalue of Sigma_even + Sigma_odd).
  GridValues expected;
  // difference.rms_px / expected.rms_px: about 1 when the lens model fits the
  // lens; much larger (> 3) when it does not, or when the views are too few.
  double ratio = 0;
};
// Both halves need enough views for fit_intrinsics (InputError otherwise);
// options.compute_uncertainty is forced on.
CrossValidation cross_validation(const Observations& observations, const IntrinsicFitOptions& options,
                                 double approx_step_px = 64);

}  // namespace glasspiv
