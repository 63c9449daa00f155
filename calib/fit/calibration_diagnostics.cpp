#include "calib/fit/calibration_diagnostics.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

#include <ceres/jet.h>
#include <ceres/rotation.h>

#include "calib/fit/reprojection_cost.h"
#include "calib/lens_maps.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

// The cell (nearest grid sample) of a pixel, or -1 outside the image.
int cell_of(const PixelGrid& grid, const Eigen::Vector2d& pixel) {
  const double fi = std::round(pixel.x() / grid.step_x_px), fj = std::round(pixel.y() / grid.step_y_px);
  if (!(fi >= 0 && fj >= 0 && fi < grid.cols && fj < grid.rows)) return -1;
  return static_cast<int>(fj) * grid.cols + static_cast<int>(fi);
}

// Largest eigenvalue and its eigenvector of a symmetric 2x2 matrix.
Eigen::Vector2d worst_direction(const Eigen::Matrix2d& covariance) {
  if (!covariance.allFinite()) return Eigen::Vector2d::Constant(kNaN);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(covariance);
  return std::sqrt(std::max(0.0, eigen.eigenvalues()(1))) * eigen.eigenvectors().col(1);
}

Observations every_other_view(const Observations& observations, int first) {
  Observations half;
  half.image_width_px = observations.image_width_px;
  half.image_height_px = observations.image_height_px;
  half.target_name = observations.target_name;
  for (std::size_t v = first; v < observations.views.size(); v += 2) half.views.push_back(observations.views[v]);
  return half;
}

}  // namespace

GridValues residual_field(const IntrinsicFit& fit, const Observations& observations, double approx_step_px) {
  GridValues out;
  out.grid = PixelGrid::over_image(fit.camera.width_px(), fit.camera.height_px(), approx_step_px);
  std::vector<Eigen::Vector2d> sum(out.grid.size(), Eigen::Vector2d::Zero());
  std::vector<int> count(out.grid.size(), 0);
  for (const ObservationResidual& r : fit.residuals) {
    if (r.outlier) continue;
    if (r.view < 0 || r.view >= static_cast<int>(observations.views.size()) || r.corner_index < 0 ||
        r.corner_index >= static_cast<int>(observations.views[r.view].corners.size()) ||
        observations.views[r.view].corners[r.corner_index].id != r.corner_id)
      throw InputError("", "observations", "are not the observations this fit was made from");
    const int cell = cell_of(out.grid, observations.views[r.view].corners[r.corner_index].pixel_px);
    if (cell < 0) continue;
    sum[cell] += r.residual_px;
    ++count[cell];
  }
  out.vector_px.resize(out.grid.size());
  for (int i = 0; i < out.grid.size(); ++i)
    out.vector_px[i] = count[i] > 0 ? Eigen::Vector2d(sum[i] / count[i]) : Eigen::Vector2d::Constant(kNaN);
  out.summarize();
  return out;
}

Coverage coverage(const Observations& observations, int width_px, int height_px, double approx_step_px) {
  Coverage out;
  out.grid = PixelGrid::over_image(width_px, height_px, approx_step_px);
  out.count.assign(out.grid.size(), 0);
  for (const ViewObservations& view : observations.views)
    for (const CornerObservation& corner : view.corners) {
      const int cell = cell_of(out.grid, corner.pixel_px);
      if (cell >= 0) ++out.count[cell];
    }
  out.covered_cells = static_cast<int>(std::count_if(out.count.begin(), out.count.end(), [](int n) { return n > 0; }));
  out.covered_fraction = static_cast<double>(out.covered_cells) / out.grid.size();
  return out;
}

std::string uncertainty_method_name(UncertaintyMethod method) {
  return method == UncertaintyMethod::intrinsics_only ? "intrinsics-only" : "board-frames";
}

UncertaintyMethod uncertainty_method_from_name(const std::string& name) {
  if (name == "board-frames") return UncertaintyMethod::board_frames;
  if (name == "intrinsics-only") return UncertaintyMethod::intrinsics_only;
  throw InputError("", "uncertainty", "'" + name + "' is not board-frames or intrinsics-only");
}

const char* to_string(UncertaintyStatus status) {
  switch (status) {
    case UncertaintyStatus::ok:
      return "ok";
    case UncertaintyStatus::no_ray:
      return "the fitted model has no ray through this pixel";
    case UncertaintyStatus::not_projected:
      return "the point cannot be projected (not in front of the camera)";
  }
  return "?";
}

