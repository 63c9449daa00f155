#pragma once
// Guidance for a calibration session (docs/intrinsic_fit.md, "Guidance: the
// next view"): of a set of feasible board poses, the one whose view, added to
// the session, would most reduce the worst projection uncertainty over the
// image.
//
// A view's effect is predicted without a refit. Its corners' rows of the
// Jacobian (projected by the fitted camera, at unit noise) are added to the
// fit's normal equations J^T J: a new pose block C_new = J_p^T J_p, its
// coupling B_new = J_theta^T J_p, and the term J_theta^T J_theta to the
// intrinsics block; the Schur complement of the poses grows by
// J_theta^T J_theta - B_new C_new^-1 B_new^T, the other poses' blocks are
// unchanged. The joint covariance of intrinsics and poses (StateCovariance)
// follows, and mrcal's board-frames uncertainty (calibration_diagnostics.h) is
// recomputed from it, the noise sigma the session's (fit.residual_std_px).
// This is the first-order effect of the view: a refit moves the optimum and
// re-estimates the noise, by a few % on the sessions the tests use.
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "calib/camera_model.h"
#include "calib/fit/calibration_diagnostics.h"
#include "calib/fit/intrinsic_fit.h"
#include "calib/observations.h"
#include "calib/pixel_grid.h"
#include "calib/rigid_transform.h"

