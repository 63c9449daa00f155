#pragma once
// Scene (the file-level description, render/scene.h) -> TraceScene (what
// trace_ray consumes, render/path_tracer.h), and the world ray of a camera
// pixel. No I/O.
//
// - Spheres (explicit and every packing's, via Scene::all_spheres), boxes, slabs
//   (as boxes), cylinders, meshes and rectangles become TraceSolids in that order; glass takes the
//   material's absolute refractive index at scene.wavelength_nm and its
//   absorption (0 when not modelled); opaque materials become opaque solids.
// - Meshes are loaded from their files (render/mesh_file.h; InputError naming
//   the scene and the mesh's field for a missing or bad file).
// - Rectangles (targets, markers, backdrops) become opaque Rectangle solids
//   with their material's albedo (white, albedo 1, without one); glass
//   rectangles are refused (a zero-thickness surface has no inside).
//   TraceSceneBuildInfo::rectangle_solids lists their solid indices, in the
//   scene's order, so a renderer can find each one's texture.
// - The fluid index is the fluid material's absolute index at the wavelength.
// - The sheet becomes the SheetPlane (origin, axes, extent). A scene without a
//   sheet throws std::invalid_argument (nothing to map onto).
#include <Eigen/Core>
#include <optional>
#include <vector>

#include "calib/camera_model.h"
#include "calib/rigid_transform.h"
#include "render/path_tracer.h"
#include "render/scene.h"

namespace glasspiv {

struct TraceSceneBuildInfo {
  int spheres = 0, boxes = 0, slabs = 0, cylinders = 0, meshes = 0, rectangles = 0;
  std::vector<int> rectangle_solids;  // solid index of scene.rectangles[i]
};

// Throws InputError (via Scene::material / Material::refractive_index) for an
// unknown material or a wavelength outside a formula's range, InputError naming
// both fields for two solids that overlap (render/overlap.h), and
// std::invalid_argument when the scene has no sheet.
TraceScene build_trace_scene(const Scene& scene, TraceSceneBuildInfo* info = nullptr);

// A camera ray in world coordinates: origin = the camera centre, direction unit.
struct WorldRay {
  Eigen::Vector3d origin_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
};

// The world ray through `pixel` (pixel (0, 0) is the centre of the top-left
// pixel) of a camera with pose camera_from_world (p_cam = R p_world + t).
// std::nullopt when the model cannot unproject the pixel (past a fold).
std::optional<WorldRay> pixel_world_ray(const CameraModel& model, const RigidTransform& camera_from_world,
                                        const Eigen::Vector2d& pixel);

// The camera ray through `pixel` with its ray differentials d(direction)/d(pixel),
// from the lens model's analytic Jacobian (the direction is left unnormalised:
// (x, y, 1) in the camera frame, rotated to the world). std::nullopt as above.
std::optional<CameraRay> pixel_camera_ray(const CameraModel& model, const RigidTransform& camera_from_world,
                                          const Eigen::Vector2d& pixel);
// What pixel_camera_rays carries along a row from one batch of pixels to the
// next (and from call to call): the last batch's pixels and unprojections,
// lane by lane. A fresh one holds no solution (not ok): its first batch
// starts cold.
struct CameraRayWarmStart {
  CameraRayWarmStart() {
    for (Eigen::Vector2d& p : pixels) p.setZero();
  }
  Eigen::Vector2d pixels[CameraModel::kUnprojectBatch];
  UnprojectResult results[CameraModel::kUnprojectBatch];
};
// pixel_camera_ray for each of `pixels`, the unprojections interleaved and
// each batch's started from the previous batch's, lane by lane
// (CameraModel::unproject_batch_near; *warm carries them on): for pixels
// listed along a row, about a Newton step fewer each. The rays agree with
// pixel_camera_ray's to the unprojection's tolerance (1e-10 px), not to the
// bit.
void pixel_camera_rays(const CameraModel& model, const RigidTransform& camera_from_world,
                       const std::vector<Eigen::Vector2d>& pixels, std::vector<std::optional<CameraRay>>* rays,
                       CameraRayWarmStart* warm);

// The same for a scene camera (index into scene.cameras; throws
// std::out_of_range for a bad index).
std::optional<WorldRay> pixel_world_ray(const Scene& scene, int camera_index, const Eigen::Vector2d& pixel);

}  // namespace glasspiv
