#include "calib/fit/next_view.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <fmt/format.h>

#include <ceres/jet.h>
#include <ceres/rotation.h>

#include "calib/fit/extrinsic_fit.h"
#include "calib/fit/marginal_covariance.h"
#include "calib/fit/reprojection_cost.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {

constexpr double kDegree = M_PI / 180;

// One corner's rows of the Jacobian: d pixel / d free intrinsics (2 x m) and d
// pixel / d pose (2 x 6), as the fit's ReprojectionCost differentiates it.
bool corner_jacobian(const IntrinsicFit& fit, const std::array<double, 6>& pose, const Eigen::Vector3d& board_mm,
                     Eigen::MatrixXd* d_intrinsics, Eigen::Matrix<double, 2, 6>* d_pose) {
  using Jet = ceres::Jet<double, 3>;
  const Jet r[3] = {Jet(pose[0], 0), Jet(pose[1], 1), Jet(pose[2], 2)};
  const Jet p[3] = {Jet(board_mm.x()), Jet(board_mm.y()), Jet(board_mm.z())};
  Jet rotated[3];
  ceres::AngleAxisRotatePoint(r, p, rotated);
  Eigen::Matrix3d d_point_d_rvec;
  Eigen::Vector3d p_camera;
  for (int k = 0; k < 3; ++k) {
    d_point_d_rvec.row(k) = rotated[k].v.transpose();
    p_camera(k) = rotated[k].a + pose[3 + k];
  }
  Eigen::Vector2d pixel;
  Eigen::MatrixXd all;
  Eigen::Matrix<double, 2, 3> d_pixel_d_point;
  if (!project_with_intrinsics_jacobian(fit.camera.lens_model(), fit.camera.intrinsics().data(), fit.aspect_ratio,
                                        p_camera, &pixel, &all, &d_pixel_d_point) ||
      !all.allFinite() || !d_pixel_d_point.allFinite())
    return false;
  const int m = static_cast<int>(fit.free_intrinsics.size());
  d_intrinsics->resize(2, m);
  for (int i = 0; i < m; ++i) d_intrinsics->col(i) = all.col(fit.free_intrinsics[i]);
  d_pose->leftCols<3>() = d_pixel_d_point * d_point_d_rvec;
  d_pose->rightCols<3>() = d_pixel_d_point;
  return true;
}

std::array<double, 6> pose_parameters(const RigidTransform& camera_from_board) {
  const Eigen::Vector3d r = camera_from_board.rvec(), t = camera_from_board.translation_mm;
  return {r.x(), r.y(), r.z(), t.x(), t.y(), t.z()};
}

// The pseudo-inverse of a symmetric positive semi-definite matrix, Jacobi-scaled,
// directions below kMinReciprocalCondition of the largest left out (as
// marginal_covariance computes the fit's).
Eigen::MatrixXd scaled_pseudo_inverse(const Eigen::MatrixXd& s) {
  const Eigen::VectorXd d = s.diagonal().cwiseMax(std::numeric_limits<double>::min()).cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd scaled = d.asDiagonal() * s * d.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(scaled);
  const Eigen::VectorXd lambda = eigen.eigenvalues();
  const int m = static_cast<int>(s.rows());
  if (m == 0 || !(lambda.allFinite() && lambda(m - 1) > 0)) return Eigen::MatrixXd::Constant(m, m, NAN);
  Eigen::VectorXd inverse = lambda.cwiseInverse();
  for (int i = 0; i < m; ++i)
    if (lambda(i) < kMinReciprocalCondition * lambda(m - 1)) inverse(i) = 0;
  return d.asDiagonal() * eigen.eigenvectors() * inverse.asDiagonal() * eigen.eigenvectors().transpose() *
         d.asDiagonal();
}

// A pose block's part of the Schur complement: C^-1 and K = C^-1 B^T.
void eliminate(const Eigen::Matrix<double, 6, 6>& pose, const Eigen::MatrixXd& pose_intrinsics,
               Eigen::Matrix<double, 6, 6>* pose_alone, Eigen::MatrixXd* from_intrinsics) {
  const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt = pose.ldlt();
  *pose_alone = ldlt.solve(Eigen::Matrix<double, 6, 6>::Identity());
  *from_intrinsics = ldlt.solve(pose_intrinsics);
}