namespace glasspiv {

// J^T J of a fit at its optimum over its inlier corners, in the fit's
// parameterisation (the free intrinsics, then each used view's 6 pose
// parameters, angle-axis rad then translation mm), unit noise.
struct NormalEquations {
  Eigen::MatrixXd intrinsics;                            // A = J_theta^T J_theta
  std::vector<int> views;                                // the input view of each pose block (-1: added)
  std::vector<std::array<double, 6>> camera_from_board;  // each pose's parameters
  std::vector<Eigen::Matrix<double, 6, 6>> pose;         // C_v = J_v^T J_v
  std::vector<Eigen::MatrixXd> pose_intrinsics;          // B_v^T = J_v^T J_theta (6 x free intrinsics)
};

// From the fit's state (fit.state_covariance's poses, fit.camera) and the
// observations it was made from. InputError "state_covariance" if the fit has
// none, "observations" if they are not the fit's.
NormalEquations normal_equations(const IntrinsicFit& fit, const Observations& observations);

// Adds a view of the board corners `corners_mm` (board frame) at
// `camera_from_board`, its corners projected by fit.camera; corners that do not
// project are left out. Returns false (nothing added) with fewer than
// kMinCornersPerView corners.
bool add_view(const IntrinsicFit& fit, const RigidTransform& camera_from_board,
              const std::vector<Eigen::Vector3d>& corners_mm, NormalEquations* normal);

// The joint covariance at unit noise (StateCovariance's factored form): S^+ by
// the Jacobi-scaled eigen-decomposition, directions below
// kMinReciprocalCondition left out, as the fit computes it.
StateCovariance state_covariance(const NormalEquations& normal);

// The board as the candidates place it.
struct BoardLayout {
  std::vector<Eigen::Vector3d> corners_mm;  // every corner a detector can report (z = 0)
  // The printed pattern spans (0, 0) to pattern_size_mm on the board: its
  // centre is the point placed, its edges the outline drawn.
  Eigen::Vector2d pattern_size_mm = Eigen::Vector2d::Zero();
};

// The distances (camera centre to the centroid of a view's observed board
// corners, mm) of the fit's used views.
struct ViewDistances {
  double min_mm = 0, median_mm = 0, max_mm = 0;
};
ViewDistances session_distances(const IntrinsicFit& fit, const Observations& observations);

struct NextViewOptions {
  // The point whose projection uncertainty counts: at this distance along each
  // pixel's ray (kAtInfinity allowed), board-frames method.
  double distance_mm = 1000;
  double approx_step_px = 0;  // the uncertainty grid; 0: max(width, height) / 16
  // Candidate poses: the board's centre on a position_cols x position_rows grid
  // over the image (cell centres), at distance_steps distances from the
  // session's nearest to its farthest board, facing the sensor (fronto-parallel)
  // and tilted by max_tilt_deg * k / tilt_steps (k = 1..tilt_steps, both signs)
  // about tilt_axes axes in the sensor plane, 180 / tilt_axes degrees apart from
  // the image's horizontal.
  int position_cols = 5, position_rows = 4;
  int distance_steps = 3;
  double max_tilt_deg = 50;
  int tilt_steps = 2;
  int tilt_axes = 4;
  // Feasible: at least this fraction of the board's corners inside the image
  // (and within the fitted distortion's invertible region), every corner in
  // front of the camera, and the board's normal within max_view_angle_deg of
  // the line of sight to its centre (detectors lose steeper boards).
  double min_visible_fraction = 0.8;
  double max_view_angle_deg = 60;
};

struct CandidateView {
  RigidTransform camera_from_board;
  Eigen::Vector2d centre_px = Eigen::Vector2d::Zero();  // where the pattern's centre appears
  double distance_mm = 0;                               // camera centre to the pattern's centre
  // Signed tilt from fronto-parallel (board plane parallel to the sensor) about
  // an axis in the sensor plane at tilt_axis_deg from the image's x axis (0: the
  // horizontal axis, 90: the vertical one; image y down).
  double tilt_deg = 0, tilt_axis_deg = 0;
  double view_angle_deg = 0;  // between the board's normal and the line of sight to its centre
  std::vector<Eigen::Vector3d> visible_corners_mm;  // the corners inside the image
  std::vector<Eigen::Vector2d> corners_px;          // their pixels (fit's camera)
  std::vector<Eigen::Vector2d> outline_px;          // the pattern's outline, sampled along its edges, where it projects
  double visible_fraction = 0;
  double predicted_worst_px = 0;  // the uncertainty map's maximum with this view added (after propose)
};

// The board at that place and tilt, or nullopt when not feasible (see
// NextViewOptions). The pattern's centre lies on `centre_px`'s ray at `distance_mm`.
std::optional<CandidateView> candidate_view(const CameraModel& camera, const BoardLayout& board,
                                            const Eigen::Vector2d& centre_px, double distance_mm,
                                            double tilt_axis_deg, double tilt_deg, const NextViewOptions& options);

// The board-frames uncertainty map (as projection_uncertainty) with `view`
// added to the session whose normal equations are `normal`.
GridValues predicted_uncertainty(const IntrinsicFit& fit, const NormalEquations& normal, const CandidateView& view,
                                 const NextViewOptions& options);

struct NextView {
  GridValues before, after;  // uncertainty maps (1 sigma, worst direction), now and with `best` added
  double worst_before_px = 0, worst_after_px = 0;  // their maxima
  CandidateView best;
  std::vector<CandidateView> candidates;  // every feasible one, predicted_worst_px filled
  int poses_tried = 0;                    // feasible or not
  ViewDistances distances;
  double noise_sigma_px = 0;  // fit.residual_std_px, the prediction's noise
  double distance_mm = 0;     // the options' point distance
};

// Tries every candidate of `options` and keeps the one with the lowest
// predicted worst uncertainty. `progress(done, total)` after each candidate.
// InputError "state_covariance" without one; "board" with fewer than
// kMinCornersPerView corners; "candidates" if no pose is feasible.
NextView propose_next_view(const IntrinsicFit& fit, const Observations& observations, const BoardLayout& board,
                           const NextViewOptions& options = {},
                           const std::function<void(int done, int total)>& progress = {});

// "tilt the board ~50 deg about the vertical axis (its right edge nearer the
// camera), with its centre in the top-left of the image, at ~600 mm" (about a
// diagonal axis: "its top-left corner nearer"); the distance to 2 digits.
std::string describe_view(const CandidateView& view, int width_px, int height_px);

// A fit-like state for a camera fitted elsewhere: its intrinsics held, each
// view's board pose fitted to them (fit_camera_pose, outlier rounds at
// outlier_k), the residuals and mrcal's noise estimate, and the joint
// covariance as if every intrinsic of its lens model had been fitted to these
// observations (meaningful when the camera is these observations' optimum).
// Views without a pose are listed in skipped_views. InputError "observations"
// (image size differs from the camera's, or no view gives a pose).
IntrinsicFit fit_with_camera_held(const CameraModel& camera, const Observations& observations,
                                  double outlier_k = 4.0);

}  // namespace glasspiv
