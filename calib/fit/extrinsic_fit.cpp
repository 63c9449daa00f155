#include "calib/fit/extrinsic_fit.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <ceres/ceres.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "calib/fit/ceres_logging.h"
#include "calib/fit/marginal_covariance.h"
#include "calib/fit/outlier_rounds.h"
#include "calib/fit/pose_cost.h"
#include "calib/fit/reprojection_cost.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

std::string format_number(const char* format, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, value);
  return buffer;
}

[[noreturn]] void refuse(const std::string& problem) { throw InputError("", "fiducials", problem); }

std::string point_name(const std::vector<PointObservation>& points, int i) {
  const std::string& label = points[i].label;
  return "point " + std::to_string(i) + (label.empty() ? "" : " (" + label + ")");
}

using PoseBlock = std::array<double, kPoseParameterCount>;

PoseBlock pose_block(const RigidTransform& pose) {
  const Eigen::Vector3d r = pose.rvec();
  return {r.x(), r.y(), r.z(), pose.translation_mm.x(), pose.translation_mm.y(), pose.translation_mm.z()};
}

RigidTransform pose_from_block(const double* block) {
  return RigidTransform::from_rvec_tvec(Eigen::Vector3d(block[0], block[1], block[2]),
                                        Eigen::Vector3d(block[3], block[4], block[5]));
}

bool finite_pose(const RigidTransform& pose) { return pose.rotation.allFinite() && pose.translation_mm.allFinite(); }

// The user's projector as a residual, differentiated by central differences
// (ceres::NumericDiffCostFunction). With the focal block: c + f (pixel - c).
struct ProjectorResidual {
  const PointProjector* projector;
  int index;
  Eigen::Vector2d observed_px;
  Eigen::Vector2d principal_px;

  bool project(const double* camera_from_world, double focal_scale, double* residual) const {
    Eigen::Vector2d pixel;
    if (!(*projector)(pose_from_block(camera_from_world), index, &pixel) || !pixel.allFinite()) return false;
    pixel = principal_px + focal_scale * (pixel - principal_px);
    residual[0] = pixel.x() - observed_px.x();
    residual[1] = pixel.y() - observed_px.y();
    return true;
  }
};
struct ProjectorPoseResidual : ProjectorResidual {
  bool operator()(const double* camera_from_world, double* residual) const {
    return project(camera_from_world, 1.0, residual);
  }
};
struct ProjectorPoseFocalResidual : ProjectorResidual {
  bool operator()(const double* camera_from_world, const double* focal_scale, double* residual) const {
    return project(camera_from_world, focal_scale[0], residual);
  }
};

// Singular values of the centred points, descending.
Eigen::Vector3d spread(const std::vector<PointObservation>& points) {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const PointObservation& p : points) centroid += p.point_world_mm;
  centroid /= static_cast<double>(points.size());
  Eigen::MatrixXd centred(points.size(), 3);
  for (std::size_t i = 0; i < points.size(); ++i) centred.row(i) = (points[i].point_world_mm - centroid).transpose();
  return Eigen::JacobiSVD<Eigen::MatrixXd>(centred).singularValues();
}

void validate(const std::vector<PointObservation>& points, const ExtrinsicFitOptions& options) {
  if (!(options.outlier_k == 0 || (std::isfinite(options.outlier_k) && options.outlier_k >= 1)))
    throw InputError("", "outlier_k", "must be 0 (off) or a finite number >= 1");
  if (options.max_iterations < 1) throw InputError("", "max_iterations", "must be at least 1");
  if (options.num_threads < 1) throw InputError("", "num_threads", "must be at least 1");
  if (!(std::isfinite(options.max_position_sigma_mm) && options.max_position_sigma_mm > 0))
    throw InputError("", "max_position_sigma_mm", "must be a finite number > 0");
  if (!(std::isfinite(options.max_rotation_sigma_deg) && options.max_rotation_sigma_deg > 0))
    throw InputError("", "max_rotation_sigma_deg", "must be a finite number > 0");
  if (options.initial_camera_from_world && !finite_pose(*options.initial_camera_from_world))
    throw InputError("", "initial_camera_from_world", "is not finite");
  if (static_cast<int>(points.size()) < kMinPosePoints)
    refuse(std::to_string(points.size()) + " points given; a camera pose needs at least " +
           std::to_string(kMinPosePoints) + " (better 20 or more, spread over the image)");
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].point_world_mm.allFinite()) refuse(point_name(points, i) + " has a non-finite world position");
    if (!points[i].pixel_px.allFinite()) refuse(point_name(points, i) + " has a non-finite pixel");
  }
  const Eigen::Vector3d s = spread(points);
  if (!(s(0) > 0)) refuse("all " + std::to_string(points.size()) + " points are at one place");
  if (!(s(1) > kCollinearRelativeSpread * s(0)))
    refuse("the " + std::to_string(points.size()) + " points are collinear (spread across their line " +
           format_number("%.2g", s(1)) + " mm against " + format_number("%.3g", s(0)) +
           " mm along it): a line leaves the rotation about it undetermined; use points spread in two directions");
}