std::string region_name(const Eigen::Vector2d& pixel, int width_px, int height_px) {
  const double fx = pixel.x() / std::max(1, width_px - 1), fy = pixel.y() / std::max(1, height_px - 1);
  const char* row = fy < 1.0 / 3 ? "top" : fy > 2.0 / 3 ? "bottom" : "";
  const char* col = fx < 1.0 / 3 ? "left" : fx > 2.0 / 3 ? "right" : "";
  if (*row == '\0' && *col == '\0') return "centre";
  if (*row == '\0') return col;
  if (*col == '\0') return row;
  return std::string(row) + "-" + col;
}

// The image direction (x right, y down) as a word: "right", "top-left", ...
std::string direction_name(const Eigen::Vector2d& direction) {
  const double angle = std::atan2(direction.y(), direction.x()) / kDegree;  // y down: 90 = bottom
  static const char* const kNames[8] = {"right", "bottom-right", "bottom", "bottom-left",
                                        "left",  "top-left",     "top",    "top-right"};
  const int sector = static_cast<int>(std::lround(angle / 45.0) + 8) % 8;
  return kNames[sector];
}

}  // namespace

NormalEquations normal_equations(const IntrinsicFit& fit, const Observations& observations) {
  const StateCovariance& state = fit.state_covariance;
  const int m = static_cast<int>(fit.free_intrinsics.size());
  if (state.empty() || m == 0)
    throw InputError("", "state_covariance", "is missing: fit with compute_uncertainty = true");
  NormalEquations out;
  out.intrinsics = Eigen::MatrixXd::Zero(m, m);
  out.views = state.views;
  out.camera_from_board = state.camera_from_board;
  out.pose.assign(state.views.size(), Eigen::Matrix<double, 6, 6>::Zero());
  out.pose_intrinsics.assign(state.views.size(), Eigen::MatrixXd::Zero(6, m));
  std::vector<int> block_of_view(observations.views.size(), -1);
  for (std::size_t b = 0; b < state.views.size(); ++b) {
    if (state.views[b] < 0 || state.views[b] >= static_cast<int>(observations.views.size()))
      throw InputError("", "observations", "are not the observations this fit was made from");
    block_of_view[state.views[b]] = static_cast<int>(b);
  }
  Eigen::MatrixXd d_intrinsics;
  Eigen::Matrix<double, 2, 6> d_pose;
  for (const ObservationResidual& r : fit.residuals) {
    if (r.outlier) continue;
    if (r.view < 0 || r.view >= static_cast<int>(observations.views.size()) || block_of_view[r.view] < 0 ||
        r.corner_index < 0 || r.corner_index >= static_cast<int>(observations.views[r.view].corners.size()) ||
        observations.views[r.view].corners[r.corner_index].id != r.corner_id)
      throw InputError("", "observations", "are not the observations this fit was made from");
    const int b = block_of_view[r.view];
    if (!corner_jacobian(fit, state.camera_from_board[b], observations.views[r.view].corners[r.corner_index].board_point_mm,
                         &d_intrinsics, &d_pose))
      throw InputError("", "observations", "hold a corner that the fitted camera cannot project");
    out.intrinsics += d_intrinsics.transpose() * d_intrinsics;
    out.pose[b] += d_pose.transpose() * d_pose;
    out.pose_intrinsics[b] += d_pose.transpose() * d_intrinsics;
  }
  return out;
}

bool add_view(const IntrinsicFit& fit, const RigidTransform& camera_from_board,
              const std::vector<Eigen::Vector3d>& corners_mm, NormalEquations* normal) {
  const int m = static_cast<int>(fit.free_intrinsics.size());
  const std::array<double, 6> pose = pose_parameters(camera_from_board);
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(m, m), bt = Eigen::MatrixXd::Zero(6, m), d_intrinsics;
  Eigen::Matrix<double, 6, 6> c = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 2, 6> d_pose;
  int used = 0;
  for (const Eigen::Vector3d& corner : corners_mm) {
    if (!corner_jacobian(fit, pose, corner, &d_intrinsics, &d_pose)) continue;
    a += d_intrinsics.transpose() * d_intrinsics;
    c += d_pose.transpose() * d_pose;
    bt += d_pose.transpose() * d_intrinsics;
    ++used;
  }
  if (used < kMinCornersPerView) return false;
  normal->intrinsics += a;
  normal->views.push_back(-1);
  normal->camera_from_board.push_back(pose);
  normal->pose.push_back(c);
  normal->pose_intrinsics.push_back(bt);
  return true;
}

