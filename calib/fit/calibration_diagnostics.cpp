#include "calib/fit/calibration_diagnostics.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

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

Eigen::Matrix2d projection_covariance_at(const IntrinsicFit& fit, const Eigen::Vector2d& pixel, double distance_mm) {
  const int m = static_cast<int>(fit.free_intrinsics.size());
  if (fit.intrinsics_covariance.rows() != m || fit.intrinsics_covariance.cols() != m || m == 0)
    throw InputError("", "intrinsics_covariance", "is missing: fit with compute_uncertainty = true");
  const UnprojectResult ray = fit.camera.unproject(pixel);
  if (!ray.ok()) return Eigen::Matrix2d::Constant(kNaN);
  Eigen::Vector2d projected;
  Eigen::MatrixXd jacobian;
  if (!project_with_intrinsics_jacobian(fit.camera.lens_model(), fit.camera.intrinsics().data(), fit.aspect_ratio,
                                        ray.ray_camera * distance_mm, &projected, &jacobian))
    return Eigen::Matrix2d::Constant(kNaN);
  Eigen::MatrixXd j_free(2, m);
  for (int i = 0; i < m; ++i) j_free.col(i) = jacobian.col(fit.free_intrinsics[i]);
  return j_free * fit.intrinsics_covariance * j_free.transpose();
}

double projection_uncertainty_at(const IntrinsicFit& fit, const Eigen::Vector2d& pixel, double distance_mm) {
  return worst_direction(projection_covariance_at(fit, pixel, distance_mm)).norm();
}

GridValues projection_uncertainty(const IntrinsicFit& fit, double distance_mm, double approx_step_px) {
  GridValues out;
  out.grid = PixelGrid::over_image(fit.camera.width_px(), fit.camera.height_px(), approx_step_px);
  out.vector_px.reserve(out.grid.size());
  for (int j = 0; j < out.grid.rows; ++j)
    for (int i = 0; i < out.grid.cols; ++i)
      out.vector_px.push_back(worst_direction(projection_covariance_at(fit, out.grid.pixel(i, j), distance_mm)));
  out.summarize();
  return out;
}

UncertaintyFigures uncertainty_figures(const IntrinsicFit& fit, double distance_mm) {
  const double w = fit.camera.width_px() - 1.0, h = fit.camera.height_px() - 1.0;
  UncertaintyFigures out;
  out.centre_px = projection_uncertainty_at(fit, {w / 2, h / 2}, distance_mm);
  const Eigen::Vector2d corners[4] = {{0, 0}, {w, 0}, {0, h}, {w, h}};
  for (int i = 0; i < 4; ++i) out.corners_px[i] = projection_uncertainty_at(fit, corners[i], distance_mm);
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

CrossValidation cross_validation(const Observations& observations, const IntrinsicFitOptions& options,
                                 double approx_step_px) {
  IntrinsicFitOptions half_options = options;
  half_options.compute_uncertainty = true;
  CrossValidation out{fit_intrinsics(every_other_view(observations, 0), half_options),
                      fit_intrinsics(every_other_view(observations, 1), half_options),
                      {},
                      {},
                      0};
  constexpr double kDistanceMm = 1000;  // any: both models sit at the same place
  out.difference = projection_difference(out.even.camera, out.odd.camera, kDistanceMm, approx_step_px);
  out.expected.grid = out.difference.grid;
  out.expected.vector_px.reserve(out.expected.grid.size());
  for (int j = 0; j < out.expected.grid.rows; ++j)
    for (int i = 0; i < out.expected.grid.cols; ++i) {
      const Eigen::Vector2d pixel = out.expected.grid.pixel(i, j);
      out.expected.vector_px.push_back(worst_direction(projection_covariance_at(out.even, pixel, kDistanceMm) +
                                                       projection_covariance_at(out.odd, pixel, kDistanceMm)));
    }
  out.expected.summarize();
  out.ratio = out.difference.rms_px / out.expected.rms_px;
  return out;
}

}  // namespace glasspiv