PixelUncertainty pixel_uncertainty(const IntrinsicFit& fit, const Eigen::Vector2d& pixel, double distance_mm,
                                   UncertaintyMethod method) {
  const int m = static_cast<int>(fit.free_intrinsics.size());
  const StateCovariance& state = fit.state_covariance;
  if (method == UncertaintyMethod::intrinsics_only &&
      (fit.intrinsics_covariance.rows() != m || fit.intrinsics_covariance.cols() != m || m == 0))
    throw InputError("", "intrinsics_covariance", "is missing: fit with compute_uncertainty = true");
  if (method == UncertaintyMethod::board_frames && (state.empty() || state.intrinsics.rows() != m || m == 0))
    throw InputError("", "state_covariance", "is missing: fit with compute_uncertainty = true");
  PixelUncertainty out;
  const auto fail = [&](UncertaintyStatus status) {
    out.status = status;
    out.covariance_px2.setConstant(kNaN);
    out.worst_px = kNaN;
    out.worst_direction.setConstant(kNaN);
    return out;
  };
  const UnprojectResult ray = fit.camera.unproject(pixel);
  if (!ray.ok()) return fail(UncertaintyStatus::no_ray);
  const bool at_infinity = std::isinf(distance_mm);
  const Eigen::Vector3d p_camera = at_infinity ? ray.ray_camera : Eigen::Vector3d(ray.ray_camera * distance_mm);
  Eigen::Vector2d projected;
  Eigen::MatrixXd d_pixel_d_intrinsics;
  Eigen::Matrix<double, 2, 3> d_pixel_d_point;
  if (!project_with_intrinsics_jacobian(fit.camera.lens_model(), fit.camera.intrinsics().data(), fit.aspect_ratio,
                                        p_camera, &projected, &d_pixel_d_intrinsics, &d_pixel_d_point))
    return fail(UncertaintyStatus::not_projected);
  Eigen::MatrixXd g_intrinsics(2, m);
  for (int i = 0; i < m; ++i) g_intrinsics.col(i) = d_pixel_d_intrinsics.col(fit.free_intrinsics[i]);

  Eigen::Matrix2d covariance;
  if (method == UncertaintyMethod::intrinsics_only) {
    covariance = g_intrinsics * fit.intrinsics_covariance * g_intrinsics.transpose();
  } else {
    // q = project(mean_v camera_from_board_v(P_v) p_board_v; theta) with the
    // point held fixed in every board frame, p_board_v = board_v_from_camera
    // p_camera at the fitted poses (so the mean is p_camera there). At
    // infinity the poses act by their rotations only. With the joint covariance
    // in its factored form (StateCovariance), for dq = G_theta dtheta + sum_v
    // G_v dP_v:  Var q = u S^+ u^T + sum_v G_v C_v^-1 G_v^T,  u = G_theta - sum_v G_v K_v.
    const int n = static_cast<int>(state.views.size());
    Eigen::MatrixXd u = g_intrinsics;
    Eigen::Matrix2d pose_part = Eigen::Matrix2d::Zero();
    using Jet = ceres::Jet<double, 3>;
    for (int v = 0; v < n; ++v) {
      const std::array<double, 6>& pose = state.camera_from_board[v];
      const RigidTransform camera_from_board =
          RigidTransform::from_rvec_tvec({pose[0], pose[1], pose[2]}, {pose[3], pose[4], pose[5]});
      const Eigen::Vector3d p_board = camera_from_board.rotation.transpose() *
                                      (at_infinity ? p_camera : Eigen::Vector3d(p_camera - camera_from_board.translation_mm));
      // d(R(r) p_board)/dr at the fitted angle-axis r (ceres' rotation, as the fit's functor).
      const Jet r[3] = {Jet(pose[0], 0), Jet(pose[1], 1), Jet(pose[2], 2)};
      const Jet p[3] = {Jet(p_board.x()), Jet(p_board.y()), Jet(p_board.z())};
      Jet rotated[3];
      ceres::AngleAxisRotatePoint(r, p, rotated);
      Eigen::Matrix3d d_point_d_rvec;
      for (int k = 0; k < 3; ++k) d_point_d_rvec.row(k) = rotated[k].v.transpose();
      Eigen::Matrix<double, 2, 6> g;
      g.leftCols<3>() = d_pixel_d_point * d_point_d_rvec / n;
      g.rightCols<3>() = at_infinity ? Eigen::Matrix<double, 2, 3>::Zero() : Eigen::Matrix<double, 2, 3>(d_pixel_d_point / n);
      u -= g * state.pose_from_intrinsics[v];
      pose_part += g * state.pose_alone[v] * g.transpose();
    }
    const double s2 = fit.residual_std_px * fit.residual_std_px;
    covariance = s2 * (u * state.intrinsics * u.transpose() + pose_part);
  }
  covariance = 0.5 * (covariance + covariance.transpose());
  if (!covariance.allFinite()) return fail(UncertaintyStatus::not_projected);
  out.covariance_px2 = covariance;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(covariance);
  out.worst_px = std::sqrt(std::max(0.0, eigen.eigenvalues()(1)));
  out.worst_direction = eigen.eigenvectors().col(1);
  return out;
}

