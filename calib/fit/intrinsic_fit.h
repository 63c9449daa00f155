#pragma once
// The intrinsic calibration fit: from board-corner observations (calib/observations.h)
// to a CameraModel, the board pose of every view, the residuals and the
// covariance of the fitted intrinsics. See docs/intrinsic_fit.md.
//
// 1. Initialisation without a guess: one homography per view (board x, y ->
//    pixels), focal lengths by Zhang's closed form with the principal point at the
//    image centre (as cv::initCameraMatrix2D), distortion zero, board poses by
//    cv::solvePnP (SOLVEPNP_IPPE). An initial camera replaces the closed form.
// 2. Ceres: one residual block per corner (calib/fit/reprojection_cost.h), the
//    board poses eliminated by the Schur complement (DENSE_SCHUR), fixed
//    intrinsics held by a ceres::SubsetManifold. Models beyond opencv5 are
//    staged: k1 k2 p1 p2 k3 first, then all coefficients.
// 3. Outlier loop: mark corners whose residual norm exceeds outlier_k * sigma
//    (sigma from the median residual), refit without them, re-test every
//    corner against the new fit, until the set stops changing.
// 4. Checks: the focal length must be observable (not in a singular direction
//    of the reduced normal matrix of the intrinsics, 1-sigma below 10% of its
//    value); nothing NaN. Distortion coefficients that trade off against each
//    other are reported, not refused.
//
// Throws InputError (file "", field "views" or the offending option) for input
// that cannot give a calibration; never returns non-finite parameters.
#include <array>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "calib/camera_model.h"
#include "calib/fit/marginal_covariance.h"
#include "calib/fit/outlier_rounds.h"
#include "calib/observations.h"
#include "calib/rigid_transform.h"

namespace glasspiv {

struct IntrinsicFitOptions {
  LensModel lens_model = LensModel::OpenCV5;
  // fy = a * fx with a = fy / fx of initial_camera, or 1 (square pixels) without
  // one (OpenCV's CALIB_FIX_ASPECT_RATIO takes the ratio of its input matrix).
  bool fix_aspect_ratio = false;
  // p1 = p2 = 0, held (OpenCV's CALIB_ZERO_TANGENT_DIST).
  bool zero_tangential = false;
  // cx, cy held at the image centre ((w - 1) / 2, (h - 1) / 2), or at
  // initial_camera's principal point when one is given.
  bool fix_principal_point = false;
  // A starting camera (size must match the observations); its distortion
  // coefficients seed the first ones of lens_model. Without it the closed form runs.
  std::optional<CameraModel> initial_camera;
  // Drop corners whose residual norm exceeds outlier_k * sigma and refit, until a
  // round changes nothing (at most kMaxOutlierRounds solves); 0 disables.
  double outlier_k = 4.0;
  int max_iterations = 100;  // per Ceres solve (one per outlier round)
  // Fill IntrinsicFit::intrinsics_covariance. The observability check that
  // guards against degenerate views (the same computation) runs regardless.
  bool compute_uncertainty = true;
  int num_threads = 0;  // Ceres threads; 0: all hardware threads (std::thread::hardware_concurrency)
};

struct ObservationResidual {
  int view = 0;                                           // index into Observations::views
  int corner_index = 0;                                   // index into that view's corners
  int corner_id = 0;                                      // CornerObservation::id
  Eigen::Vector2d residual_px = Eigen::Vector2d::Zero();  // projected - observed
  bool outlier = false;                                   // dropped by the outlier loop
};

// The joint covariance of the fit's full state, the free intrinsics theta and
// every used view's pose P_v (its 6 Ceres parameters: angle-axis rad, then
// translation mm), at unit noise (multiply by the noise variance). Kept in the
// factored form of the Schur complement (calib/fit/marginal_covariance.h):
// with J^T J = [[A, B], [B^T, C]] and S = A - B C^-1 B^T,
//   Cov(theta)      = S^+
//   Cov(theta, P_v) = -S^+ K_v^T                       K_v = C_v^-1 B_v^T
//   Cov(P_v, P_w)   = delta_vw C_v^-1 + K_v S^+ K_w^T
// mrcal's projection uncertainty propagates this through the board frames
// (calib/fit/calibration_diagnostics.h).
struct StateCovariance {
  Eigen::MatrixXd intrinsics;                            // S^+ (free_intrinsics order)
  std::vector<int> views;                                // the input view of each pose block
  std::vector<std::array<double, 6>> camera_from_board;  // each pose's parameters as fitted
  std::vector<Eigen::Matrix<double, 6, 6>> pose_alone;   // C_v^-1
  std::vector<Eigen::MatrixXd> pose_from_intrinsics;     // K_v: 6 x free intrinsics
  bool empty() const { return views.empty(); }
  // The whole matrix: theta first, then the poses in `views` order.
  Eigen::MatrixXd dense() const;
};

struct SkippedView {
  int view = 0;
  std::string reason;
};

struct IntrinsicFit {
  explicit IntrinsicFit(CameraModel fitted) : camera(std::move(fitted)) {}

