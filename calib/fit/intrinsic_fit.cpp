#include "calib/fit/intrinsic_fit.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <optional>
#include <thread>

#include <ceres/ceres.h>

#include "calib/fit/board_pose.h"
#include "calib/fit/ceres_logging.h"
#include "calib/fit/marginal_covariance.h"
#include "calib/fit/outlier_rounds.h"
#include "calib/fit/reprojection_cost.h"
#include "util/input_error.h"
#include "util/stopwatch.h"

namespace glasspiv {
namespace {

std::string format_number(const char* format, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, value);
  return buffer;
}

// "0-12", "1, 4, 7-9": view indices, ascending, runs compressed.
std::string view_list(std::vector<int> views) {
  std::sort(views.begin(), views.end());
  std::string out;
  for (std::size_t i = 0; i < views.size();) {
    std::size_t j = i;
    while (j + 1 < views.size() && views[j + 1] == views[j] + 1) ++j;
    if (!out.empty()) out += ", ";
    out += std::to_string(views[i]);
    if (j > i) out += "-" + std::to_string(views[j]);
    i = j + 1;
  }
  return out;
}

// One corner that takes part in the fit.
struct FitCorner {
  int view = 0;    // index into Observations::views
  int corner = 0;  // index into that view's corners
  int slot = 0;    // index into the used views (its pose block)
  std::unique_ptr<ceres::CostFunction> cost;
  ceres::ResidualBlockId block = nullptr;  // nullptr once dropped
  Eigen::Vector2d residual_px = Eigen::Vector2d::Zero();
  bool outlier = false;
};

// A view with enough corners for a homography and a pose.
struct UsedView {
  int view = 0;
  Eigen::Matrix3d homography;
  std::array<double, kPoseParameterCount> pose{};  // angle-axis, translation mm
  bool active = true;                              // false once outlier rejection emptied it
};

// How far apart two views' board poses are, in pixels: the RMS distance between
// where their homographies put the same board points (each view's own corners,
// the larger of the two). Two photos of an unmoved board give the detector's
// noise; a copied view gives round-off.
double homography_distance_px(const UsedView& a, const UsedView& b, const Observations& observations) {
  const auto rms_over = [&](const UsedView& corners_of) {
    double sum = 0;
    int n = 0;
    for (const CornerObservation& c : observations.views[corners_of.view].corners) {
      const Eigen::Vector3d p(c.board_point_mm.x(), c.board_point_mm.y(), 1.0);
      const Eigen::Vector3d qa = a.homography * p, qb = b.homography * p;
      const double dx = qa[0] / qa[2] - qb[0] / qb[2], dy = qa[1] / qa[2] - qb[1] / qb[2];
      sum += dx * dx + dy * dy;
      ++n;
    }
    return n > 0 ? std::sqrt(sum / n) : std::numeric_limits<double>::infinity();
  };
  const double d = std::max(rms_over(a), rms_over(b));
  return std::isfinite(d) ? d : std::numeric_limits<double>::infinity();
}

// Views grouped by board pose: a view joins the first group whose first view is
// within kSamePoseRmsPx (homography_distance_px). `spread_px` gets, per group,
// the largest distance of a member to the group's first view.
std::vector<std::vector<int>> same_pose_groups(const std::vector<UsedView>& views, const Observations& observations,
                                               std::vector<double>* spread_px) {
  std::vector<std::vector<int>> groups;  // indices into views
  spread_px->clear();
  for (std::size_t i = 0; i < views.size(); ++i) {
    bool placed = false;
    for (std::size_t g = 0; g < groups.size() && !placed; ++g) {
      const double d = homography_distance_px(views[groups[g][0]], views[i], observations);
      if (d < kSamePoseRmsPx) {
        groups[g].push_back(static_cast<int>(i));
        (*spread_px)[g] = std::max((*spread_px)[g], d);
        placed = true;
      }
    }
    if (!placed) {
      groups.push_back({static_cast<int>(i)});
      spread_px->push_back(0);
    }
  }
  return groups;
}

void validate(const Observations& observations) {
  if (observations.image_width_px <= 0 || observations.image_height_px <= 0)
    throw InputError("", "image size", "must be a positive number of pixels");
  for (std::size_t v = 0; v < observations.views.size(); ++v)
    for (std::size_t c = 0; c < observations.views[v].corners.size(); ++c) {
      const CornerObservation& corner = observations.views[v].corners[c];
      const std::string field = "views[" + std::to_string(v) + "].corners[" + std::to_string(c) + "]";
      if (!corner.pixel_px.allFinite() || !corner.board_point_mm.allFinite())
        throw InputError("", field, "has a non-finite pixel or board point");
      if (corner.board_point_mm.z() != 0)
        throw InputError("", field + ".board_point_mm",
                         "has z != 0: the intrinsic fit needs a planar board with its points at z = 0");
    }
}

// Zhang's closed form with the principal point known (as cv::initCameraMatrix2D):
// each homography gives two linear equations in (1/fx^2, 1/fy^2) from the
// orthogonality and equal length of the board axes. `aspect_ratio` > 0 ties
// fy = a fx. Returns false if the solution is not positive (degenerate views,
// typically all fronto-parallel).
bool closed_form_focal(const std::vector<UsedView>& views, double cx, double cy, double aspect_ratio, double* fx,
                       double* fy) {
  Eigen::MatrixXd a(2 * views.size(), 2);
  Eigen::VectorXd b(2 * views.size());
  for (std::size_t i = 0; i < views.size(); ++i) {
    Eigen::Matrix3d h = views[i].homography;
    h.row(0) -= cx * h.row(2);
    h.row(1) -= cy * h.row(2);
    const Eigen::Vector3d h1 = h.col(0).normalized(), h2 = h.col(1).normalized();
    const Eigen::Vector3d d1 = (h1 + h2).normalized(), d2 = (h1 - h2).normalized();
    a.row(2 * i) << h1.x() * h2.x(), h1.y() * h2.y();
    b(2 * i) = -h1.z() * h2.z();
    a.row(2 * i + 1) << d1.x() * d2.x(), d1.y() * d2.y();
    b(2 * i + 1) = -d1.z() * d2.z();
  }
  double inv_fx2, inv_fy2;
  if (aspect_ratio > 0) {
    const Eigen::VectorXd column = a.col(0) + a.col(1) / (aspect_ratio * aspect_ratio);
    inv_fx2 = column.dot(b) / column.squaredNorm();
    inv_fy2 = inv_fx2 / (aspect_ratio * aspect_ratio);
  } else {
    const Eigen::Vector2d x = a.colPivHouseholderQr().solve(b);
    inv_fx2 = x(0);
    inv_fy2 = x(1);
  }
  if (!(std::isfinite(inv_fx2) && std::isfinite(inv_fy2) && inv_fx2 > 0 && inv_fy2 > 0)) return false;
  *fx = 1 / std::sqrt(inv_fx2);
  *fy = 1 / std::sqrt(inv_fy2);
  return std::isfinite(*fx) && std::isfinite(*fy);
}

// The covariance of the tangent-space intrinsics with the board poses
// marginalised (calib/fit/marginal_covariance.h), at the current parameters.
MarginalCovariance marginal_intrinsics_covariance(ceres::Problem& problem, double* intrinsics,
                                                  const std::vector<UsedView>& views,
                                                  const std::vector<FitCorner>& corners, double sigma_px,
                                                  int num_threads) {
  ceres::Problem::EvaluateOptions evaluate;
  evaluate.parameter_blocks.push_back(intrinsics);
  std::vector<int> active_slot(views.size(), -1);
  int active = 0;
  for (std::size_t s = 0; s < views.size(); ++s)
    if (views[s].active) {
      evaluate.parameter_blocks.push_back(const_cast<double*>(views[s].pose.data()));
      active_slot[s] = active++;
    }
  // Residual blocks grouped by view (corners are stored view by view).
  std::vector<int> rows_per_active(active, 0);
  for (const FitCorner& c : corners)
    if (c.block) {
      evaluate.residual_blocks.push_back(c.block);
      rows_per_active[active_slot[c.slot]] += 2;
    }
  evaluate.num_threads = num_threads;
  ceres::CRSMatrix jacobian;
  // Fails when a corner lies behind the camera at the fitted poses.
  if (!problem.Evaluate(evaluate, nullptr, nullptr, nullptr, &jacobian)) return {};
  const int m = jacobian.num_cols - kPoseParameterCount * active;
  return marginal_covariance(jacobian, m, std::vector<int>(active, kPoseParameterCount), rows_per_active, sigma_px,
                             kMinReciprocalCondition);
}

// Beyond this fit RMS the corners are not one board seen by one camera (a
// detector is off by a fraction of a pixel, a lens model by a few pixels).
constexpr double kInconsistentRmsPx = 10;

[[noreturn]] void throw_unobservable(const std::string& detail, const IntrinsicFit& fit, int views) {
  std::string problem = "the focal length is not determined by these views (" + detail + "; fit RMS " +
                        format_number("%.3g", fit.rms_px) + " px";
  if (fit.termination != "CONVERGENCE") problem += ", the solver stopped with " + fit.termination;
  if (fit.rms_px > kInconsistentRmsPx)
    throw InputError("", "views",
                     problem + "): the corners do not fit one board seen by one camera (RMS above " +
                         format_number("%g", kInconsistentRmsPx) +
                         " px): check the corner ids, the board points and the target spec");
  problem +=
      "): views are nearly fronto-parallel, or all tilted alike: tilt the board by 20-40 degrees in some views, "
      "in different directions";
  if (views < 5) problem += ", and use more views (" + std::to_string(views) + " used)";
  if (fit.termination != "CONVERGENCE")
    problem += "; if they are tilted, the lens model or the held parameters may not suit the lens";
  throw InputError("", "views", problem);
}

}  // namespace

