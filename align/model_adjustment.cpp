#include "align/model_adjustment.h"

#include <type_traits>
#include <variant>

namespace glasspiv {

TraceScene adjusted_glass(const TraceScene& scene, double refractive_index_offset, const Eigen::Vector3d& offset_mm) {
  TraceScene out = scene;
  for (TraceSolid& solid : out.solids) {
    if (solid.material.kind != TraceMaterial::Kind::glass) continue;
    solid.material.refractive_index += refractive_index_offset;
    std::visit(
        [&](auto& shape) {
          using T = std::decay_t<decltype(shape)>;
          if constexpr (!std::is_same_v<T, TriangleMesh>) shape.centre_mm += offset_mm;
        },
        solid.shape);
  }
  return out;
}

bool has_fixed_glass(const TraceScene& scene) {
  for (const TraceSolid& solid : scene.solids)
    if (solid.material.kind == TraceMaterial::Kind::glass && std::holds_alternative<TriangleMesh>(solid.shape))
      return true;
  return false;
}

CameraModel scaled_focal(const CameraModel& camera, double focal_scale) {
  return CameraModel(camera.width_px(), camera.height_px(), camera.fx_px() * focal_scale,
                     camera.fy_px() * focal_scale, camera.cx_px(), camera.cy_px(), camera.distortion());
}

}  // namespace glasspiv
