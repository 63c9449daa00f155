#include "calib/fit/multi_start.h"

#include <algorithm>
#include <cstdio>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <random>
#include <thread>
#include <utility>

#include <Eigen/Eigenvalues>
#include <ceres/ceres.h>

#include "calib/fit/ceres_logging.h"
#include "calib/fit/reprojection_cost.h"
#include "util/input_error.h"
#include "util/stopwatch.h"

namespace glasspiv {
namespace {

// The regularisation as one residual block on the intrinsics: w_j (x_j - target_j)
// for each penalised slot (a linear residual, its Jacobian diagonal).
class RegularisationCost : public ceres::CostFunction {
 public:
  struct Term {
    int slot = 0;
    double weight = 0, target = 0;
  };
  RegularisationCost(int intrinsic_count, std::vector<Term> terms) : terms_(std::move(terms)) {
    set_num_residuals(static_cast<int>(terms_.size()));
    mutable_parameter_block_sizes()->push_back(intrinsic_count);
    intrinsic_count_ = intrinsic_count;
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    for (std::size_t i = 0; i < terms_.size(); ++i)
      residuals[i] = terms_[i].weight * (parameters[0][terms_[i].slot] - terms_[i].target);
    if (jacobians && jacobians[0]) {
      std::fill(jacobians[0], jacobians[0] + terms_.size() * intrinsic_count_, 0.0);
      for (std::size_t i = 0; i < terms_.size(); ++i) jacobians[0][i * intrinsic_count_ + terms_[i].slot] = terms_[i].weight;
    }
    return true;
  }

