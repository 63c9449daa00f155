#include "sim/plate_experiment.h"

#include <cmath>

#include <Eigen/Geometry>

#include "render/forward_render.h"
#include "render/material.h"
#include "render/transport_map.h"
#include "sim/random_variates.h"

namespace glasspiv {
namespace {

Eigen::Vector3d random_unit(RandomVariates& rng) {
  Eigen::Vector3d v(rng.normal(), rng.normal(), rng.normal());
  return v.norm() > 0 ? Eigen::Vector3d(v.normalized()) : Eigen::Vector3d::UnitX();
}

}  // namespace

PlateRig ball_layer_rig(int width_px, int height_px) {
  const double f = width_px * 650.0 / 160.0;
  PlateRig rig{{}, CameraModel(width_px, height_px, f, f, 0.5 * (width_px - 1), 0.5 * (height_px - 1), {}), {}};
  const double n_glass = material_from_name("N-BK7").refractive_index(532);
  rig.drawing.fluid_index = standard_air_index(532);
  for (int j = -1; j <= 1; ++j)
    for (int i = -1; i <= 1; ++i)
      rig.drawing.solids.push_back(
          {Sphere{Eigen::Vector3d(40.5 * i, 40.5 * j, 0), 20}, TraceMaterial::glass(n_glass)});
  rig.drawing.sheet.origin_mm = Eigen::Vector3d(0, 0, 50);
  rig.drawing.sheet.s_axis = Eigen::Vector3d::UnitX();
  rig.drawing.sheet.t_axis = -Eigen::Vector3d::UnitY();  // t up: the camera's y runs down
  rig.drawing.sheet.extent_s_mm = rig.drawing.sheet.extent_t_mm = 220;
  rig.camera_from_world.translation_mm = Eigen::Vector3d(0, 0, 600);
  return rig;
}

TargetSpec speckle_spec(double width_mm, double height_mm, double dot_mm, std::uint64_t seed) {
  TargetSpec spec;
  spec.kind = TargetKind::speckle;
  spec.plate_size_mm = Eigen::Vector2d(width_mm, height_mm);
  spec.dot_diameter_mm = dot_mm;
  spec.fill = 0.4;
  spec.seed = seed;
  return spec;
}

AsBuilt as_built(const TraceScene& drawing, const std::vector<RigidTransform>& cameras_from_world,
                 const BuildDeviation& deviation) {
  RandomVariates rng(deviation.seed);
  AsBuilt built;
  built.scene = drawing;
  for (TraceSolid& s : built.scene.solids) {
    if (s.material.kind != TraceMaterial::Kind::glass) continue;
    s.material.refractive_index += deviation.index_offset;
    if (Sphere* sphere = std::get_if<Sphere>(&s.shape))
      for (int a = 0; a < 3; ++a) sphere->centre_mm[a] += deviation.sphere_centre_sigma_mm * rng.normal();
  }
  const double rad = M_PI / 180.0;
  SheetPlane& sheet = built.scene.sheet;
  const Eigen::Matrix3d turn(Eigen::AngleAxisd(deviation.sheet_turn_deg * rad, random_unit(rng)));
  sheet.origin_mm += deviation.sheet_shift_mm * random_unit(rng);
  sheet.s_axis = turn * sheet.s_axis;
  sheet.t_axis = turn * sheet.t_axis;
  for (const RigidTransform& c0 : cameras_from_world) {
    const Eigen::Vector3d centre =
        -c0.rotation.transpose() * c0.translation_mm + deviation.camera_shift_mm * random_unit(rng);
    RigidTransform c;
    c.rotation = Eigen::Matrix3d(Eigen::AngleAxisd(deviation.camera_turn_deg * rad, random_unit(rng))) * c0.rotation;
    c.translation_mm = -c.rotation * centre;
    built.camera_from_world.push_back(c);
  }
  return built;
}

cv::Mat plate_photo(const TraceScene& scene, const CameraModel& camera, const RigidTransform& camera_from_world,
                    const SheetTexture& plate, const PlatePhotoOptions& options) {
  const TransportMap map =
      build_transport_map(scene, camera, camera_from_world, options.trace, options.samples_per_axis, options.threads);
  const std::vector<float> radiance = forward_render_values(map, plate);
  return photo_from_radiance(radiance, map.width, map.height, options.look);
}

}  // namespace glasspiv