// cv::solvePnP on undistorted (normalised) coordinates: SQPnP, then IPPE for
// planar points, then EPnP (SQPnP refuses points whose normalised coordinates
// spread less than ~3e-3: a small patch far away). nullopt when none gives a
// finite pose with every point in front.
std::optional<RigidTransform> pnp_start(const CameraModel& camera, const std::vector<PointObservation>& points,
                                        bool planar) {
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> normalized;
  for (const PointObservation& p : points) {
    const UnprojectResult u = camera.unproject(p.pixel_px);
    if (!u.ok()) continue;  // beyond the lens model's fold: left to the fit and its outlier rounds
    object.emplace_back(p.point_world_mm.x(), p.point_world_mm.y(), p.point_world_mm.z());
    normalized.emplace_back(u.normalized.x(), u.normalized.y());
  }
  if (static_cast<int>(object.size()) < kMinPosePoints) return std::nullopt;
  const auto solve = [&](int method) -> std::optional<RigidTransform> {
    cv::Vec3d rvec, tvec;
    try {
      if (!cv::solvePnP(object, normalized, cv::Matx33d::eye(), cv::noArray(), rvec, tvec, false, method))
        return std::nullopt;
    } catch (const cv::Exception&) {
      return std::nullopt;  // degenerate points
    }
    if (!cv::checkRange(rvec) || !cv::checkRange(tvec)) return std::nullopt;
    const RigidTransform pose =
        RigidTransform::from_rvec_tvec(Eigen::Vector3d(rvec[0], rvec[1], rvec[2]), Eigen::Vector3d(tvec[0], tvec[1], tvec[2]));
    for (const cv::Point3d& p : object)
      if (!(pose.apply(Eigen::Vector3d(p.x, p.y, p.z)).z() > 0)) return std::nullopt;
    return pose;
  };
  if (auto pose = solve(cv::SOLVEPNP_SQPNP)) return pose;
  if (planar)
    if (auto pose = solve(cv::SOLVEPNP_IPPE)) return pose;
  return solve(cv::SOLVEPNP_EPNP);
}

// One point of the fit.
struct FitPoint {
  std::unique_ptr<ceres::CostFunction> cost;
  ceres::ResidualBlockId block = nullptr;  // nullptr while dropped
  Eigen::Vector2d residual_px = Eigen::Vector2d::Zero();
  bool outlier = false;
};

// The outlier rounds' view of the points (calib/fit/outlier_rounds.h), and
// their verdict applied: dropped points leave the problem, readmitted ones
// come back through add_block(index).
std::vector<OutlierCandidate> outlier_candidates(const std::vector<FitPoint>& points) {
  std::vector<OutlierCandidate> out;
  for (const FitPoint& f : points) out.push_back({f.residual_px.norm(), f.block == nullptr});
  return out;
}

template <typename AddBlock>
void apply_outlier_verdict(const OutlierVerdict& verdict, ceres::Problem& problem, std::vector<FitPoint>& points,
                           const AddBlock& add_block) {
  for (std::size_t i = 0; i < points.size(); ++i) {
    FitPoint& f = points[i];
    if (verdict.outlier[i] && f.block) {
      problem.RemoveResidualBlock(f.block);
      f.block = nullptr;
    } else if (!verdict.outlier[i] && !f.block) {
      add_block(static_cast<int>(i));
    }
    f.outlier = verdict.outlier[i];
  }
}

// d(rotation angle vector)/d(rvec) at rvec: the rotation log(R(rvec + d) R(rvec)^T)
// per unit d, by central differences.
Eigen::Matrix3d rotation_jacobian(const Eigen::Vector3d& rvec) {
  const Eigen::Matrix3d r_transposed = RigidTransform::from_rvec_tvec(rvec, Eigen::Vector3d::Zero()).rotation.transpose();
  const double h = 1e-6;
  Eigen::Matrix3d j;
  for (int i = 0; i < 3; ++i) {
    Eigen::Vector3d step = Eigen::Vector3d::Zero();
    step(i) = h;
    const auto log_of = [&](const Eigen::Vector3d& w) {
      return RigidTransform{RigidTransform::from_rvec_tvec(w, Eigen::Vector3d::Zero()).rotation * r_transposed,
                            Eigen::Vector3d::Zero()}
          .rvec();
    };
    j.col(i) = (log_of(rvec + step) - log_of(rvec - step)) / (2 * h);
  }
  return j;
}

double largest_rotation_sigma_deg(const Eigen::Vector3d& rvec, const Eigen::Matrix3d& rvec_covariance) {
  const Eigen::Matrix3d j = rotation_jacobian(rvec);
  const Eigen::Matrix3d c = j * rvec_covariance * j.transpose();
  const double lambda = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(c).eigenvalues().maxCoeff();
  return std::sqrt(std::max(0.0, lambda)) * kRadToDeg;
}