  CameraModel camera;
  // One per input view (Observations::views order); identity for skipped views.
  std::vector<RigidTransform> camera_from_board;
  std::vector<double> view_rms_px;  // per input view over its inliers; NaN for skipped views
  std::vector<SkippedView> skipped_views;
  // Board poses among the used views: views whose homographies agree to within
  // kSamePoseRmsPx count once (a copied photo, an unmoved board).
  int distinct_views = 0;
  // Every corner of every used view, outliers included (flagged), in input order.
  std::vector<ObservationResidual> residuals;
  int inlier_count = 0, outlier_count = 0;
  // sqrt(mean |residual|^2) over the inliers: OpenCV's calibrateCamera RMS. For
  // independent Gaussian noise of sigma px per axis it approaches sqrt(2) sigma.
  double rms_px = 0;
  // The per-axis noise estimate sqrt(sum |r|^2 / (2 n - p)) over the inliers
  // (p: free parameters, poses included): the sigma that scales the covariance.
  double sigma_px = 0;
  // Per outlier round: the threshold (outlier_k * robust sigma, robust sigma =
  // median |r| / sqrt(2 ln 2) over all corners; at least
  // kMinOutlierThresholdPx), the corners newly dropped and
  // those readmitted (every corner is re-tested against each new fit). The last
  // round changes nothing unless kMaxOutlierRounds was reached. Empty when
  // outlier_k == 0.
  std::vector<int> dropped_per_round;
  std::vector<int> readmitted_per_round;
  std::vector<double> threshold_px_per_round;

  // Indices into CameraModel::intrinsics() (0 fx, 1 fy, 2 cx, 3 cy, 4 + i the
  // i-th distortion coefficient) of the free parameters, ascending.
  std::vector<int> free_intrinsics;
  double aspect_ratio = 0;  // fy / fx when tied by fix_aspect_ratio, else 0
  // Covariance of the free intrinsics (free_intrinsics order, units px^2 for
  // fx..cy, squared coefficient units for distortion): the intrinsics block of
  // sigma_px^2 (J^T J)^-1 over all free parameters, i.e. with the board poses
  // marginalised; computed as the inverse of the Schur complement of the poses
  // in J^T J (Jacobi-scaled). Empty unless compute_uncertainty.
  Eigen::MatrixXd intrinsics_covariance;
  // The intrinsics and the board poses jointly (see StateCovariance), at unit
  // noise. Empty unless compute_uncertainty.
  StateCovariance state_covariance;
  // mrcal's noise estimate: the standard deviation of all inlier residual
  // components (x and y together, their mean removed, divided by 2n), as
  // mrcal.projection_uncertainty takes it. Below sigma_px by the factor
  // sqrt((2n - p) / 2n) (a few % on small sets).
  double residual_std_px = 0;
  // 1-sigma of fx from the observability check (always computed; with
  // sigma_px floored at kObservabilitySigmaFloorPx).
  double fx_sigma_px = 0;
  // lambda_min / lambda_max of the Jacobi-scaled reduced normal matrix of the
  // free intrinsics: 1 for independent parameters, towards 0 as some
  // combination of them becomes undetermined.
  double reciprocal_condition = 0;
  // The free parameters taking part in combinations the views do not determine
  // (eigenvalue < kMinReciprocalCondition * largest): typically k1..k6 of a
  // rational model on a lens that needs no denominator. The projection is
  // unaffected in the observed region, the coefficients themselves mean little,
  // and intrinsics_covariance is the pseudo-inverse over the determined
  // directions. Empty for a well-posed fit.
  std::vector<std::string> undetermined_parameters;

  // Ceres, summed over the outlier rounds.
  int rounds = 0;
  int iterations = 0;
  double solver_time_s = 0;   // Ceres Solve() wall time
  double total_time_s = 0;    // the whole call: initialisation, solves, checks, covariance
  std::string termination;    // of the last solve: "CONVERGENCE", "NO_CONVERGENCE", ...
  double initial_rms_px = 0;  // after initialisation, before the first solve
};

// kMaxOutlierRounds and kMinOutlierThresholdPx: calib/fit/outlier_rounds.h.
constexpr int kMinCornersPerView = 4;  // a homography and a board pose need 4
// The focal length counts as unobservable when its 1-sigma exceeds this fraction.
constexpr double kMaxRelativeFocalSigma = 0.10;
// Directions of the (Jacobi-scaled) reduced normal matrix with eigenvalues below
// kMinReciprocalCondition times the largest are undetermined: if fx or fy takes
// part the fit is refused as "nearly fronto-parallel" (field "views"); otherwise
// the distortion coefficients involved are listed in undetermined_parameters.
// The observability check uses max(sigma_px, kObservabilitySigmaFloorPx). Both
// constants: calib/fit/marginal_covariance.h.
// Two views are one board pose when their homographies put the board's corners
// within this RMS distance of each other (px). The views are then counted once:
// with a free principal point, a single distinct pose is refused (field "views").
constexpr double kSamePoseRmsPx = 0.5;

IntrinsicFit fit_intrinsics(const Observations& observations, const IntrinsicFitOptions& options = {});

// "fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3", ... "tau_y" for an index
// into CameraModel::intrinsics().
std::string intrinsic_name(int index);

}  // namespace glasspiv
