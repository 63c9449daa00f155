#pragma once
// Camera pose from points at known places (fiducial corners), the camera model
// known: camera_from_world, its covariance and the residuals; and the rig
// bundle, several cameras and fiducials in one problem. See docs/pose_fit.md.
//
// fit_camera_pose:
// 1. Start: the observed pixels undistorted (CameraModel::unproject) to
//    normalised coordinates, then cv::solvePnP SOLVEPNP_SQPNP (identity camera
//    matrix, no distortion); if SQPnP fails, SOLVEPNP_IPPE for planar points,
//    then SOLVEPNP_EPNP.
//    initial_camera_from_world replaces it.
// 2. Ceres (DENSE_QR, Levenberg-Marquardt): one residual per point,
//    calib/fit/pose_cost.h (autodiff) or the projector (central differences).
// 3. Outlier rounds (calib/fit/outlier_rounds.h).
// 4. Covariance of the pose parameters (calib/fit/marginal_covariance.h) at
//    max(sigma_px, kObservabilitySigmaFloorPx): noise-free data cannot make a
//    degenerate set of points look determined. A pose whose camera position or
//    rotation 1-sigma exceeds the options' limits is refused.
//
// Throws InputError (file "", field "fiducials", or the offending option): fewer
// than 4 points, non-finite input, collinear points, an undetermined pose,
// points behind the camera at the fitted pose. Never returns a non-finite pose.
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "calib/camera_model.h"
#include "calib/rigid_transform.h"