 private:
  std::vector<Term> terms_;
  int intrinsic_count_ = 0;
};

// The observations without the corners `fit` marks as outliers (views keep
// their index; a view the fit skipped keeps no corners).
Observations inlier_observations(const Observations& observations, const IntrinsicFit& fit) {
  Observations out = observations;
  for (ViewObservations& v : out.views) v.corners.clear();
  for (const ObservationResidual& r : fit.residuals)
    if (!r.outlier) out.views[r.view].corners.push_back(observations.views[r.view].corners[r.corner_index]);
  return out;
}

std::string fmt_step(double step) {
  char text[64];
  std::snprintf(text, sizeof text, "valley step %+.3g", step);
  return text;
}

}  // namespace

bool is_rich_lens_model(LensModel model) { return static_cast<int>(model) > 5; }

RegularisationWeights mrcal_regularisation_weights(LensModel model, int corner_count, double scale) {
  const double measurements = 2.0 * corner_count;
  const int distortion_count = static_cast<int>(model);
  RegularisationWeights w;
  // mrcal: the expected pixel cost N * 1 px^2, of which 0.5 % is shared by the
  // two kinds of regularisation; a typical coefficient is 2, a typical
  // principal-point offset 500 px.
  const double share = 0.005 / 2 * measurements;
  if (distortion_count > 0) w.distortion = scale * std::sqrt(share / (distortion_count * 2.0 * 2.0));
  w.denominator = 5 * w.distortion;  // mrcal favours a denominator near 1: no 0/0 ratios
  w.centre = scale * std::sqrt(share / (2 * 500.0 * 500.0));
  return w;
}

namespace {

// The flattest direction of the cost at a minimum: the eigenvector of the
// smallest eigenvalue of the Jacobi-scaled reduced normal matrix of the free
// intrinsics (the board poses eliminated: S = Jc'Jc - sum_v Jc'Jv (Jv'Jv)^-1 Jv'Jc),
// with the poses' first-order response dp_v = -(Jv'Jv)^-1 Jv'Jc dc, so that a
// step along it stays on the valley floor to first order. For the rational
// models it is the trade of numerator against denominator.
struct ValleyDirection {
  Eigen::VectorXd intrinsics;                  // full intrinsics block (held slots 0)
  std::vector<Eigen::Matrix<double, 6, 1>> poses;  // per view (zero for views without corners)
};

ValleyDirection flattest_direction(ceres::Problem& problem, const std::vector<double>& intrinsics,
                                   std::vector<std::array<double, kPoseParameterCount>>& poses,
                                   const Observations& observations, const std::vector<int>& held) {
  const int intrinsic_count = static_cast<int>(intrinsics.size());
  std::vector<int> free;
  for (int i = 0; i < intrinsic_count; ++i)
    if (std::find(held.begin(), held.end(), i) == held.end()) free.push_back(i);
  const int m = static_cast<int>(free.size());
  ceres::Problem::EvaluateOptions evaluate;
  evaluate.parameter_blocks.push_back(const_cast<double*>(intrinsics.data()));
  std::vector<int> views;
  for (std::size_t v = 0; v < observations.views.size(); ++v)
    if (!observations.views[v].corners.empty()) {
      evaluate.parameter_blocks.push_back(poses[v].data());
      views.push_back(static_cast<int>(v));
    }
  ceres::CRSMatrix crs;
  problem.Evaluate(evaluate, nullptr, nullptr, nullptr, &crs);
  Eigen::MatrixXd j = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
  for (int r = 0; r < crs.num_rows; ++r)
    for (int k = crs.rows[r]; k < crs.rows[r + 1]; ++k) j(r, crs.cols[k]) = crs.values[k];
  const Eigen::MatrixXd a = j.transpose() * j;  // columns: m free intrinsics, then 6 per view
  Eigen::MatrixXd s = a.topLeftCorner(m, m);
  std::vector<Eigen::MatrixXd> response(views.size());  // (Jv'Jv)^-1 Jv'Jc
  for (std::size_t k = 0; k < views.size(); ++k) {
    const int at = m + 6 * static_cast<int>(k);
    response[k] = a.block(at, at, 6, 6).ldlt().solve(a.block(at, 0, 6, m));
    s -= a.block(0, at, m, 6) * response[k];
  }
  const Eigen::VectorXd d = s.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(d.asDiagonal() * s * d.asDiagonal());
  const Eigen::VectorXd dc = d.asDiagonal() * eigen.eigenvectors().col(0);
  ValleyDirection out;
  out.intrinsics = Eigen::VectorXd::Zero(intrinsic_count);
  for (int i = 0; i < m; ++i) out.intrinsics(free[i]) = dc(i);
  // Unit step: the largest distortion coefficient moves by 1.
  const double largest = out.intrinsics.tail(intrinsic_count - 4).cwiseAbs().maxCoeff();
  const double unit = largest > 0 ? 1.0 / largest : 1.0;
  out.intrinsics *= unit;
  out.poses.assign(observations.views.size(), Eigen::Matrix<double, 6, 1>::Zero());
  for (std::size_t k = 0; k < views.size(); ++k) out.poses[views[k]] = -unit * response[k] * dc;
  return out;
}

// The least-squares fit from `start` and its poses, all free coefficients at
// once (no staging), with mrcal's regularisation times `scale` (0: none).
// `camera_from_board` receives the fitted poses.
CameraModel solve_from(const Observations& observations, const IntrinsicFitOptions& options, const CameraModel& start,
                       const std::vector<RigidTransform>& start_camera_from_board, double scale,
                       std::vector<RigidTransform>* camera_from_board, ValleyDirection* valley = nullptr) {
  silence_ceres_logging();
  if (start_camera_from_board.size() != observations.views.size())
    throw InputError("", "views", "the start has " + std::to_string(start_camera_from_board.size()) +
                                      " board poses for " + std::to_string(observations.views.size()) + " views");
  const LensModel model = options.lens_model;
  const int distortion_count = static_cast<int>(model);
  const int intrinsic_count = 4 + distortion_count;
  std::vector<double> intrinsics(intrinsic_count, 0.0);
  for (int i = 0; i < 4; ++i) intrinsics[i] = start.intrinsics()[i];
  for (int i = 0; i < std::min(distortion_count, start.distortion_count()); ++i)
    intrinsics[4 + i] = start.intrinsics()[4 + i];
  const double aspect_ratio = options.fix_aspect_ratio ? start.fy_px() / start.fx_px() : 0.0;
  if (options.zero_tangential && distortion_count >= 4) intrinsics[6] = intrinsics[7] = 0;

  std::vector<int> held;
  if (aspect_ratio > 0) held.push_back(1);
  if (options.fix_principal_point) held.insert(held.end(), {2, 3});
  if (options.zero_tangential && distortion_count >= 4) held.insert(held.end(), {6, 7});
  const auto is_held = [&](int slot) { return std::find(held.begin(), held.end(), slot) != held.end(); };

  ceres::Problem problem;
  problem.AddParameterBlock(intrinsics.data(), intrinsic_count);
  if (!held.empty()) problem.SetManifold(intrinsics.data(), new ceres::SubsetManifold(intrinsic_count, held));
  std::vector<std::array<double, kPoseParameterCount>> poses(observations.views.size());
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  int corner_count = 0;
  for (std::size_t v = 0; v < observations.views.size(); ++v) {
    const auto& corners = observations.views[v].corners;
    if (corners.empty()) continue;
    const Eigen::Vector3d rvec = start_camera_from_board[v].rvec();
    for (int i = 0; i < 3; ++i) {
      poses[v][i] = rvec(i);
      poses[v][3 + i] = start_camera_from_board[v].translation_mm(i);
    }
    problem.AddParameterBlock(poses[v].data(), kPoseParameterCount);
    ordering->AddElementToGroup(poses[v].data(), 0);  // eliminated first (Schur)
    for (const CornerObservation& c : corners)
      problem.AddResidualBlock(create_reprojection_cost(model, c.pixel_px, c.board_point_mm, aspect_ratio), nullptr,
                               intrinsics.data(), poses[v].data());
    corner_count += static_cast<int>(corners.size());
  }
  ordering->AddElementToGroup(intrinsics.data(), 1);

  const RegularisationWeights w = mrcal_regularisation_weights(model, corner_count, scale);
  std::vector<RegularisationCost::Term> terms;
  for (int j = 0; j < distortion_count; ++j)
    if (!is_held(4 + j)) terms.push_back({4 + j, j >= 5 && j <= 7 ? w.denominator : w.distortion, 0.0});
  if (!options.fix_principal_point) {
    terms.push_back({2, w.centre, (start.width_px() - 1) / 2.0});
    terms.push_back({3, w.centre, (start.height_px() - 1) / 2.0});
  }
  if (scale > 0 && !terms.empty()) problem.AddResidualBlock(new RegularisationCost(intrinsic_count, terms), nullptr, intrinsics.data());

  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_SCHUR;
  solver.linear_solver_ordering = ordering;
  // The rational models' valleys take hundreds of short steps to cross: a
  // start gets up to 5 times the per-solve iterations of fit_intrinsics.
  solver.max_num_iterations = 5 * options.max_iterations;
  solver.function_tolerance = solver.gradient_tolerance = solver.parameter_tolerance = 1e-12;
  solver.num_threads = options.num_threads > 0 ? options.num_threads
                                               : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  solver.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  if (summary.termination_type == ceres::FAILURE)
    throw InputError("", "views", "the regularised pass failed (" + summary.message + ")");
  for (double p : intrinsics)
    if (!std::isfinite(p)) throw InputError("", "views", "the regularised pass diverged (non-finite intrinsics)");
  if (valley) *valley = flattest_direction(problem, intrinsics, poses, observations, held);
  if (aspect_ratio > 0) intrinsics[1] = aspect_ratio * intrinsics[0];
  if (camera_from_board) {
    *camera_from_board = start_camera_from_board;
    for (std::size_t v = 0; v < observations.views.size(); ++v)
      if (!observations.views[v].corners.empty())
        (*camera_from_board)[v] =
            RigidTransform::from_rvec_tvec(Eigen::Vector3d(poses[v][0], poses[v][1], poses[v][2]),
                                           Eigen::Vector3d(poses[v][3], poses[v][4], poses[v][5]));
  }
  return CameraModel(start.width_px(), start.height_px(), intrinsics[0], intrinsics[1], intrinsics[2], intrinsics[3],
                     std::vector<double>(intrinsics.begin() + 4, intrinsics.end()));
}

}  // namespace

CameraModel fit_regularised(const Observations& observations, const IntrinsicFitOptions& options,
                            const CameraModel& start, const std::vector<RigidTransform>& start_camera_from_board,
                            double scale) {
  return solve_from(observations, options, start, start_camera_from_board, scale, nullptr);
}

MultiStartFit fit_intrinsics_multi_start(const Observations& observations, const IntrinsicFitOptions& options,
                                         const MultiStartOptions& multi) {
  const Stopwatch clock;
  if (!(std::isfinite(multi.regularisation_scale) && multi.regularisation_scale >= 0))
    throw InputError("", "regularisation_scale", "must be a finite number >= 0");
  if (multi.perturbed_starts < 0) throw InputError("", "perturbed_starts", "must be 0 or more");

  // The staged fit with the caller's options: the reference, and the result
  // when nothing beats it.
  Stopwatch staged_clock;
  MultiStartFit out(fit_intrinsics(observations, options));
  FitStart staged{"staged", true, "", out.fit.rms_px, staged_clock.seconds(), {}};
  if (!is_rich_lens_model(options.lens_model)) {
    out.starts.push_back(staged);
    out.total_time_s = clock.seconds();
    return out;
  }

  // Every other start is released on the staged fit's inliers, without an
  // outlier loop, so that all costs are sums over the same corners.
  const Observations inliers = inlier_observations(observations, out.fit);
  const auto validity_of = [&](const IntrinsicFit& fit) {
    return check_one_to_one(fit.camera, observed_undistorted_radius(inliers, fit.camera_from_board));
  };
  const auto refused = [&](const LensValidity& v) { return multi.require_one_to_one && !v.one_to_one; };
  staged.validity = validity_of(out.fit);
  out.starts.push_back(staged);
  IntrinsicFitOptions plain = options;
  plain.outlier_k = 0;
  // Without outliers the inliers are all corners and the winning start's fit
  // is the result: it carries the covariance the caller asked for.
  const bool all_inliers = out.fit.outlier_count == 0;
  if (!all_inliers) plain.compute_uncertainty = false;
  std::optional<IntrinsicFit> best_fit;
  // A staged fit that is not one to one is beaten by any start that is.
  double best_rms = refused(staged.validity) ? std::numeric_limits<double>::infinity() : out.fit.rms_px;
  CameraModel best_camera = out.fit.camera;
  std::vector<RigidTransform> best_camera_from_board = out.fit.camera_from_board;

  // A start: its seed (camera and board poses), optionally the regularised
  // pass, then released: the plain least squares with every coefficient free
  // at once from there, and fit_intrinsics from that camera for the fit's
  // figures (starting at an optimum, its staged solve stays there).
  struct Seed {
    CameraModel camera;
    std::vector<RigidTransform> camera_from_board;
  };
  const auto release = [&](const std::string& name, double scale, const std::function<Seed()>& make_seed) {
    Stopwatch start_clock;
    FitStart start{name, false, "", 0, 0, {}};
    try {
      Seed seed = make_seed();
      if (scale > 0) {
        std::vector<RigidTransform> poses;
        seed.camera = solve_from(inliers, plain, seed.camera, seed.camera_from_board, scale, &poses);
        seed.camera_from_board = std::move(poses);
      }
      IntrinsicFitOptions o = plain;
      o.initial_camera = solve_from(inliers, plain, seed.camera, seed.camera_from_board, 0.0, nullptr);
      IntrinsicFit fit = fit_intrinsics(inliers, o);
      if (fit.inlier_count != out.fit.inlier_count) {
        start.failure = "fitted " + std::to_string(fit.inlier_count) + " corners, not the staged fit's " +
                        std::to_string(out.fit.inlier_count);
      } else {
        start.rms_px = fit.rms_px;
        start.validity = validity_of(fit);
        start.ok = !refused(start.validity);
        if (!start.ok) start.failure = "not one to one where the corners are: " + start.validity.why;
        if (start.ok && fit.rms_px < best_rms) {
          best_rms = fit.rms_px;
          best_camera = fit.camera;
          best_camera_from_board = fit.camera_from_board;
          out.winner = static_cast<int>(out.starts.size());
          best_fit = std::move(fit);
        }
      }
    } catch (const InputError& e) {
      start.failure = e.problem();
    }
    start.seconds = start_clock.seconds();
    out.starts.push_back(start);
  };

  IntrinsicFitOptions opencv5 = plain;
  opencv5.lens_model = LensModel::OpenCV5;
  std::optional<IntrinsicFit> opencv5_fit;
  const auto from_opencv5 = [&] {
    if (!opencv5_fit) opencv5_fit = fit_intrinsics(inliers, opencv5);
    return Seed{opencv5_fit->camera, opencv5_fit->camera_from_board};
  };
  release("from opencv5", 0.0, from_opencv5);
  if (multi.regularisation_scale > 0) {
    release("regularised", multi.regularisation_scale, from_opencv5);
    release("regularised from pinhole", multi.regularisation_scale, [&] {
      IntrinsicFitOptions pinhole = plain;
      pinhole.lens_model = LensModel::Pinhole;
      const IntrinsicFit seed = fit_intrinsics(inliers, pinhole);
      return Seed{seed.camera, seed.camera_from_board};
    });
  }
  // Steps along the valley floor from the best minimum so far, of seeded
  // random length and sign: the far minima of the rational models (mrcal's
  // route reaches some with coefficients of 10 to 50) lie along it.
  std::mt19937 rng(multi.perturbation_seed);
  std::uniform_real_distribution<double> exponent(0.0, 1.7);
  for (int i = 0; i < multi.perturbed_starts; ++i) {
    const double step = (i % 2 ? -1.0 : 1.0) * std::pow(10.0, exponent(rng));
    release(fmt_step(step), 0.0, [&] {
      ValleyDirection valley;
      std::vector<RigidTransform> poses;
      const CameraModel at = solve_from(inliers, plain, best_camera, best_camera_from_board, 0.0, &poses, &valley);
      std::array<double, 4 + kMaxDistortionCoefficients> moved = at.intrinsics();
      for (int k = 0; k < static_cast<int>(valley.intrinsics.size()); ++k) moved[k] += step * valley.intrinsics(k);
      Seed seed{CameraModel(at.width_px(), at.height_px(), moved[0], moved[1], moved[2], moved[3],
                            std::vector<double>(moved.begin() + 4, moved.begin() + 4 + at.distortion_count())),
                poses};
      for (std::size_t v = 0; v < poses.size(); ++v)
        seed.camera_from_board[v] = RigidTransform::from_rvec_tvec(poses[v].rvec() + step * valley.poses[v].head<3>(),
                                                                   poses[v].translation_mm + step * valley.poses[v].tail<3>());
      return seed;
    });
  }

  if (out.winner > 0 && all_inliers) {
    out.fit = std::move(*best_fit);
  } else if (out.winner > 0) {
    // The winner with the caller's options on all corners: its outlier loop
    // and covariance. The loop starts from all corners; should it leave the
    // winner's minimum for one no better than the staged fit's, the staged fit stays.
    IntrinsicFitOptions o = options;
    o.initial_camera = best_camera;
    IntrinsicFit final_fit = fit_intrinsics(observations, o);
    const LensValidity final_validity = check_one_to_one(
        final_fit.camera, observed_undistorted_radius(inlier_observations(observations, final_fit), final_fit.camera_from_board));
    if (refused(final_validity)) {
      out.starts[out.winner].failure = "its refit with the outlier loop is not one to one where the corners are: " + final_validity.why;
      out.winner = 0;
    } else if (!refused(staged.validity) && final_fit.inlier_count == out.fit.inlier_count &&
               final_fit.rms_px >= out.fit.rms_px) {
      out.starts[out.winner].failure = "its refit with the outlier loop returned to a minimum no lower than the staged one";
      out.winner = 0;
    } else {
      out.fit = std::move(final_fit);
    }
  }
  out.total_time_s = clock.seconds();
  return out;
}

}  // namespace glasspiv