Eigen::MatrixXd StateCovariance::dense() const {
  const int m = static_cast<int>(intrinsics.rows()), n = static_cast<int>(views.size());
  Eigen::MatrixXd out(m + kPoseParameterCount * n, m + kPoseParameterCount * n);
  out.topLeftCorner(m, m) = intrinsics;
  for (int v = 0; v < n; ++v) {
    const Eigen::MatrixXd cross = -intrinsics * pose_from_intrinsics[v].transpose();
    out.block(0, m + 6 * v, m, 6) = cross;
    out.block(m + 6 * v, 0, 6, m) = cross.transpose();
    for (int w = 0; w < n; ++w)
      out.block(m + 6 * v, m + 6 * w, 6, 6) =
          pose_from_intrinsics[v] * intrinsics * pose_from_intrinsics[w].transpose() +
          (v == w ? pose_alone[v] : Eigen::Matrix<double, 6, 6>::Zero());
  }
  return out;
}

std::string intrinsic_name(int index) {
  static const char* names[] = {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2",    "k3",
                                "k4", "k5", "k6", "s1", "s2", "s3", "s4", "tau_x", "tau_y"};
  return index >= 0 && index < 4 + kMaxDistortionCoefficients ? names[index] : "?";
}

IntrinsicFit fit_intrinsics(const Observations& observations, const IntrinsicFitOptions& options) {
  const Stopwatch clock;
  silence_ceres_logging();
  validate(observations);
  const int width = observations.image_width_px, height = observations.image_height_px;
  const int distortion_count = static_cast<int>(options.lens_model);
  const int intrinsic_count = 4 + distortion_count;
  if (options.initial_camera &&
      (options.initial_camera->width_px() != width || options.initial_camera->height_px() != height))
    throw InputError("", "initial_camera",
                     "is " + std::to_string(options.initial_camera->width_px()) + "x" +
                         std::to_string(options.initial_camera->height_px()) + " px but the observations are " +
                         std::to_string(width) + "x" + std::to_string(height) + " px");
  if (!(options.outlier_k == 0 || (std::isfinite(options.outlier_k) && options.outlier_k >= 1)))
    throw InputError("", "outlier_k", "must be 0 (off) or a finite number >= 1");
  if (options.max_iterations < 1) throw InputError("", "max_iterations", "must be at least 1");
  const int threads = options.num_threads > 0 ? options.num_threads
                                              : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));

  // --- Views with enough corners for a homography.
  std::vector<SkippedView> skipped;
  std::vector<UsedView> views;
  for (std::size_t v = 0; v < observations.views.size(); ++v) {
    const auto& corners = observations.views[v].corners;
    if (static_cast<int>(corners.size()) < kMinCornersPerView) {
      skipped.push_back({static_cast<int>(v), "has " + std::to_string(corners.size()) +
                                                  " corners; a board pose needs at least " +
                                                  std::to_string(kMinCornersPerView)});
      continue;
    }
    const std::optional<Eigen::Matrix3d> h = board_homography(corners);
    if (!h) {
      skipped.push_back({static_cast<int>(v), "its corners give no homography (collinear or repeated points)"});
      continue;
    }
    UsedView used;
    used.view = static_cast<int>(v);
    used.homography = *h;
    views.push_back(used);
  }
  const auto check_view_count = [&](std::size_t count, const char* when) {
    if (count == 0)
      throw InputError("", "views",
                       std::string("no usable view") + when + " (" + std::to_string(observations.views.size()) +
                           " given); an intrinsic fit needs at least 2 views of a tilted board");
    if (count == 1 && !options.fix_principal_point)
      throw InputError("", "views",
                       std::string("only 1 usable view") + when +
                           ": with a free principal point one view is degenerate; use at least 2 "
                           "(better 10 or more) views, or fix the principal point");
  };
  check_view_count(views.size(), "");

  // --- Initial intrinsics.
  std::vector<double> intrinsics(intrinsic_count, 0.0);
  double aspect_ratio = 0;
  if (options.initial_camera) {
    const CameraModel& init = *options.initial_camera;
    for (int i = 0; i < 4; ++i) intrinsics[i] = init.intrinsics()[i];
    for (int i = 0; i < std::min(distortion_count, init.distortion_count()); ++i)
      intrinsics[4 + i] = init.intrinsics()[4 + i];
    if (options.fix_aspect_ratio) aspect_ratio = init.fy_px() / init.fx_px();
  } else {
    intrinsics[2] = (width - 1) / 2.0;
    intrinsics[3] = (height - 1) / 2.0;
    if (options.fix_aspect_ratio) aspect_ratio = 1.0;
    double fx, fy;
    if (!closed_form_focal(views, intrinsics[2], intrinsics[3], aspect_ratio, &fx, &fy)) {
      // Degenerate homographies: start from a 53-degree field of view and let the
      // observability check below judge the result.
      fx = std::max(width, height);
      fy = aspect_ratio > 0 ? aspect_ratio * fx : fx;
    }
    intrinsics[0] = fx;
    intrinsics[1] = fy;
  }
  if (options.zero_tangential && distortion_count >= 4) intrinsics[6] = intrinsics[7] = 0;
  if (aspect_ratio > 0) intrinsics[1] = aspect_ratio * intrinsics[0];

  // --- Initial board poses (IPPE on the undistorted model unless a camera was given).
  {
    std::vector<double> distortion;
    if (options.initial_camera && distortion_count > 0) distortion.assign(intrinsics.begin() + 4, intrinsics.end());
    const CameraModel start(width, height, intrinsics[0], intrinsics[1], intrinsics[2], intrinsics[3], distortion);
    std::vector<UsedView> posed;
    for (UsedView& used : views) {
      const std::optional<BoardPose> pose = board_pose_ippe(start, observations.views[used.view].corners);
      if (!pose) {
        skipped.push_back({used.view, "no board pose could be found from its corners"});
        continue;
      }
      for (int i = 0; i < 3; ++i) {
        used.pose[i] = pose->rvec(i);
        used.pose[3 + i] = pose->translation_mm(i);
      }
      posed.push_back(used);
    }
    views = std::move(posed);
  }
  check_view_count(views.size(), " with a board pose");

  // --- Views of one board pose (a photo copied, or the board not moved) count
  // once: repeating a view adds no geometry, only false confidence (13 copies of
  // one view fit a focal length 75% off with a 1-sigma of 3%).
  std::vector<double> group_spread_px;
  const std::vector<std::vector<int>> pose_groups = same_pose_groups(views, observations, &group_spread_px);
  const int distinct_views = static_cast<int>(pose_groups.size());
  if (distinct_views == 1 && !options.fix_principal_point) {
    std::vector<int> members;
    for (int i : pose_groups[0]) members.push_back(views[i].view);
    throw InputError("", "views",
                     "views " + view_list(members) + " are one board pose (their homographies agree to " +
                         format_number("%.1e", group_spread_px[0]) + " px RMS, below " +
                         format_number("%g", kSamePoseRmsPx) +
                         " px): 1 distinct view, and with a free principal point one view cannot determine the "
                         "focal length; move and tilt the board by 20-40 degrees between photos (10 or more "
                         "distinct views), or fix the principal point");
  }
  std::sort(skipped.begin(), skipped.end(), [](const SkippedView& a, const SkippedView& b) { return a.view < b.view; });

  // --- The problem.
  std::vector<int> constant;  // indices into the intrinsics block held fixed
  if (aspect_ratio > 0) constant.push_back(1);
  if (options.fix_principal_point) {
    constant.push_back(2);
    constant.push_back(3);
  }
  if (options.zero_tangential && distortion_count >= 4) {
    constant.push_back(6);
    constant.push_back(7);
  }
  std::vector<int> free_intrinsics;
  for (int i = 0; i < intrinsic_count; ++i)
    if (std::find(constant.begin(), constant.end(), i) == constant.end()) free_intrinsics.push_back(i);

  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.enable_fast_removal = true;
  ceres::Problem problem(problem_options);
  problem.AddParameterBlock(intrinsics.data(), intrinsic_count);
  if (!constant.empty()) problem.SetManifold(intrinsics.data(), new ceres::SubsetManifold(intrinsic_count, constant));

  std::vector<FitCorner> corners;
  corners.reserve(observations.corner_count());
  for (std::size_t slot = 0; slot < views.size(); ++slot) {
    problem.AddParameterBlock(views[slot].pose.data(), kPoseParameterCount);
    const auto& view_corners = observations.views[views[slot].view].corners;
    for (std::size_t c = 0; c < view_corners.size(); ++c) {
      FitCorner corner;
      corner.view = views[slot].view;
      corner.corner = static_cast<int>(c);
      corner.slot = static_cast<int>(slot);
      corner.cost.reset(create_reprojection_cost(options.lens_model, view_corners[c].pixel_px,
                                                 view_corners[c].board_point_mm, aspect_ratio));
      corner.block = problem.AddResidualBlock(corner.cost.get(), nullptr, intrinsics.data(), views[slot].pose.data());
      corners.push_back(std::move(corner));
    }
  }
  const auto free_parameter_count = [&] {
    int active = 0;
    for (const UsedView& v : views) active += v.active;
    return static_cast<int>(free_intrinsics.size()) + kPoseParameterCount * active;
  };
  if (2 * static_cast<int>(corners.size()) <= free_parameter_count())
    throw InputError("", "views",
                     std::to_string(corners.size()) + " corners in " + std::to_string(views.size()) +
                         " views cannot determine " + std::to_string(free_parameter_count()) +
                         " parameters (the intrinsics and 6 per board pose); add views or corners");

  // Residuals of all corners (dropped ones too) at the current parameters.
  const auto update_residuals = [&] {
    for (FitCorner& c : corners) {
      if (!views[c.slot].active) continue;
      const double* parameters[2] = {intrinsics.data(), views[c.slot].pose.data()};
      double r[2];
      if (c.cost->Evaluate(parameters, r, nullptr))
        c.residual_px = Eigen::Vector2d(r[0], r[1]);
      else
        c.residual_px.setConstant(std::numeric_limits<double>::infinity());  // behind the camera
    }
  };
  const auto inlier_rms = [&] {
    double sum = 0;
    int n = 0;
    for (const FitCorner& c : corners)
      if (c.block) {
        sum += c.residual_px.squaredNorm();
        ++n;
      }
    return n > 0 ? std::sqrt(sum / n) : 0.0;
  };

  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_SCHUR;
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  for (UsedView& v : views) ordering->AddElementToGroup(v.pose.data(), 0);  // eliminated first
  ordering->AddElementToGroup(intrinsics.data(), 1);
  solver_options.linear_solver_ordering = ordering;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.function_tolerance = 1e-12;
  solver_options.gradient_tolerance = 1e-12;
  solver_options.parameter_tolerance = 1e-12;
  solver_options.num_threads = threads;
  solver_options.logging_type = ceres::SILENT;
  solver_options.minimizer_progress_to_stdout = false;

  IntrinsicFit fit(CameraModel(width, height, 1, 1, 0, 0));
  fit.distinct_views = distinct_views;
  update_residuals();
  fit.initial_rms_px = inlier_rms();

  const auto add_summary = [&](const ceres::Solver::Summary& summary) {
    fit.iterations += std::max(0, static_cast<int>(summary.iterations.size()) - 1);
    fit.solver_time_s += summary.total_time_in_seconds;
    fit.termination = ceres::TerminationTypeToString(summary.termination_type);
    // FAILURE: the cost could not be evaluated (corners behind the camera at
    // the start) or the linear solver failed for good; the parameters are not a fit.
    if (summary.termination_type == ceres::FAILURE)
      throw InputError("", "views",
                       "the solver failed (" + summary.message +
                           "): the corners do not fit one board seen by one camera; check the corner ids, the "
                           "board points and the target spec");
  };

  // --- Rational, thin-prism and tilt models: first converge with only k1 k2 p1
  // p2 k3 free (the rest held at their start, zero without an initial camera).
  // Released all at once from zero distortion, the rational denominator sends
  // about one synthetic calibration in six into a region where the reduced
  // normal matrix is not positive definite and the solver fails.
  if (distortion_count > 5) {
    std::vector<int> staged = constant;
    for (int i = 4 + 5; i < intrinsic_count; ++i) staged.push_back(i);
    problem.SetManifold(intrinsics.data(), new ceres::SubsetManifold(intrinsic_count, staged));
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options, &problem, &summary);
    add_summary(summary);
    problem.SetManifold(intrinsics.data(),
                        constant.empty() ? nullptr : new ceres::SubsetManifold(intrinsic_count, constant));
  }

  // --- Solve, drop outliers, repeat (calib/fit/outlier_rounds.h).
  const auto solve = [&](int round) {
    // Later rounds start at the optimum of a problem with a few corners more:
    // near-Gauss-Newton steps (a wide initial trust region) finish them in ~2
    // iterations instead of ~12 crawling along the rational models' valleys.
    if (round > 0) solver_options.initial_trust_region_radius = 1e12;
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options, &problem, &summary);
    add_summary(summary);
    for (double p : intrinsics)
      if (!std::isfinite(p))
        throw InputError("", "views",
                         "the fit diverged (non-finite intrinsics); check the corner ids and board points");
    update_residuals();
  };
  // The corners of the views that still have a pose, in storage order.
  const auto candidates = [&] {
    std::vector<OutlierCandidate> out;
    for (const FitCorner& c : corners)
      if (views[c.slot].active) out.push_back({c.residual_px.norm(), c.block == nullptr});
    return out;
  };
  const auto apply = [&](const OutlierVerdict& verdict) {
    std::vector<int> inliers_per_slot(views.size(), 0);
    std::size_t i = 0;
    for (FitCorner& c : corners) {
      if (!views[c.slot].active) continue;
      const bool outlier = verdict.outlier[i++];
      if (outlier && c.block) {
        problem.RemoveResidualBlock(c.block);
        c.block = nullptr;
      } else if (!outlier && !c.block) {
        c.block = problem.AddResidualBlock(c.cost.get(), nullptr, intrinsics.data(), views[c.slot].pose.data());
      }
      c.outlier = outlier;
      if (!outlier) ++inliers_per_slot[c.slot];
    }
    // A view left with too few corners loses its pose (it would be undetermined).
    for (std::size_t slot = 0; slot < views.size(); ++slot) {
      if (!views[slot].active || inliers_per_slot[slot] >= kMinCornersPerView) continue;
      views[slot].active = false;
      for (FitCorner& c : corners)
        if (static_cast<int>(slot) == c.slot && c.block) {
          problem.RemoveResidualBlock(c.block);
          c.block = nullptr;
        }
      problem.RemoveParameterBlock(views[slot].pose.data());
      ordering->Remove(views[slot].pose.data());
      skipped.push_back({views[slot].view,
                         "fewer than " + std::to_string(kMinCornersPerView) + " corners left after outlier rejection"});
    }
    if (!verdict.changed()) return;
    int active = 0;
    for (const UsedView& v : views) active += v.active;
    check_view_count(static_cast<std::size_t>(active), " after outlier rejection");
  };
  const OutlierRoundsLog log = run_outlier_rounds(options.outlier_k, solve, candidates, apply);
  fit.rounds = log.rounds;
  fit.dropped_per_round = log.dropped_per_round;
  fit.readmitted_per_round = log.readmitted_per_round;
  fit.threshold_px_per_round = log.threshold_px_per_round;
  std::sort(skipped.begin(), skipped.end(), [](const SkippedView& a, const SkippedView& b) { return a.view < b.view; });

  // --- Statistics.
  double sum_squares = 0;
  int inliers = 0, outliers = 0;
  for (const FitCorner& c : corners) {
    if (!views[c.slot].active) continue;
    if (c.block) {
      sum_squares += c.residual_px.squaredNorm();
      ++inliers;
    } else {
      ++outliers;
    }
  }
  const int degrees_of_freedom = 2 * inliers - free_parameter_count();
  if (degrees_of_freedom <= 0)
    throw InputError("", "views", "too few corners remain after outlier rejection to determine the parameters");
  fit.inlier_count = inliers;
  fit.outlier_count = outliers;
  fit.rms_px = std::sqrt(sum_squares / inliers);
  fit.sigma_px = std::sqrt(sum_squares / degrees_of_freedom);
  {
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    for (const FitCorner& c : corners)
      if (views[c.slot].active && c.block) sum += c.residual_px;
    const double mean = sum.sum() / (2.0 * inliers);
    fit.residual_std_px = std::sqrt(std::max(0.0, sum_squares / (2.0 * inliers) - mean * mean));
  }

  // --- Observability: the focal length's 1-sigma from the marginal covariance.
  int active_views = 0;
  for (const UsedView& v : views) active_views += v.active;
  const double check_sigma = std::max(fit.sigma_px, kObservabilitySigmaFloorPx);
  const MarginalCovariance check =
      marginal_intrinsics_covariance(problem, intrinsics.data(), views, corners, check_sigma, threads);
  fit.reciprocal_condition = check.reciprocal_condition;
  if (check.covariance.size() == 0)
    throw_unobservable("the normal equations of the intrinsics are zero, not finite or not evaluable", fit,
                       active_views);
  if (check.undetermined.cols() > 0) {
    const std::string condition = "reciprocal condition " + format_number("%.1e", check.reciprocal_condition);
    // Does the undetermined subspace contain the focal length?
    double focal_share = check.undetermined.row(0).squaredNorm();
    if (free_intrinsics.size() > 1 && free_intrinsics[1] == 1) focal_share += check.undetermined.row(1).squaredNorm();
    if (focal_share > 0.1)
      throw_unobservable("the normal equations are singular, " + condition + " < " +
                             format_number("%.0e", kMinReciprocalCondition),
                         fit, active_views);
    // Otherwise a trade-off among distortion coefficients (a rational model on
    // a lens that does not need it): keep the fit, name them.
    for (int i = 0; i < check.undetermined.rows(); ++i)
      if (check.undetermined.row(i).cwiseAbs().maxCoeff() > 0.3)
        fit.undetermined_parameters.push_back(intrinsic_name(free_intrinsics[i]));
  }
  fit.fx_sigma_px = std::sqrt(check.covariance(0, 0));  // fx is always the first free intrinsic
  if (!(fit.fx_sigma_px <= kMaxRelativeFocalSigma * intrinsics[0]))
    throw_unobservable("1-sigma of fx = " + format_number("%.3g", 100 * fit.fx_sigma_px / intrinsics[0]) +
                           "% of fx > " + format_number("%g", 100 * kMaxRelativeFocalSigma) + "% at " +
                           format_number("%.3g", check_sigma) + " px noise; reciprocal condition " +
                           format_number("%.1e", check.reciprocal_condition),
                       fit, active_views);

  // --- Covariance of the free intrinsics: the same Schur complement at the
  // estimated sigma. (ceres::Covariance gives the same matrix on well-scaled
  // problems, see the tests, but its SuiteSparseQR rank test is not scale
  // invariant: it declares long lenses rank deficient and logs to stderr.)
  if (options.compute_uncertainty) {
    fit.intrinsics_covariance = check.covariance * (fit.sigma_px * fit.sigma_px) / (check_sigma * check_sigma);
    StateCovariance& state = fit.state_covariance;
    state.intrinsics = check.covariance / (check_sigma * check_sigma);
    std::size_t block = 0;  // the eliminated blocks are the active views in order
    for (const UsedView& v : views) {
      if (!v.active) continue;
      if (block >= check.eliminated_inverse.size() || check.eliminated_inverse[block].rows() != kPoseParameterCount)
        throw InputError("", "views", "the covariance of the board poses could not be evaluated");
      state.views.push_back(v.view);
      state.camera_from_board.push_back(v.pose);
      state.pose_alone.push_back(check.eliminated_inverse[block]);
      state.pose_from_intrinsics.push_back(check.eliminated_from_kept[block]);
      ++block;
    }
  }

  // --- The result.
  if (aspect_ratio > 0) intrinsics[1] = aspect_ratio * intrinsics[0];
  if (!(intrinsics[0] > 0 && intrinsics[1] > 0))
    throw InputError("", "views", "the fit ended with a non-positive focal length; the views do not constrain it");
  fit.camera = CameraModel(width, height, intrinsics[0], intrinsics[1], intrinsics[2], intrinsics[3],
                           std::vector<double>(intrinsics.begin() + 4, intrinsics.end()));
  fit.free_intrinsics = free_intrinsics;
  fit.aspect_ratio = aspect_ratio;
  fit.skipped_views = std::move(skipped);
  fit.camera_from_board.assign(observations.views.size(), RigidTransform{});
  fit.view_rms_px.assign(observations.views.size(), std::numeric_limits<double>::quiet_NaN());
  std::vector<double> view_sum(observations.views.size(), 0);
  std::vector<int> view_count(observations.views.size(), 0);
  for (const UsedView& v : views) {
    if (!v.active) continue;
    const Eigen::Vector3d rvec(v.pose[0], v.pose[1], v.pose[2]), tvec(v.pose[3], v.pose[4], v.pose[5]);
    if (!rvec.allFinite() || !tvec.allFinite())
      throw InputError("", "views", "the fit diverged (non-finite board pose of view " + std::to_string(v.view) + ")");
    fit.camera_from_board[v.view] = RigidTransform::from_rvec_tvec(rvec, tvec);
  }
  for (const FitCorner& c : corners) {
    if (!views[c.slot].active) continue;
    fit.residuals.push_back(
        {c.view, c.corner, observations.views[c.view].corners[c.corner].id, c.residual_px, c.outlier});
    if (!c.outlier) {
      view_sum[c.view] += c.residual_px.squaredNorm();
      ++view_count[c.view];
    }
  }
  for (std::size_t v = 0; v < view_sum.size(); ++v)
    if (view_count[v] > 0) fit.view_rms_px[v] = std::sqrt(view_sum[v] / view_count[v]);
  fit.total_time_s = clock.seconds();
  return fit;
}

}  // namespace glasspiv