namespace glasspiv {

struct PointObservation {
  Eigen::Vector3d point_world_mm = Eigen::Vector3d::Zero();
  Eigen::Vector2d pixel_px = Eigen::Vector2d::Zero();  // glasspiv convention: (0,0) centre of the top-left pixel
  int group = 0;      // e.g. the fiducial (marker) it belongs to: per-group residuals are reported
  std::string label;  // e.g. "marker 17 corner 2", used in messages
};

// Optional: a projection other than the camera model's pinhole (e.g. through
// refracting glass). Returns false when the point has no image under that pose.
// Must be deterministic; it is differentiated numerically (central
// differences) when set. With refine_focal the scale f acts on its pixel about
// the principal point: c + f (pixel - c), as scaling fx, fy does for the pinhole.
using PointProjector =
    std::function<bool(const RigidTransform& camera_from_world, int point_index, Eigen::Vector2d* pixel_px)>;

struct ExtrinsicFitOptions {
  bool refine_focal = false;  // one common scale on fx, fy free (aspect kept)
  double outlier_k = 4.0;     // 0 disables the outlier rounds; else >= 1
  int max_iterations = 100;   // per Ceres solve (one per outlier round)
  std::optional<RigidTransform> initial_camera_from_world;  // skip the PnP start
  PointProjector projector;  // empty: the camera model's own projection (autodiff)
  // A pose whose 1-sigma camera position exceeds this (mm) or rotation this (deg) is refused
  // (InputError field "fiducials", message with the figures): never a silent unconstrained pose.
  double max_position_sigma_mm = 10.0;
  double max_rotation_sigma_deg = 1.0;
  int num_threads = 1;
  // Coplanar points whose mirrored pose fits within kPlanarAmbiguityRatio are
  // refused; false returns the better of the two and reports the other's RMS
  // (ExtrinsicFit::mirrored_pose_rms_px), as OpenCV's solvePnP would.
  bool refuse_planar_ambiguity = true;
};

struct PointResidual {
  int point = 0;  // index into the input points
  int group = 0;
  Eigen::Vector2d residual_px = Eigen::Vector2d::Zero();  // projected - observed; infinite when no image
  bool outlier = false;
};

struct GroupResidual {
  int group = 0;
  int points = 0;     // the group's inliers
  double rms_px = 0;  // over them; NaN when all its points are outliers
};

struct ExtrinsicFit {
  RigidTransform camera_from_world;
  CameraModel camera = CameraModel(1, 1, 1, 1, 0, 0);  // the input model, with the refined focal when refine_focal
  double focal_scale = 1.0;
  std::vector<PointResidual> residuals;  // input order
  std::vector<GroupResidual> groups;     // ascending group
  int inlier_count = 0, outlier_count = 0;
  double rms_px = 0;          // sqrt(mean |r|^2) over inliers
  double sigma_px = 0;        // sqrt(sum|r|^2 / (2n - p)), p = 6 (7 with refine_focal)
  double initial_rms_px = 0;  // after the PnP start (over the points that have an image there)
  // Coplanar points: the RMS of the other pose IPPE finds (the mirrored tilt),
  // refined; 0 when the points are not coplanar, or when that start refines
  // back into the fitted pose (no second minimum: a wide or tilted plane).
  double mirrored_pose_rms_px = 0;
  // Covariance of (angle-axis rad x3, translation mm x3[, focal scale]) in camera_from_world's
  // parameterisation, scaled by max(sigma_px, kObservabilitySigmaFloorPx)^2; plus derived figures:
  Eigen::MatrixXd covariance;
  Eigen::Vector3d position_sigma_mm = Eigen::Vector3d::Zero();  // camera centre in the world frame, 1-sigma per axis
  double rotation_sigma_deg = 0;                                // largest 1-sigma rotation angle
  double reciprocal_condition = 0;                              // of the Jacobi-scaled normal matrix
  int rounds = 0, iterations = 0;
  double solve_time_s = 0;  // Ceres Solve() wall time, summed over the rounds
  std::string termination;  // of the last solve: "CONVERGENCE", "NO_CONVERGENCE", ...
};

constexpr int kMinPosePoints = 4;
// Coplanar points: a fit is refused when the other pose that fits a plane (the
// mirrored tilt IPPE also returns) has an RMS within this factor of the fit's
// (with the fit's RMS floored at kObservabilitySigmaFloorPx): the data cannot
// tell the two apart reliably (a single small marker, a distant flat target).
constexpr double kPlanarAmbiguityRatio = 3.0;
// Points count as collinear when the second singular value of their centred
// coordinates is below this fraction of the first (1 um over 1 m).
constexpr double kCollinearRelativeSpread = 1e-6;

ExtrinsicFit fit_camera_pose(const CameraModel& camera, const std::vector<PointObservation>& points,
                             const ExtrinsicFitOptions& options = {});

// 1-sigma figures from the 6 x 6 covariance of a pose block (angle-axis rad,
// translation mm; the leading block of `covariance` is used): a frame origin's
// position per axis (mm) and the largest 1-sigma rotation angle (deg; the same
// in either frame).
struct PoseSigma {
  Eigen::Vector3d position_sigma_mm = Eigen::Vector3d::Zero();
  double rotation_sigma_deg = 0;
};
// The camera centre in the world frame, -R^T t of camera_from_world.
PoseSigma camera_centre_sigma(const RigidTransform& camera_from_world, const Eigen::MatrixXd& covariance);
// The source frame's origin in the destination frame, the translation t.
PoseSigma origin_sigma(const RigidTransform& destination_from_source, const Eigen::MatrixXd& covariance);

// --- The rig bundle: several cameras and fiducials, one Ceres problem.
//
// Every observation is a point known in its fiducial's frame seen by one camera:
//   pixel = project(camera, camera_from_world * world_from_fiducial * point_fiducial).
// Fiducials are held (world_from_fiducial known: they fix the world frame) or
// free (estimated). At least one must be held, else the world frame floats
// (gauge freedom): refused. Cameras start at their camera_from_world (e.g. from
// fit_camera_pose) and are all free; intrinsics are held. Ceres DENSE_SCHUR
// (trust region); the outlier rounds as in fit_camera_pose, except that the
// first verdict is taken at a Cauchy-loss optimum (scale kRigCauchyScalePx): a
// free fiducial has few points, and in least squares one bad corner drags its
// neighbours past the threshold. The result is always the least-squares fit of
// the inliers. The covariance covers every free block jointly.
//
// Throws InputError (file ""): field "fiducials" (none held, a free one unseen
// or undetermined), "cameras" (fewer than 4 observations, undetermined),
// "observations" (indices out of range, non-finite, behind a camera, a singular
// problem, too few observations left), or the offending option.
struct RigCamera {
  CameraModel camera;
  RigidTransform camera_from_world;  // the start
};

struct RigFiducial {
  RigidTransform world_from_fiducial;  // known when held, else the start
  bool held = true;
};

struct RigObservation {
  int camera = 0;    // index into the cameras
  int fiducial = 0;  // index into the fiducials
  Eigen::Vector3d point_fiducial_mm = Eigen::Vector3d::Zero();
  Eigen::Vector2d pixel_px = Eigen::Vector2d::Zero();
  std::string label;
};

struct RigFitOptions {
  double outlier_k = 4.0;  // 0 disables the outlier rounds
  int max_iterations = 100;
  // Every camera centre and every free fiducial's origin (their 1-sigma per
  // axis, mm) and rotation (largest 1-sigma angle, deg) must stay within these.
  double max_position_sigma_mm = 10.0;
  double max_rotation_sigma_deg = 1.0;
  int num_threads = 1;
};

struct RigResidual {
  int observation = 0, camera = 0, fiducial = 0;
  Eigen::Vector2d residual_px = Eigen::Vector2d::Zero();
  bool outlier = false;
};

struct RigFit {
  std::vector<RigidTransform> camera_from_world;    // per camera
  std::vector<RigidTransform> world_from_fiducial;  // per fiducial (held ones as given)
  std::vector<RigResidual> residuals;               // input order
  // Per camera and per fiducial over their inliers (rms NaN when none).
  std::vector<int> camera_points, fiducial_points;
  std::vector<double> camera_rms_px, fiducial_rms_px;
  int inlier_count = 0, outlier_count = 0;
  double rms_px = 0, sigma_px = 0, initial_rms_px = 0;
  // 1-sigma (at max(sigma_px, kObservabilitySigmaFloorPx)), every free block
  // marginalised over all others: camera centres in the world, free fiducials'
  // origins in the world (zero for held ones).
  std::vector<PoseSigma> camera_sigma, fiducial_sigma;
  double reciprocal_condition = 0;
  int rounds = 0, iterations = 0;
  double solve_time_s = 0;
  std::string termination;
};

// The Cauchy loss scale of the rig's first outlier verdict (see fit_rig).
constexpr double kRigCauchyScalePx = 1.0;

RigFit fit_rig(const std::vector<RigCamera>& cameras, const std::vector<RigFiducial>& fiducials,
               const std::vector<RigObservation>& observations, const RigFitOptions& options = {});

}  // namespace glasspiv