// Coplanar points: the RMS (px) of the IPPE solution that is not the fitted
// pose (its camera centre more than 5 sigma or 1 % of the distance away, or
// its rotation more than 5 sigma), refined by solvePnPRefineLM on the
// undistorted points; nullopt when IPPE offers no such second pose.
std::optional<double> other_planar_pose_rms(const CameraModel& camera, const std::vector<PointObservation>& points,
                                            const std::vector<int>& inliers, const ExtrinsicFit& fit) {
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> normalized;
  std::vector<int> used;
  for (int i : inliers) {
    const UnprojectResult u = camera.unproject(points[static_cast<std::size_t>(i)].pixel_px);
    if (!u.ok()) continue;
    const Eigen::Vector3d& w = points[static_cast<std::size_t>(i)].point_world_mm;
    object.emplace_back(w.x(), w.y(), w.z());
    normalized.emplace_back(u.normalized.x(), u.normalized.y());
    used.push_back(i);
  }
  if (static_cast<int>(object.size()) < kMinPosePoints) return std::nullopt;
  std::vector<cv::Mat> rvecs, tvecs;
  try {
    cv::solvePnPGeneric(object, normalized, cv::Matx33d::eye(), cv::noArray(), rvecs, tvecs, false, cv::SOLVEPNP_IPPE);
  } catch (const cv::Exception&) {
    return std::nullopt;
  }
  const Eigen::Vector3d centre = fit.camera_from_world.inverse().translation_mm;
  const double distance_mm = fit.camera_from_world.translation_mm.norm();
  std::optional<double> best;
  for (std::size_t k = 0; k < rvecs.size(); ++k) {
    cv::Vec3d rvec(rvecs[k]), tvec(tvecs[k]);
    try {
      cv::solvePnPRefineLM(object, normalized, cv::Matx33d::eye(), cv::noArray(), rvec, tvec);
    } catch (const cv::Exception&) {
      continue;
    }
    if (!cv::checkRange(rvec) || !cv::checkRange(tvec)) continue;
    const RigidTransform pose = RigidTransform::from_rvec_tvec(Eigen::Vector3d(rvec[0], rvec[1], rvec[2]),
                                                               Eigen::Vector3d(tvec[0], tvec[1], tvec[2]));
    const double moved_mm = (pose.inverse().translation_mm - centre).norm();
    const double turned_deg =
        Eigen::AngleAxisd(pose.rotation * fit.camera_from_world.rotation.transpose()).angle() * kRadToDeg;
    if (moved_mm <= std::max(5 * fit.position_sigma_mm.norm(), 0.01 * distance_mm) &&
        turned_deg <= 5 * fit.rotation_sigma_deg)
      continue;  // the fitted pose itself
    double sum2 = 0;
    int count = 0;
    for (int i : used) {
      const auto px = camera.project(pose.apply(points[static_cast<std::size_t>(i)].point_world_mm));
      if (!px) {
        sum2 = std::numeric_limits<double>::infinity();
        break;
      }
      sum2 += (*px - points[static_cast<std::size_t>(i)].pixel_px).squaredNorm();
      ++count;
    }
    if (count == 0 || !std::isfinite(sum2)) continue;
    const double rms = std::sqrt(sum2 / count);
    if (!best || rms < *best) best = rms;
  }
  return best;
}

}  // namespace

PoseSigma camera_centre_sigma(const RigidTransform& camera_from_world, const Eigen::MatrixXd& covariance) {
  const Eigen::Matrix<double, 6, 6> c = covariance.topLeftCorner<6, 6>();
  const Eigen::Vector3d rvec = camera_from_world.rvec(), t = camera_from_world.translation_mm;
  // C = -R(rvec)^T t: d/dt = -R^T; d/drvec by central differences.
  Eigen::Matrix<double, 3, 6> j;
  const double h = 1e-6;
  for (int i = 0; i < 3; ++i) {
    Eigen::Vector3d step = Eigen::Vector3d::Zero();
    step(i) = h;
    const Eigen::Vector3d plus = RigidTransform::from_rvec_tvec(rvec + step, t).inverse().translation_mm;
    const Eigen::Vector3d minus = RigidTransform::from_rvec_tvec(rvec - step, t).inverse().translation_mm;
    j.col(i) = (plus - minus) / (2 * h);
  }
  j.rightCols<3>() = -camera_from_world.rotation.transpose();
  PoseSigma out;
  out.position_sigma_mm = (j * c * j.transpose()).diagonal().cwiseMax(0).cwiseSqrt();
  out.rotation_sigma_deg = largest_rotation_sigma_deg(rvec, c.topLeftCorner<3, 3>());
  return out;
}

PoseSigma origin_sigma(const RigidTransform& destination_from_source, const Eigen::MatrixXd& covariance) {
  const Eigen::Matrix<double, 6, 6> c = covariance.topLeftCorner<6, 6>();
  PoseSigma out;
  out.position_sigma_mm = c.bottomRightCorner<3, 3>().diagonal().cwiseMax(0).cwiseSqrt();
  out.rotation_sigma_deg = largest_rotation_sigma_deg(destination_from_source.rvec(), c.topLeftCorner<3, 3>());
  return out;
}