StateCovariance state_covariance(const NormalEquations& normal) {
  StateCovariance out;
  out.views = normal.views;
  out.camera_from_board = normal.camera_from_board;
  out.pose_alone.resize(normal.pose.size());
  out.pose_from_intrinsics.resize(normal.pose.size());
  Eigen::MatrixXd s = normal.intrinsics;
  for (std::size_t b = 0; b < normal.pose.size(); ++b) {
    eliminate(normal.pose[b], normal.pose_intrinsics[b], &out.pose_alone[b], &out.pose_from_intrinsics[b]);
    s -= normal.pose_intrinsics[b].transpose() * out.pose_from_intrinsics[b];
  }
  out.intrinsics = scaled_pseudo_inverse(0.5 * (s + s.transpose()));
  return out;
}

ViewDistances session_distances(const IntrinsicFit& fit, const Observations& observations) {
  std::vector<double> d;
  for (std::size_t b = 0; b < fit.state_covariance.views.size(); ++b) {
    const int v = fit.state_covariance.views[b];
    if (v < 0 || v >= static_cast<int>(observations.views.size()) || observations.views[v].corners.empty()) continue;
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (const CornerObservation& c : observations.views[v].corners) centroid += c.board_point_mm;
    centroid /= static_cast<double>(observations.views[v].corners.size());
    const std::array<double, 6>& p = fit.state_covariance.camera_from_board[b];
    d.push_back(RigidTransform::from_rvec_tvec({p[0], p[1], p[2]}, {p[3], p[4], p[5]}).apply(centroid).norm());
  }
  if (d.empty()) throw InputError("", "state_covariance", "has no board poses");
  std::sort(d.begin(), d.end());
  return {d.front(), d[d.size() / 2], d.back()};
}

std::optional<CandidateView> candidate_view(const CameraModel& camera, const BoardLayout& board,
                                            const Eigen::Vector2d& centre_px, double distance_mm,
                                            double tilt_axis_deg, double tilt_deg, const NextViewOptions& options) {
  const UnprojectResult ray = camera.unproject(centre_px);
  if (!ray.ok() || board.corners_mm.empty() || !(distance_mm > 0)) return std::nullopt;
  CandidateView out;
  out.centre_px = centre_px;
  out.distance_mm = distance_mm;
  out.tilt_deg = tilt_deg;
  out.tilt_axis_deg = tilt_axis_deg;
  const Eigen::Vector3d axis(std::cos(tilt_axis_deg * kDegree), std::sin(tilt_axis_deg * kDegree), 0);
  // Fronto-parallel: the board's x, y along the image's x, y (its z, away from
  // its printed side, along the optical axis), then tilted.
  out.camera_from_board.rotation = Eigen::AngleAxisd(tilt_deg * kDegree, axis).toRotationMatrix();
  const Eigen::Vector3d centre_board(board.pattern_size_mm.x() / 2, board.pattern_size_mm.y() / 2, 0);
  out.camera_from_board.translation_mm =
      ray.ray_camera.normalized() * distance_mm - out.camera_from_board.rotation * centre_board;
  const Eigen::Vector3d normal = out.camera_from_board.rotation.col(2);
  out.view_angle_deg = std::acos(std::clamp(normal.dot(ray.ray_camera.normalized()), -1.0, 1.0)) / kDegree;
  if (!(out.view_angle_deg <= options.max_view_angle_deg)) return std::nullopt;

  const double w = camera.width_px() - 1.0, h = camera.height_px() - 1.0;
  const auto image_of = [&](const Eigen::Vector3d& board_mm) -> std::optional<Eigen::Vector2d> {
    const Eigen::Vector3d p = out.camera_from_board.apply(board_mm);
    if (!(p.z() > 0) || Eigen::Vector2d(p.x() / p.z(), p.y() / p.z()).norm() >= camera.fold_radius())
      return std::nullopt;
    return camera.project(p);
  };
  for (const Eigen::Vector3d& corner : board.corners_mm) {
    if (!(out.camera_from_board.apply(corner).z() > 0)) return std::nullopt;
    const std::optional<Eigen::Vector2d> pixel = image_of(corner);
    if (!pixel || !(pixel->x() >= 0 && pixel->y() >= 0 && pixel->x() <= w && pixel->y() <= h)) continue;
    out.visible_corners_mm.push_back(corner);
    out.corners_px.push_back(*pixel);
  }
  out.visible_fraction = static_cast<double>(out.corners_px.size()) / board.corners_mm.size();
  if (out.visible_fraction < options.min_visible_fraction ||
      static_cast<int>(out.corners_px.size()) < kMinCornersPerView)
    return std::nullopt;
  const Eigen::Vector2d size = board.pattern_size_mm;
  const Eigen::Vector2d outline[5] = {{0, 0}, {size.x(), 0}, {size.x(), size.y()}, {0, size.y()}, {0, 0}};
  constexpr int kSamplesPerEdge = 16;  // the distortion bends the edges
  for (int e = 0; e < 4; ++e)
    for (int k = 0; k < kSamplesPerEdge; ++k) {
      const Eigen::Vector2d q = outline[e] + (outline[e + 1] - outline[e]) * (static_cast<double>(k) / kSamplesPerEdge);
      if (const std::optional<Eigen::Vector2d> pixel = image_of({q.x(), q.y(), 0})) out.outline_px.push_back(*pixel);
    }
  return out;
}

