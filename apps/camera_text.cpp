#include "apps/camera_text.h"

#include <cmath>

#include <fmt/format.h>

namespace glasspiv {

std::string describe_camera(const Camera& camera) {
  const CameraModel& m = camera.model;
  std::string s;
  s += fmt::format("camera '{}'  {}x{} px  lens model {}\n", camera.name, m.width_px(), m.height_px(),
                   lens_model_name(m.lens_model()));
  s += fmt::format("  OpenCV:  fx {:.10g}  fy {:.10g}  cx {:.10g}  cy {:.10g} px\n", m.fx_px(), m.fy_px(), m.cx_px(),
                   m.cy_px());
  if (m.distortion_count() > 0) s += fmt::format("           distortion [{:.8g}]\n", fmt::join(m.distortion(), ", "));
  if (camera.pixel_pitch_um) {
    const DavisStyleIntrinsics d = to_davis_style(m, *camera.pixel_pitch_um);
    s += fmt::format("  DaVis:   focal length {:.8g} mm", d.focal_length_x_mm);
    if (d.focal_length_y_mm != d.focal_length_x_mm) s += fmt::format(" (y {:.8g} mm)", d.focal_length_y_mm);
    s += fmt::format("  pixel pitch {:.6g} um  principal point ({:.6g}, {:.6g}) px\n", d.pixel_pitch_um,
                     d.principal_point_x_px, d.principal_point_y_px);
    s += fmt::format("           sensor {:.4g} x {:.4g} mm\n", m.width_px() * d.pixel_pitch_um * 1e-3,
                     m.height_px() * d.pixel_pitch_um * 1e-3);
  } else {
    s += "  DaVis:   pixel pitch unknown (give --pixel-pitch-um for focal length in mm)\n";
  }
  const double centre_offset_x = m.cx_px() - (m.width_px() - 1) / 2.0;
  const double centre_offset_y = m.cy_px() - (m.height_px() - 1) / 2.0;
  s += fmt::format("  principal point is ({:+.3f}, {:+.3f}) px from the image centre\n", centre_offset_x,
                   centre_offset_y);
  if (const auto fov = m.field_of_view())
    s += fmt::format("  field of view: {:.3f} x {:.3f} deg (diagonal {:.3f} deg)\n", fov->horizontal_deg,
                     fov->vertical_deg, fov->diagonal_deg);
  else
    s += "  field of view: undefined, part of the image edge has no ray (distortion folds back)\n";
  if (m.fold_radius() < CameraModel::kFoldSearchRadius)
    s += fmt::format("  distortion folds back at normalised radius {:.4g} (about {:.1f} deg off axis)\n",
                     m.fold_radius(), std::atan(m.fold_radius()) * 180.0 / M_PI);
  if (camera.camera_from_world) {
    const RigidTransform world_from_camera = camera.camera_from_world->inverse();
    const Eigen::Vector3d rvec = camera.camera_from_world->rvec();
    const Eigen::Vector3d centre = world_from_camera.translation_mm;
    const Eigen::Vector3d axis = world_from_camera.rotation.col(2);
    s += fmt::format("  pose:    camera_from_world rvec [{:.8g}, {:.8g}, {:.8g}] rad  tvec [{:.8g}, {:.8g}, {:.8g}] mm\n",
                     rvec.x(), rvec.y(), rvec.z(), camera.camera_from_world->translation_mm.x(),
                     camera.camera_from_world->translation_mm.y(), camera.camera_from_world->translation_mm.z());
    s += fmt::format("           centre ({:.6g}, {:.6g}, {:.6g}) mm, looking along ({:.4f}, {:.4f}, {:.4f})\n",
                     centre.x(), centre.y(), centre.z(), axis.x(), axis.y(), axis.z());
  } else {
    s += "  pose:    none (intrinsics only)\n";
  }
  return s;
}

}  // namespace glasspiv