ExtrinsicFit fit_camera_pose(const CameraModel& camera, const std::vector<PointObservation>& points,
                             const ExtrinsicFitOptions& options) {
  silence_ceres_logging();
  validate(points, options);
  const int n = static_cast<int>(points.size());
  const Eigen::Vector3d singular_values = spread(points);
  const bool planar = !(singular_values(2) > kCollinearRelativeSpread * singular_values(0));

  // --- Start.
  RigidTransform start;
  if (options.initial_camera_from_world) {
    start = *options.initial_camera_from_world;
  } else {
    const std::optional<RigidTransform> pnp = pnp_start(camera, points, planar);
    if (!pnp)
      refuse("no camera pose puts the " + std::to_string(n) +
             " points in front of the camera (SQPnP" + std::string(planar ? ", IPPE" : "") +
             " and EPnP on the undistorted pixels): check that the pixels belong to the world points, or give "
             "initial_camera_from_world");
    start = *pnp;
  }
  PoseBlock pose = pose_block(start);
  double focal_scale = 1.0;

  // --- The problem.
  const int parameter_count = kPoseParameterCount + (options.refine_focal ? 1 : 0);
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.enable_fast_removal = true;
  ceres::Problem problem(problem_options);
  problem.AddParameterBlock(pose.data(), kPoseParameterCount);
  std::vector<double*> blocks = {pose.data()};
  if (options.refine_focal) {
    problem.AddParameterBlock(&focal_scale, 1);
    problem.SetParameterLowerBound(&focal_scale, 0, 1e-3);  // a focal length stays positive
    blocks.push_back(&focal_scale);
  }
  const Eigen::Vector2d principal_px(camera.cx_px(), camera.cy_px());
  std::vector<FitPoint> fit_points(n);
  for (int i = 0; i < n; ++i) {
    const PointObservation& p = points[i];
    ceres::CostFunction* cost = nullptr;
    if (options.projector) {
      const ProjectorResidual r{&options.projector, i, p.pixel_px, principal_px};
      if (options.refine_focal)
        cost = new ceres::NumericDiffCostFunction<ProjectorPoseFocalResidual, ceres::CENTRAL, 2, kPoseParameterCount, 1>(
            new ProjectorPoseFocalResidual{r});
      else
        cost = new ceres::NumericDiffCostFunction<ProjectorPoseResidual, ceres::CENTRAL, 2, kPoseParameterCount>(
            new ProjectorPoseResidual{r});
    } else {
      cost = options.refine_focal ? PoseFocalReprojectionCost::Create(camera, p.pixel_px, p.point_world_mm)
                                  : PoseReprojectionCost::Create(camera, p.pixel_px, p.point_world_mm);
    }
    fit_points[i].cost.reset(cost);
  }
  const auto update_residuals = [&] {
    const double* parameters[2] = {pose.data(), &focal_scale};
    for (FitPoint& f : fit_points) {
      double r[2];
      if (f.cost->Evaluate(parameters, r, nullptr))
        f.residual_px = Eigen::Vector2d(r[0], r[1]);
      else
        f.residual_px.setConstant(std::numeric_limits<double>::infinity());  // no image
    }
  };
  const auto add_block = [&](FitPoint& f) { f.block = problem.AddResidualBlock(f.cost.get(), nullptr, blocks); };

  // Points without an image at the start stay out of the first solve; the
  // outlier rounds re-test them.
  update_residuals();
  ExtrinsicFit fit;
  double start_sum = 0;
  int start_count = 0;
  for (int i = 0; i < n; ++i) {
    FitPoint& f = fit_points[i];
    if (f.residual_px.allFinite()) {
      add_block(f);
      start_sum += f.residual_px.squaredNorm();
      ++start_count;
    } else {
      if (options.outlier_k == 0) refuse(point_name(points, i) + " has no image at the start pose");
      f.outlier = true;
    }
  }
  if (start_count < kMinPosePoints)
    refuse("only " + std::to_string(start_count) + " of the " + std::to_string(n) +
           " points have an image at the start pose; give initial_camera_from_world");
  fit.initial_rms_px = std::sqrt(start_sum / start_count);

  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_QR;
  solver_options.minimizer_type = ceres::TRUST_REGION;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.function_tolerance = 1e-14;
  solver_options.gradient_tolerance = 1e-14;
  solver_options.parameter_tolerance = 1e-14;
  solver_options.num_threads = options.num_threads;
  solver_options.logging_type = ceres::SILENT;
  solver_options.minimizer_progress_to_stdout = false;

  const auto solve = [&](int) {
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options, &problem, &summary);
    fit.iterations += std::max(0, static_cast<int>(summary.iterations.size()) - 1);
    fit.solve_time_s += summary.total_time_in_seconds;
    fit.termination = ceres::TerminationTypeToString(summary.termination_type);
    if (summary.termination_type == ceres::FAILURE)
      refuse("the solver failed (" + summary.message + "): check that the pixels belong to the world points");
    for (double v : pose)
      if (!std::isfinite(v)) refuse("the fit diverged (non-finite pose)");
    update_residuals();
  };
  const auto candidates = [&] { return outlier_candidates(fit_points); };
  const auto apply = [&](const OutlierVerdict& verdict) {
    apply_outlier_verdict(verdict, problem, fit_points, [&](int i) { add_block(fit_points[i]); });
    int inliers = 0;
    for (const FitPoint& f : fit_points) inliers += f.block != nullptr;
    if (inliers < kMinPosePoints)
      refuse("only " + std::to_string(inliers) + " of the " + std::to_string(n) +
             " points fit one pose (the rest are outliers at threshold " +
             format_number("%.3g", verdict.threshold_px) + " px); a pose needs " + std::to_string(kMinPosePoints));
  };
  fit.rounds = run_outlier_rounds(options.outlier_k, solve, candidates, apply).rounds;

  // --- The pose and its checks.
  fit.camera_from_world = pose_from_block(pose.data());
  fit.focal_scale = focal_scale;
  if (!finite_pose(fit.camera_from_world) || !std::isfinite(focal_scale)) refuse("the fit diverged (non-finite pose)");
  for (int i = 0; i < n; ++i)
    if (!(fit.camera_from_world.apply(points[i].point_world_mm).z() > 0))
      refuse(point_name(points, i) +
             " lies behind the camera at the fitted pose: the pixels do not belong to the world points, or the "
             "start was wrong (give initial_camera_from_world)");

  double sum_squares = 0;
  std::map<int, std::pair<int, double>> group_sums;  // group -> (inliers, sum |r|^2)
  for (int i = 0; i < n; ++i) {
    const FitPoint& f = fit_points[i];
    const bool outlier = f.block == nullptr;
    fit.residuals.push_back({i, points[i].group, f.residual_px, outlier});
    auto& g = group_sums[points[i].group];
    if (outlier) {
      ++fit.outlier_count;
      continue;
    }
    ++fit.inlier_count;
    sum_squares += f.residual_px.squaredNorm();
    ++g.first;
    g.second += f.residual_px.squaredNorm();
  }
  for (const auto& [group, sums] : group_sums)
    fit.groups.push_back({group, sums.first,
                          sums.first > 0 ? std::sqrt(sums.second / sums.first) : std::numeric_limits<double>::quiet_NaN()});
  fit.rms_px = std::sqrt(sum_squares / fit.inlier_count);
  fit.sigma_px = std::sqrt(sum_squares / (2 * fit.inlier_count - parameter_count));

  // --- Covariance at max(sigma_px, floor).
  const double covariance_sigma = std::max(fit.sigma_px, kObservabilitySigmaFloorPx);
  ceres::Problem::EvaluateOptions evaluate;
  evaluate.parameter_blocks = blocks;
  for (const FitPoint& f : fit_points)
    if (f.block) evaluate.residual_blocks.push_back(f.block);
  evaluate.num_threads = options.num_threads;
  ceres::CRSMatrix jacobian;
  if (!problem.Evaluate(evaluate, nullptr, nullptr, nullptr, &jacobian))
    refuse("the Jacobian at the fitted pose cannot be evaluated");
  const MarginalCovariance covariance = marginal_covariance(jacobian, parameter_count, {}, {}, covariance_sigma);
  fit.reciprocal_condition = covariance.reciprocal_condition;
  if (covariance.covariance.size() == 0 || covariance.undetermined.cols() > 0)
    refuse("the pose is not determined: the normal equations are singular (reciprocal condition " +
           format_number("%.1e", covariance.reciprocal_condition) + "); use points spread over the image and in depth");
  fit.covariance = covariance.covariance;
  const PoseSigma sigma = camera_centre_sigma(fit.camera_from_world, fit.covariance);
  fit.position_sigma_mm = sigma.position_sigma_mm;
  fit.rotation_sigma_deg = sigma.rotation_sigma_deg;
  const double position_sigma = fit.position_sigma_mm.maxCoeff();
  if (!(position_sigma <= options.max_position_sigma_mm) || !(fit.rotation_sigma_deg <= options.max_rotation_sigma_deg))
    refuse("the pose is not determined: camera position 1-sigma " + format_number("%.3g", position_sigma) +
           " mm (limit " + format_number("%g", options.max_position_sigma_mm) + " mm), rotation 1-sigma " +
           format_number("%.3g", fit.rotation_sigma_deg) + " deg (limit " +
           format_number("%g", options.max_rotation_sigma_deg) + " deg) at " +
           format_number("%.3g", covariance_sigma) + " px noise from " + std::to_string(fit.inlier_count) +
           " points; use points spread wider over the image and in depth");

  // --- Coplanar points: the other pose IPPE finds (the mirrored tilt of a
  // small or distant plane) must fit clearly worse, or the fit could have
  // picked either: refused, never a silently flipped pose.
  if (planar && !options.projector) {
    std::vector<int> inlier_index;
    for (int i = 0; i < n; ++i)
      if (fit_points[i].block) inlier_index.push_back(i);
    const std::optional<double> other_rms = other_planar_pose_rms(camera, points, inlier_index, fit);
    if (other_rms) fit.mirrored_pose_rms_px = *other_rms;
    if (other_rms && options.refuse_planar_ambiguity &&
        *other_rms <= kPlanarAmbiguityRatio * std::max(fit.rms_px, kObservabilitySigmaFloorPx))
      refuse("two poses fit the " + std::to_string(fit.inlier_count) + " coplanar points about equally (RMS " +
             format_number("%.3g", fit.rms_px) + " px and " + format_number("%.3g", *other_rms) +
             " px for the mirrored tilt): add points off their plane, or spread them wider over the image");
  }

  // --- The camera.
  if (options.refine_focal) {
    const std::vector<double> distortion = camera.distortion();
    fit.camera = CameraModel(camera.width_px(), camera.height_px(), focal_scale * camera.fx_px(),
                             focal_scale * camera.fy_px(), camera.cx_px(), camera.cy_px(), distortion);
  } else {
    fit.camera = camera;
  }
  return fit;
}

}  // namespace glasspiv