Eigen::Matrix2d projection_covariance_at(const IntrinsicFit& fit, const Eigen::Vector2d& pixel, double distance_mm,
                                         UncertaintyMethod method) {
  return pixel_uncertainty(fit, pixel, distance_mm, method).covariance_px2;
}

double projection_uncertainty_at(const IntrinsicFit& fit, const Eigen::Vector2d& pixel, double distance_mm,
                                 UncertaintyMethod method) {
  return pixel_uncertainty(fit, pixel, distance_mm, method).worst_px;
}

GridValues projection_uncertainty(const IntrinsicFit& fit, double distance_mm, double approx_step_px,
                                  UncertaintyMethod method) {
  GridValues out;
  out.grid = PixelGrid::over_image(fit.camera.width_px(), fit.camera.height_px(), approx_step_px);
  out.vector_px.reserve(out.grid.size());
  for (int j = 0; j < out.grid.rows; ++j)
    for (int i = 0; i < out.grid.cols; ++i) {
      const PixelUncertainty u = pixel_uncertainty(fit, out.grid.pixel(i, j), distance_mm, method);
      out.vector_px.push_back(u.status == UncertaintyStatus::ok ? Eigen::Vector2d(u.worst_px * u.worst_direction)
                                                                : Eigen::Vector2d::Constant(kNaN));
    }
  out.summarize();
  return out;
}

double UncertaintyFigures::worst_corner_px() const {
  double worst = kNaN;
  for (double c : corners_px)
    if (std::isfinite(c) && !(worst >= c)) worst = c;
  return worst;
}

int UncertaintyFigures::undefined_corners() const {
  return static_cast<int>(std::count_if(corner_status.begin(), corner_status.end(),
                                        [](UncertaintyStatus s) { return s != UncertaintyStatus::ok; }));
}

UncertaintyFigures uncertainty_figures(const IntrinsicFit& fit, double distance_mm, UncertaintyMethod method) {
  const double w = fit.camera.width_px() - 1.0, h = fit.camera.height_px() - 1.0;
  UncertaintyFigures out;
  const PixelUncertainty centre = pixel_uncertainty(fit, {w / 2, h / 2}, distance_mm, method);
  out.centre_px = centre.worst_px;
  out.centre_status = centre.status;
  const Eigen::Vector2d corners[4] = {{0, 0}, {w, 0}, {0, h}, {w, h}};
  for (int i = 0; i < 4; ++i) {
    const PixelUncertainty c = pixel_uncertainty(fit, corners[i], distance_mm, method);
    out.corners_px[i] = c.worst_px;
    out.corner_status[i] = c.status;
  }
  return out;
}