namespace {

double step_of(const IntrinsicFit& fit, const NextViewOptions& options) {
  return options.approx_step_px > 0 ? options.approx_step_px
                                    : std::max(fit.camera.width_px(), fit.camera.height_px()) / 16.0;
}

// The fit as the uncertainty maps read it (camera, free intrinsics, noise),
// without its residuals: its state covariance is swapped per candidate.
IntrinsicFit scratch_fit(const IntrinsicFit& fit) {
  IntrinsicFit out(fit.camera);
  out.free_intrinsics = fit.free_intrinsics;
  out.aspect_ratio = fit.aspect_ratio;
  out.residual_std_px = fit.residual_std_px;
  out.sigma_px = fit.sigma_px;
  return out;
}

}  // namespace

GridValues predicted_uncertainty(const IntrinsicFit& fit, const NormalEquations& normal, const CandidateView& view,
                                 const NextViewOptions& options) {
  NormalEquations with_view = normal;
  IntrinsicFit scratch = scratch_fit(fit);
  if (add_view(fit, view.camera_from_board, view.visible_corners_mm, &with_view))
    scratch.state_covariance = state_covariance(with_view);
  else
    scratch.state_covariance = state_covariance(normal);
  return projection_uncertainty(scratch, options.distance_mm, step_of(fit, options), UncertaintyMethod::board_frames);
}