namespace glasspiv {
namespace {

[[noreturn]] void refuse_rig(const std::string& field, const std::string& problem) {
  throw InputError("", field, problem);
}

std::string observation_name(const std::vector<RigObservation>& observations, int i) {
  const std::string& label = observations[i].label;
  return "observation " + std::to_string(i) + (label.empty() ? "" : " (" + label + ")");
}

void validate_rig(const std::vector<RigCamera>& cameras, const std::vector<RigFiducial>& fiducials,
                  const std::vector<RigObservation>& observations, const RigFitOptions& options) {
  if (!(options.outlier_k == 0 || (std::isfinite(options.outlier_k) && options.outlier_k >= 1)))
    throw InputError("", "outlier_k", "must be 0 (off) or a finite number >= 1");
  if (options.max_iterations < 1) throw InputError("", "max_iterations", "must be at least 1");
  if (options.num_threads < 1) throw InputError("", "num_threads", "must be at least 1");
  if (!(std::isfinite(options.max_position_sigma_mm) && options.max_position_sigma_mm > 0))
    throw InputError("", "max_position_sigma_mm", "must be a finite number > 0");
  if (!(std::isfinite(options.max_rotation_sigma_deg) && options.max_rotation_sigma_deg > 0))
    throw InputError("", "max_rotation_sigma_deg", "must be a finite number > 0");
  if (cameras.empty()) refuse_rig("cameras", "no camera given");
  if (fiducials.empty()) refuse_rig("fiducials", "no fiducial given");
  for (std::size_t c = 0; c < cameras.size(); ++c)
    if (!finite_pose(cameras[c].camera_from_world))
      refuse_rig("cameras", "camera " + std::to_string(c) + " has a non-finite camera_from_world");
  bool any_held = false;
  for (std::size_t f = 0; f < fiducials.size(); ++f) {
    if (!finite_pose(fiducials[f].world_from_fiducial))
      refuse_rig("fiducials", "fiducial " + std::to_string(f) + " has a non-finite world_from_fiducial");
    any_held = any_held || fiducials[f].held;
  }
  if (!any_held)
    refuse_rig("fiducials",
               "no fiducial is held: with every fiducial and camera free the world frame can move with them all "
               "(gauge freedom); hold at least one fiducial at its known place");
  std::vector<int> per_camera(cameras.size(), 0), per_fiducial(fiducials.size(), 0);
  for (std::size_t i = 0; i < observations.size(); ++i) {
    const RigObservation& o = observations[i];
    if (o.camera < 0 || o.camera >= static_cast<int>(cameras.size()))
      refuse_rig("observations", observation_name(observations, i) + " names camera " + std::to_string(o.camera) +
                                     " of " + std::to_string(cameras.size()));
    if (o.fiducial < 0 || o.fiducial >= static_cast<int>(fiducials.size()))
      refuse_rig("observations", observation_name(observations, i) + " names fiducial " +
                                     std::to_string(o.fiducial) + " of " + std::to_string(fiducials.size()));
    if (!o.point_fiducial_mm.allFinite() || !o.pixel_px.allFinite())
      refuse_rig("observations", observation_name(observations, i) + " has a non-finite point or pixel");
    ++per_camera[o.camera];
    ++per_fiducial[o.fiducial];
  }
  for (std::size_t c = 0; c < cameras.size(); ++c)
    if (per_camera[c] < kMinPosePoints)
      refuse_rig("cameras", "camera " + std::to_string(c) + " has " + std::to_string(per_camera[c]) +
                                " observations; a camera pose needs at least " + std::to_string(kMinPosePoints));
  for (std::size_t f = 0; f < fiducials.size(); ++f)
    if (!fiducials[f].held && per_fiducial[f] == 0)
      refuse_rig("fiducials", "fiducial " + std::to_string(f) + " is free but no camera sees it");
}

std::string sigma_problem(const std::string& what, const PoseSigma& sigma, const RigFitOptions& options) {
  return what + " is not determined: position 1-sigma " + format_number("%.3g", sigma.position_sigma_mm.maxCoeff()) +
         " mm (limit " + format_number("%g", options.max_position_sigma_mm) + " mm), rotation 1-sigma " +
         format_number("%.3g", sigma.rotation_sigma_deg) + " deg (limit " +
         format_number("%g", options.max_rotation_sigma_deg) + " deg)";
}

}  // namespace

RigFit fit_rig(const std::vector<RigCamera>& cameras, const std::vector<RigFiducial>& fiducials,
               const std::vector<RigObservation>& observations, const RigFitOptions& options) {
  silence_ceres_logging();
  validate_rig(cameras, fiducials, observations, options);
  const int n = static_cast<int>(observations.size());

  std::vector<PoseBlock> camera_blocks, fiducial_blocks;
  for (const RigCamera& c : cameras) camera_blocks.push_back(pose_block(c.camera_from_world));
  for (const RigFiducial& f : fiducials) fiducial_blocks.push_back(pose_block(f.world_from_fiducial));

  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.enable_fast_removal = true;
  ceres::Problem problem(problem_options);
  // A free fiducial has few points (12 for a square seen by 3 cameras) and 6
  // parameters: in plain least squares one bad corner spreads into its
  // neighbours, and the first verdict drops good points with it. The first
  // round's verdict is therefore taken at a Cauchy-loss optimum.
  const std::unique_ptr<ceres::LossFunction> cauchy(new ceres::CauchyLoss(kRigCauchyScalePx));
  std::vector<double*> free_blocks;  // cameras, then free fiducials: the covariance's order
  for (PoseBlock& b : camera_blocks) {
    problem.AddParameterBlock(b.data(), kPoseParameterCount);
    free_blocks.push_back(b.data());
  }
  std::vector<int> fiducial_slot(fiducials.size(), -1);  // index into free_blocks
  for (std::size_t f = 0; f < fiducials.size(); ++f) {
    problem.AddParameterBlock(fiducial_blocks[f].data(), kPoseParameterCount);
    if (fiducials[f].held) {
      problem.SetParameterBlockConstant(fiducial_blocks[f].data());
    } else {
      fiducial_slot[f] = static_cast<int>(free_blocks.size());
      free_blocks.push_back(fiducial_blocks[f].data());
    }
  }
  const int parameter_count = kPoseParameterCount * static_cast<int>(free_blocks.size());

  std::vector<FitPoint> fit_points(n);
  for (int i = 0; i < n; ++i) {
    const RigObservation& o = observations[i];
    fit_points[i].cost.reset(RigReprojectionCost::Create(cameras[o.camera].camera, o.pixel_px, o.point_fiducial_mm));
  }
  const auto update_residuals = [&] {
    for (int i = 0; i < n; ++i) {
      const double* parameters[2] = {camera_blocks[observations[i].camera].data(),
                                     fiducial_blocks[observations[i].fiducial].data()};
      double r[2];
      FitPoint& f = fit_points[i];
      if (f.cost->Evaluate(parameters, r, nullptr))
        f.residual_px = Eigen::Vector2d(r[0], r[1]);
      else
        f.residual_px.setConstant(std::numeric_limits<double>::infinity());
    }
  };
  const auto add_block = [&](int i, ceres::LossFunction* loss = nullptr) {
    fit_points[i].block = problem.AddResidualBlock(fit_points[i].cost.get(), loss,
                                                   camera_blocks[observations[i].camera].data(),
                                                   fiducial_blocks[observations[i].fiducial].data());
  };
  // The inliers' blocks re-added with `loss` (nullptr: plain least squares).
  const auto set_loss = [&](ceres::LossFunction* loss) {
    for (int i = 0; i < n; ++i)
      if (fit_points[i].block) {
        problem.RemoveResidualBlock(fit_points[i].block);
        add_block(i, loss);
      }
  };
  // The free parameters must stay determined as observations drop out.
  const auto check_count = [&](const char* when) {
    int inliers = 0;
    for (const FitPoint& f : fit_points) inliers += f.block != nullptr;
    if (2 * inliers <= parameter_count)
      refuse_rig("observations", std::to_string(inliers) + " observations" + when + " cannot determine " +
                                     std::to_string(parameter_count) + " pose parameters (6 per camera and free fiducial)");
  };

  RigFit fit;
  update_residuals();
  double start_sum = 0;
  int start_count = 0;
  for (int i = 0; i < n; ++i) {
    if (fit_points[i].residual_px.allFinite()) {
      add_block(i);
      start_sum += fit_points[i].residual_px.squaredNorm();
      ++start_count;
    } else {
      if (options.outlier_k == 0)
        refuse_rig("observations", observation_name(observations, i) + " is behind its camera at the start poses");
      fit_points[i].outlier = true;
    }
  }
  check_count(" in front of their cameras at the start");
  fit.initial_rms_px = std::sqrt(start_sum / start_count);

  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_SCHUR;  // Ceres picks the fiducials to eliminate
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.function_tolerance = 1e-14;
  solver_options.gradient_tolerance = 1e-14;
  solver_options.parameter_tolerance = 1e-14;
  solver_options.num_threads = options.num_threads;
  solver_options.logging_type = ceres::SILENT;
  solver_options.minimizer_progress_to_stdout = false;

  const auto solve_once = [&] {
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options, &problem, &summary);
    fit.iterations += std::max(0, static_cast<int>(summary.iterations.size()) - 1);
    fit.solve_time_s += summary.total_time_in_seconds;
    fit.termination = ceres::TerminationTypeToString(summary.termination_type);
    if (summary.termination_type == ceres::FAILURE)
      refuse_rig("observations", "the solver failed (" + summary.message +
                                     "): check that the pixels belong to the fiducial points and the start poses");
  };
  const auto solve = [&](int round) {
    solve_once();
    if (round == 0 && options.outlier_k > 0) {  // from the least-squares optimum to the robust one
      set_loss(cauchy.get());
      solve_once();
      set_loss(nullptr);
    }
    for (double* b : free_blocks)
      for (int k = 0; k < kPoseParameterCount; ++k)
        if (!std::isfinite(b[k])) refuse_rig("observations", "the fit diverged (non-finite pose)");
    update_residuals();
  };
  const auto candidates = [&] { return outlier_candidates(fit_points); };
  const auto apply = [&](const OutlierVerdict& verdict) {
    apply_outlier_verdict(verdict, problem, fit_points, [&](int i) { add_block(i); });
    check_count(" left after outlier rejection");
  };
  fit.rounds = run_outlier_rounds(options.outlier_k, solve, candidates, apply).rounds;
  if (fit.rounds == 1 && options.outlier_k > 0) {  // the first verdict kept every point: the robust optimum
    solve_once();                                  // is not the least-squares one
    update_residuals();
  }

