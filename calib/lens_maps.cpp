#include "calib/lens_maps.h"

#include <limits>

namespace glasspiv {
namespace {
const Eigen::Vector2d kInvalid = Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
}

GridValues distortion_field(const CameraModel& model, double approx_step_px) {
  GridValues out;
  out.grid = PixelGrid::over_image(model.width_px(), model.height_px(), approx_step_px);
  out.vector_px.reserve(out.grid.size());
  for (int j = 0; j < out.grid.rows; ++j)
    for (int i = 0; i < out.grid.cols; ++i) {
      const Eigen::Vector2d pixel = out.grid.pixel(i, j);
      const UnprojectResult ray = model.unproject(pixel);
      if (!ray.ok()) {
        out.vector_px.push_back(kInvalid);
        continue;
      }
      const Eigen::Vector2d pinhole(model.fx_px() * ray.normalized.x() + model.cx_px(),
                                    model.fy_px() * ray.normalized.y() + model.cy_px());
      out.vector_px.push_back(pixel - pinhole);
    }
  out.summarize();
  return out;
}

GridValues projection_difference(const CameraModel& a, const CameraModel& b, double distance_mm,
                                 double approx_step_px, const RigidTransform& b_from_a) {
  GridValues out;
  out.grid = PixelGrid::over_image(a.width_px(), a.height_px(), approx_step_px);
  out.vector_px.reserve(out.grid.size());
  for (int j = 0; j < out.grid.rows; ++j)
    for (int i = 0; i < out.grid.cols; ++i) {
      const Eigen::Vector2d pixel_a = out.grid.pixel(i, j);
      const UnprojectResult ray = a.unproject(pixel_a);
      if (!ray.ok()) {
        out.vector_px.push_back(kInvalid);
        continue;
      }
      // Both models project the same point, so the unprojection's own tolerance
      // does not enter the difference (identical models give exactly zero).
      const Eigen::Vector3d point_a = ray.ray_camera * distance_mm;
      const std::optional<Eigen::Vector2d> reprojected_a = a.project(point_a);
      const std::optional<Eigen::Vector2d> pixel_b = b.project(b_from_a.apply(point_a));
      out.vector_px.push_back(reprojected_a && pixel_b ? Eigen::Vector2d(*pixel_b - *reprojected_a) : kInvalid);
    }
  out.summarize();
  return out;
}

}  // namespace glasspiv