NextView propose_next_view(const IntrinsicFit& fit, const Observations& observations, const BoardLayout& board,
                           const NextViewOptions& options, const std::function<void(int done, int total)>& progress) {
  if (static_cast<int>(board.corners_mm.size()) < kMinCornersPerView)
    throw InputError("", "board", fmt::format("has {} corners; a view needs at least {}", board.corners_mm.size(),
                                              kMinCornersPerView));
  NextView out;
  out.distance_mm = options.distance_mm;
  out.noise_sigma_px = fit.residual_std_px;
  const double step = step_of(fit, options);
  out.before = projection_uncertainty(fit, options.distance_mm, step, UncertaintyMethod::board_frames);
  out.worst_before_px = out.before.max_px;
  const NormalEquations normal = normal_equations(fit, observations);
  out.distances = session_distances(fit, observations);

  // The session's Schur complement and pose blocks once; each candidate adds
  // its own term and block.
  const StateCovariance base = state_covariance(normal);
  Eigen::MatrixXd base_schur = normal.intrinsics;
  for (std::size_t b = 0; b < normal.pose.size(); ++b)
    base_schur -= normal.pose_intrinsics[b].transpose() * base.pose_from_intrinsics[b];

  const int w = fit.camera.width_px(), h = fit.camera.height_px();
  std::vector<double> distances;
  for (int k = 0; k < std::max(1, options.distance_steps); ++k)
    distances.push_back(options.distance_steps <= 1 || out.distances.max_mm == out.distances.min_mm
                            ? out.distances.median_mm
                            : out.distances.min_mm +
                                  (out.distances.max_mm - out.distances.min_mm) * k / (options.distance_steps - 1));
  distances.erase(std::unique(distances.begin(), distances.end()), distances.end());
  std::vector<std::pair<double, double>> tilts = {{0, 0}};  // (axis, tilt) deg
  for (int a = 0; a < std::max(1, options.tilt_axes); ++a)
    for (int k = 1; k <= options.tilt_steps; ++k)
      for (int sign : {1, -1})
        tilts.push_back({180.0 * a / std::max(1, options.tilt_axes), sign * options.max_tilt_deg * k / options.tilt_steps});
  const int cols = std::max(1, options.position_cols), rows = std::max(1, options.position_rows);
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < cols; ++i)
      for (double d : distances)
        for (const auto& [axis, tilt] : tilts) {
          ++out.poses_tried;
          const Eigen::Vector2d centre((i + 0.5) / cols * (w - 1), (j + 0.5) / rows * (h - 1));
          if (std::optional<CandidateView> c = candidate_view(fit.camera, board, centre, d, axis, tilt, options))
            out.candidates.push_back(std::move(*c));
        }
  if (out.candidates.empty())
    throw InputError("", "candidates",
                     fmt::format("none of {} board poses keeps {:.0f}% of the board's corners in the image at the "
                                 "session's distances ({:.0f}-{:.0f} mm)",
                                 out.poses_tried, 100 * options.min_visible_fraction, out.distances.min_mm,
                                 out.distances.max_mm));

  IntrinsicFit scratch = scratch_fit(fit);
  scratch.state_covariance = base;
  scratch.state_covariance.views.push_back(-1);
  scratch.state_covariance.camera_from_board.emplace_back();
  scratch.state_covariance.pose_alone.emplace_back();
  scratch.state_covariance.pose_from_intrinsics.emplace_back();
  int best = -1;
  const int total = static_cast<int>(out.candidates.size());
  for (int c = 0; c < total; ++c) {
    CandidateView& candidate = out.candidates[c];
    NormalEquations single;
    single.intrinsics = Eigen::MatrixXd::Zero(normal.intrinsics.rows(), normal.intrinsics.cols());
    candidate.predicted_worst_px = std::numeric_limits<double>::quiet_NaN();
    if (add_view(fit, candidate.camera_from_board, candidate.visible_corners_mm, &single)) {
      StateCovariance& s = scratch.state_covariance;
      eliminate(single.pose[0], single.pose_intrinsics[0], &s.pose_alone.back(), &s.pose_from_intrinsics.back());
      const Eigen::MatrixXd schur =
          base_schur + single.intrinsics - single.pose_intrinsics[0].transpose() * s.pose_from_intrinsics.back();
      s.intrinsics = scaled_pseudo_inverse(0.5 * (schur + schur.transpose()));
      s.camera_from_board.back() = single.camera_from_board[0];
      candidate.predicted_worst_px =
          projection_uncertainty(scratch, options.distance_mm, step, UncertaintyMethod::board_frames).max_px;
      if (std::isfinite(candidate.predicted_worst_px) &&
          (best < 0 || candidate.predicted_worst_px < out.candidates[best].predicted_worst_px))
        best = c;
    }
    if (progress) progress(c + 1, total);
  }
  if (best < 0) throw InputError("", "candidates", "no feasible board pose gives an uncertainty map");
  out.best = out.candidates[best];
  out.after = predicted_uncertainty(fit, normal, out.best, options);
  out.worst_after_px = out.after.max_px;
  return out;
}

std::string describe_view(const CandidateView& view, int width_px, int height_px) {
  // Two significant digits: a distance to hold the board at, not a measurement.
  const double unit = std::pow(10.0, std::floor(std::log10(std::max(view.distance_mm, 1e-9))) - 1);
  const std::string where = fmt::format("with its centre in the {} of the image, at ~{:g} mm",
                                        region_name(view.centre_px, width_px, height_px),
                                        std::round(view.distance_mm / unit) * unit);
  if (std::abs(view.tilt_deg) < 0.5) return "hold the board facing the camera (parallel to the sensor), " + where;
  const double a = std::fmod(view.tilt_axis_deg + 360, 180);
  const std::string axis = std::abs(a) < 1 || std::abs(a - 180) < 1 ? "the horizontal axis"
                           : std::abs(a - 90) < 1                   ? "the vertical axis"
                           : std::abs(a - 45) < 1                   ? "the diagonal axis from top-left to bottom-right"
                           : std::abs(a - 135) < 1                  ? "the diagonal axis from top-right to bottom-left"
                                                   : fmt::format("an axis {:.0f} deg from the horizontal", a);
  // Rotating by +t about the axis u moves the board's side n = z x u away from
  // the camera (z grows by |n| sin t), so the side -sign(t) n comes nearer.
  const Eigen::Vector2d u(std::cos(view.tilt_axis_deg * kDegree), std::sin(view.tilt_axis_deg * kDegree));
  const Eigen::Vector2d n(-u.y(), u.x());
  const Eigen::Vector2d nearer = view.tilt_deg > 0 ? Eigen::Vector2d(-n) : n;
  const std::string side = direction_name(nearer);
  return fmt::format("tilt the board ~{:.0f} deg about {} (its {} {} nearer the camera), {}", std::abs(view.tilt_deg),
                     axis, side, side.find('-') == std::string::npos ? "edge" : "corner", where);
}