  // --- The poses and their checks.
  for (const PoseBlock& b : camera_blocks) fit.camera_from_world.push_back(pose_from_block(b.data()));
  for (std::size_t f = 0; f < fiducials.size(); ++f)
    fit.world_from_fiducial.push_back(fiducials[f].held ? fiducials[f].world_from_fiducial
                                                        : pose_from_block(fiducial_blocks[f].data()));
  for (int i = 0; i < n; ++i) {
    const RigObservation& o = observations[i];
    const Eigen::Vector3d p = fit.camera_from_world[o.camera].apply(fit.world_from_fiducial[o.fiducial].apply(o.point_fiducial_mm));
    if (!(p.z() > 0))
      refuse_rig("observations", observation_name(observations, i) + " lies behind camera " +
                                     std::to_string(o.camera) + " at the fitted poses");
  }

  // --- Residual statistics.
  fit.camera_points.assign(cameras.size(), 0);
  fit.fiducial_points.assign(fiducials.size(), 0);
  std::vector<double> camera_sum(cameras.size(), 0), fiducial_sum(fiducials.size(), 0);
  double sum_squares = 0;
  for (int i = 0; i < n; ++i) {
    const RigObservation& o = observations[i];
    const FitPoint& f = fit_points[i];
    const bool outlier = f.block == nullptr;
    fit.residuals.push_back({i, o.camera, o.fiducial, f.residual_px, outlier});
    if (outlier) {
      ++fit.outlier_count;
      continue;
    }
    const double r2 = f.residual_px.squaredNorm();
    ++fit.inlier_count;
    sum_squares += r2;
    ++fit.camera_points[o.camera];
    camera_sum[o.camera] += r2;
    ++fit.fiducial_points[o.fiducial];
    fiducial_sum[o.fiducial] += r2;
  }
  const auto rms = [](double sum, int count) {
    return count > 0 ? std::sqrt(sum / count) : std::numeric_limits<double>::quiet_NaN();
  };
  for (std::size_t c = 0; c < cameras.size(); ++c) fit.camera_rms_px.push_back(rms(camera_sum[c], fit.camera_points[c]));
  for (std::size_t f = 0; f < fiducials.size(); ++f)
    fit.fiducial_rms_px.push_back(rms(fiducial_sum[f], fit.fiducial_points[f]));
  fit.rms_px = std::sqrt(sum_squares / fit.inlier_count);
  fit.sigma_px = std::sqrt(sum_squares / (2 * fit.inlier_count - parameter_count));