RigidTransform implied_rotation(const CameraModel& a, const CameraModel& b, double approx_step_px) {
  const PixelGrid grid = PixelGrid::over_image(a.width_px(), a.height_px(), approx_step_px);
  Eigen::Matrix3d correlation = Eigen::Matrix3d::Zero();
  int samples = 0;
  for (int j = 0; j < grid.rows; ++j)
    for (int i = 0; i < grid.cols; ++i) {
      const UnprojectResult ray_a = a.unproject(grid.pixel(i, j)), ray_b = b.unproject(grid.pixel(i, j));
      if (!ray_a.ok() || !ray_b.ok()) continue;
      correlation += ray_b.ray_camera * ray_a.ray_camera.transpose();
      ++samples;
    }
  RigidTransform out;
  if (samples < 3) return out;
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(correlation, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d sign = Eigen::Matrix3d::Identity();
  sign(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1 : 1;
  out.rotation = svd.matrixU() * sign * svd.matrixV().transpose();
  return out;
}

namespace {

// Per grid sample, the covariance of the difference between two fits of the
// same lens expected from the noise alone, to first order in d = theta_odd -
// theta_even ~ N(0, Sigma_even + Sigma_odd) (intrinsics only: the difference
// of two models compares rays, not boards). Pixel i with unit ray r_i of the
// even model, J_i = dq/dtheta and P_i = dq/dp there:
//   without the rotation: dq_i = J_i d;
//   after it: the odd model's ray moves by U_i d, U_i = -P_i^+ J_i (the ray that
//   keeps the pixel), the implied rotation w minimises sum |U_i d - w x r_i|^2
//   as implied_rotation's Kabsch fit does, w = M d, and
//   dq_i = (J_i + P_i [w]x r_i) d = (J_i - P_i [r_i]x M) d.
std::vector<Eigen::Matrix2d> difference_covariances(const IntrinsicFit& even, const IntrinsicFit& odd,
                                                    const PixelGrid& grid, bool after_rotation) {
  const int m = static_cast<int>(even.free_intrinsics.size());
  if (odd.free_intrinsics != even.free_intrinsics || even.intrinsics_covariance.rows() != m ||
      odd.intrinsics_covariance.rows() != m || m == 0)
    throw InputError("", "intrinsics_covariance", "is missing or differs between the halves");
  const Eigen::MatrixXd sum = even.intrinsics_covariance + odd.intrinsics_covariance;
  std::vector<Eigen::MatrixXd> j(grid.size()), k_u(grid.size());
  std::vector<Eigen::Matrix<double, 2, 3>> p(grid.size());
  std::vector<Eigen::Matrix3d> cross(grid.size());
  std::vector<bool> ok(grid.size(), false);
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::MatrixXd right = Eigen::MatrixXd::Zero(3, m);
  for (int s = 0; s < grid.size(); ++s) {
    const UnprojectResult ray = even.camera.unproject(grid.pixel(s % grid.cols, s / grid.cols));
    if (!ray.ok()) continue;
    Eigen::Vector2d q;
    Eigen::MatrixXd all;
    if (!project_with_intrinsics_jacobian(even.camera.lens_model(), even.camera.intrinsics().data(), even.aspect_ratio,
                                          ray.ray_camera, &q, &all, &p[s]))
      continue;
    j[s].resize(2, m);
    for (int i = 0; i < m; ++i) j[s].col(i) = all.col(even.free_intrinsics[i]);
    const Eigen::Vector3d& r = ray.ray_camera;
    cross[s] << 0, -r.z(), r.y(), r.z(), 0, -r.x(), -r.y(), r.x(), 0;  // [r]x
    const Eigen::Matrix<double, 3, 2> p_pinv = p[s].transpose() * (p[s] * p[s].transpose()).inverse();
    const Eigen::MatrixXd u = -p_pinv * j[s];
    // w x r = -[r]x w: the residual U d + [r]x w, normal equations in w.
    normal += cross[s].transpose() * cross[s];
    right -= cross[s].transpose() * u;
    ok[s] = true;
  }
  const Eigen::MatrixXd rotation_from_d = normal.ldlt().solve(right);  // M
  std::vector<Eigen::Matrix2d> out(grid.size(), Eigen::Matrix2d::Constant(kNaN));
  for (int s = 0; s < grid.size(); ++s) {
    if (!ok[s]) continue;
    const Eigen::MatrixXd a = after_rotation ? Eigen::MatrixXd(j[s] - p[s] * cross[s] * rotation_from_d) : j[s];
    out[s] = a * sum * a.transpose();
  }
  return out;
}

}  // namespace

CrossValidation cross_validation(const Observations& observations, const IntrinsicFitOptions& options,
                                 double approx_step_px, UncertaintyMethod method) {
  IntrinsicFitOptions half_options = options;
  half_options.compute_uncertainty = true;
  CrossValidation out{fit_intrinsics(every_other_view(observations, 0), half_options),
                      fit_intrinsics(every_other_view(observations, 1), half_options),
                      method,
                      {},
                      {},
                      {},
                      0};
  const bool after_rotation = method == UncertaintyMethod::board_frames;
  if (after_rotation) out.odd_from_even = implied_rotation(out.even.camera, out.odd.camera, approx_step_px);
  constexpr double kDistanceMm = 1000;  // any: the models differ by a rotation at most
  out.difference =
      projection_difference(out.even.camera, out.odd.camera, kDistanceMm, approx_step_px, out.odd_from_even);
  out.expected.grid = out.difference.grid;
  for (const Eigen::Matrix2d& c : difference_covariances(out.even, out.odd, out.expected.grid, after_rotation))
    out.expected.vector_px.push_back(worst_direction(c));
  out.expected.summarize();
  out.ratio = out.difference.rms_px / out.expected.rms_px;
  return out;
}

}  // namespace glasspiv