IntrinsicFit fit_with_camera_held(const CameraModel& camera, const Observations& observations, double outlier_k) {
  if (camera.width_px() != observations.image_width_px || camera.height_px() != observations.image_height_px)
    throw InputError("", "observations",
                     fmt::format("are of {}x{} px images but the camera's are {}x{} px", observations.image_width_px,
                                 observations.image_height_px, camera.width_px(), camera.height_px()));
  IntrinsicFit out(camera);
  const int m = 4 + camera.distortion_count();
  for (int i = 0; i < m; ++i) out.free_intrinsics.push_back(i);
  out.camera_from_board.assign(observations.views.size(), RigidTransform{});
  out.view_rms_px.assign(observations.views.size(), std::numeric_limits<double>::quiet_NaN());
  ExtrinsicFitOptions pose_options;
  pose_options.outlier_k = outlier_k;
  pose_options.refuse_planar_ambiguity = false;  // a calibration board is large and tilted
  // The joint covariance below judges what the views determine, not each pose alone.
  pose_options.max_position_sigma_mm = 1e9;
  pose_options.max_rotation_sigma_deg = 180;
  double sum_squares = 0;
  std::vector<double> components;
  for (std::size_t v = 0; v < observations.views.size(); ++v) {
    const ViewObservations& view = observations.views[v];
    if (static_cast<int>(view.corners.size()) < kMinCornersPerView) {
      out.skipped_views.push_back({static_cast<int>(v), fmt::format("{} corners (a pose needs {})", view.corners.size(),
                                                                     kMinCornersPerView)});
      continue;
    }
    std::vector<PointObservation> points;
    for (const CornerObservation& c : view.corners) points.push_back({c.board_point_mm, c.pixel_px, 0, ""});
    ExtrinsicFit pose;
    try {
      pose = fit_camera_pose(camera, points, pose_options);
    } catch (const InputError& e) {
      out.skipped_views.push_back({static_cast<int>(v), e.problem()});
      continue;
    }
    out.camera_from_board[v] = pose.camera_from_world;
    out.view_rms_px[v] = pose.rms_px;
    out.state_covariance.views.push_back(static_cast<int>(v));
    out.state_covariance.camera_from_board.push_back(pose_parameters(pose.camera_from_world));
    for (const PointResidual& r : pose.residuals) {
      out.residuals.push_back({static_cast<int>(v), r.point, view.corners[r.point].id, r.residual_px, r.outlier});
      if (r.outlier) {
        ++out.outlier_count;
        continue;
      }
      ++out.inlier_count;
      sum_squares += r.residual_px.squaredNorm();
      components.push_back(r.residual_px.x());
      components.push_back(r.residual_px.y());
    }
  }
  const int poses = static_cast<int>(out.state_covariance.views.size());
  if (poses == 0) throw InputError("", "observations", "no view gives a board pose with this camera");
  out.distinct_views = poses;
  out.rms_px = std::sqrt(sum_squares / std::max(1, out.inlier_count));
  const int dof = 2 * out.inlier_count - m - 6 * poses;
  out.sigma_px = std::sqrt(sum_squares / std::max(1, dof));
  double mean = 0, variance = 0;
  for (double c : components) mean += c / components.size();
  for (double c : components) variance += (c - mean) * (c - mean) / components.size();
  out.residual_std_px = std::sqrt(variance);
  const StateCovariance state = state_covariance(normal_equations(out, observations));
  out.state_covariance = state;
  out.intrinsics_covariance = out.sigma_px * out.sigma_px * state.intrinsics;
  out.fx_sigma_px = std::sqrt(std::max(0.0, out.intrinsics_covariance(0, 0)));
  return out;
}

}  // namespace glasspiv