  // --- Covariance of all free poses at max(sigma_px, floor).
  const double covariance_sigma = std::max(fit.sigma_px, kObservabilitySigmaFloorPx);
  ceres::Problem::EvaluateOptions evaluate;
  evaluate.parameter_blocks = free_blocks;
  for (const FitPoint& f : fit_points)
    if (f.block) evaluate.residual_blocks.push_back(f.block);
  evaluate.num_threads = options.num_threads;
  ceres::CRSMatrix jacobian;
  if (!problem.Evaluate(evaluate, nullptr, nullptr, nullptr, &jacobian))
    refuse_rig("observations", "the Jacobian at the fitted poses cannot be evaluated");
  const MarginalCovariance covariance = marginal_covariance(jacobian, parameter_count, {}, {}, covariance_sigma);
  fit.reciprocal_condition = covariance.reciprocal_condition;
  if (covariance.covariance.size() == 0 || covariance.undetermined.cols() > 0)
    refuse_rig("observations", "the rig is not determined: the normal equations are singular (reciprocal condition " +
                                   format_number("%.1e", covariance.reciprocal_condition) +
                                   "); every free fiducial needs 3 or more points seen, and every camera 4 or more");
  const auto block_covariance = [&](int slot) {
    return Eigen::MatrixXd(covariance.covariance.block(kPoseParameterCount * slot, kPoseParameterCount * slot,
                                                       kPoseParameterCount, kPoseParameterCount));
  };
  for (std::size_t c = 0; c < cameras.size(); ++c) {
    const PoseSigma sigma = camera_centre_sigma(fit.camera_from_world[c], block_covariance(static_cast<int>(c)));
    if (!(sigma.position_sigma_mm.maxCoeff() <= options.max_position_sigma_mm &&
          sigma.rotation_sigma_deg <= options.max_rotation_sigma_deg))
      refuse_rig("cameras", sigma_problem("camera " + std::to_string(c), sigma, options));
    fit.camera_sigma.push_back(sigma);
  }
  for (std::size_t f = 0; f < fiducials.size(); ++f) {
    if (fiducial_slot[f] < 0) {
      fit.fiducial_sigma.push_back({});
      continue;
    }
    const PoseSigma sigma = origin_sigma(fit.world_from_fiducial[f], block_covariance(fiducial_slot[f]));
    if (!(sigma.position_sigma_mm.maxCoeff() <= options.max_position_sigma_mm &&
          sigma.rotation_sigma_deg <= options.max_rotation_sigma_deg))
      refuse_rig("fiducials", sigma_problem("fiducial " + std::to_string(f), sigma, options));
    fit.fiducial_sigma.push_back(sigma);
  }
  return fit;
}

}  // namespace glasspiv
