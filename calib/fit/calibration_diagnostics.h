#pragma once
// What a calibration's numbers mean, as pictures over the sensor and as a few
// figures (see docs/intrinsic_fit.md):
// - residual_field: the mean residual vector per cell (systematic patterns show a
//   lens model that cannot follow the lens);
// - coverage: how many corners fell into each cell (empty corners of the image
//   are extrapolated, not measured);
// - projection_uncertainty: mrcal's, the 1-sigma pixel error of projecting a
//   point defined through the board frames, from the joint covariance of the
//   intrinsics and the board poses (or, as an option, the intrinsics alone);
// - cross_validation: mrcal's cross-validation, the projection difference of the
//   models fitted to the even- and the odd-indexed views, after the rotation
//   implied between them.
#include <array>
#include <limits>
#include <string>

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

// Which uncertainty a projection uncertainty propagates (docs/intrinsic_fit.md).
enum class UncertaintyMethod {
  // mrcal's (mrcal.projection_uncertainty): the observation noise through the
  // intrinsics and the board poses jointly (IntrinsicFit::state_covariance), to
  // the projection of a point defined through the board frames: the pixel's ray
  // taken to distance_mm (or a direction, at infinity), expressed in every
  // board's frame by the fitted pose, mapped back by each pose and averaged,
  // then projected. A camera rotation that the boards cannot tell from a
  // principal-point shift thus does not count. Noise: fit.residual_std_px.
  board_frames,
  // The intrinsics' covariance alone (poses marginalised), the point held fixed
  // in the camera frame: 3-4x larger near the centre than board_frames, and
  // independent of the distance. Noise: fit.sigma_px.
  intrinsics_only,
};
// "board-frames", "intrinsics-only"; the parse throws InputError (field "uncertainty").
std::string uncertainty_method_name(UncertaintyMethod method);
UncertaintyMethod uncertainty_method_from_name(const std::string& name);

// distance_mm for a point at infinity (board_frames then uses the board poses'
// rotations only, as mrcal's atinfinity).
constexpr double kAtInfinity = std::numeric_limits<double>::infinity();

enum class UncertaintyStatus {
  ok,
  no_ray,         // the fitted model cannot unproject the pixel (beyond the distortion's fold)
  not_projected,  // the point is not in front of the camera, or its projection fails
};
const char* to_string(UncertaintyStatus status);

struct PixelUncertainty {
  UncertaintyStatus status = UncertaintyStatus::ok;
  Eigen::Matrix2d covariance_px2 = Eigen::Matrix2d::Zero();  // of the projected pixel; NaN unless ok
  // Worst-direction 1-sigma, sqrt(largest eigenvalue of the covariance), as mrcal
  // reports it (its 'worstdirection-stdev'); NaN unless ok.
  double worst_px = 0;
  Eigen::Vector2d worst_direction = Eigen::Vector2d::Zero();  // unit eigenvector of that eigenvalue
};

// The projection uncertainty of the point at `distance_mm` (or kAtInfinity)
// along the fitted model's ray through `pixel`, linearised (autodiff through the
// fit's reprojection functor). InputError "state_covariance" (board_frames) or
// "intrinsics_covariance" (intrinsics_only) if the fit has none.
PixelUncertainty pixel_uncertainty(const IntrinsicFit& fit, const Eigen::Vector2d& pixel, double distance_mm,
                                   UncertaintyMethod method = UncertaintyMethod::board_frames);
// Its covariance (NaN where not ok) and its worst-direction 1-sigma (NaN where not ok).
Eigen::Matrix2d projection_covariance_at(const IntrinsicFit& fit, const Eigen::Vector2d& pixel, double distance_mm,
                                         UncertaintyMethod method = UncertaintyMethod::board_frames);
double projection_uncertainty_at(const IntrinsicFit& fit, const Eigen::Vector2d& pixel, double distance_mm,
                                 UncertaintyMethod method = UncertaintyMethod::board_frames);

// Per grid sample: the worst direction of the projection covariance scaled to
// its 1-sigma length (px), so |vector| = projection_uncertainty_at and rms_px /
// max_px summarise the 1-sigma over the image. NaN where not ok: valid_count
// counts the others.
GridValues projection_uncertainty(const IntrinsicFit& fit, double distance_mm, double approx_step_px,
                                  UncertaintyMethod method = UncertaintyMethod::board_frames);

// The uncertainty at the image centre and the four corner pixels.
struct UncertaintyFigures {
  double centre_px = 0;                // NaN unless centre_status is ok
  std::array<double, 4> corners_px{};  // top-left, top-right, bottom-left, bottom-right; NaN unless ok
  UncertaintyStatus centre_status = UncertaintyStatus::ok;
  std::array<UncertaintyStatus, 4> corner_status{};
  static constexpr std::array<const char*, 4> kCornerNames = {"top-left", "top-right", "bottom-left",
                                                              "bottom-right"};
  // The worst corner with a figure (NaN if none) and how many have none.
  double worst_corner_px() const;
  int undefined_corners() const;
};
UncertaintyFigures uncertainty_figures(const IntrinsicFit& fit, double distance_mm,
                                       UncertaintyMethod method = UncertaintyMethod::board_frames);

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
  UncertaintyMethod method = UncertaintyMethod::board_frames;
  // board_frames: implied_rotation(even.camera, odd.camera), the camera rotation
  // the boards cannot tell from a principal-point shift; identity for
  // intrinsics_only.
  RigidTransform odd_from_even;
  // projection_difference(even.camera, odd.camera, ..., odd_from_even): odd's
  // pixel minus even's for the same ray (a rotation: the distance does not matter).
  GridValues difference;
  // Per sample the worst-direction 1-sigma of that difference expected from the
  // noise alone: sqrt(largest eigenvalue of Sigma_even + Sigma_odd), each at
  // infinity by `method`.
  GridValues expected;
  // difference.rms_px / expected.rms_px: about 1 when the lens model fits the
  // lens; much larger (> 3) when it does not, or when the views are too few.
  double ratio = 0;
};
// Both halves need enough views for fit_intrinsics (InputError otherwise);
// options.compute_uncertainty is forced on.
CrossValidation cross_validation(const Observations& observations, const IntrinsicFitOptions& options,
                                 double approx_step_px = 64,
                                 UncertaintyMethod method = UncertaintyMethod::board_frames);

}  // namespace glasspiv
