#include "render/trace_scene_builder.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "render/mesh_file.h"
#include "render/overlap.h"
#include "util/input_error.h"

namespace glasspiv {

namespace {

TraceMaterial trace_material(const Scene& scene, const std::string& name, const std::string& field) {
  const Material m = scene.material(name, field);
  if (m.kind == MaterialKind::opaque) return TraceMaterial::opaque(m.albedo.value_or(0.0));
  return TraceMaterial::glass(m.refractive_index(scene.wavelength_nm), m.absorption_per_mm.value_or(0.0));
}

Box to_trace_box(const BoxSolid& b) {
  Box box;
  box.centre_mm = b.centre_mm;
  box.world_from_box = b.world_from_box;
  box.half_extent_mm = 0.5 * b.size_mm;
  return box;
}

}  // namespace

TraceScene build_trace_scene(const Scene& scene, TraceSceneBuildInfo* info) {
  if (!scene.sheet) throw std::invalid_argument("build_trace_scene: the scene has no sheet");
  TraceSceneBuildInfo counts;
  TraceScene out;
  out.fluid_index = scene.material(scene.fluid, "fluid").refractive_index(scene.wavelength_nm);

  std::vector<std::string> fields;  // per solid, for errors
  for (const SphereSolid& s : scene.all_spheres()) {
    fields.push_back(s.field);
    out.solids.push_back({Sphere{s.centre_mm, 0.5 * s.diameter_mm}, trace_material(scene, s.material, s.field)});
    ++counts.spheres;
  }
  for (const BoxSolid& b : scene.boxes) {
    fields.push_back(b.field);
    out.solids.push_back({to_trace_box(b), trace_material(scene, b.material, b.field)});
    ++counts.boxes;
  }
  for (const SlabSolid& s : scene.slabs) {
    fields.push_back(s.field);
    out.solids.push_back({to_trace_box(s.to_box()), trace_material(scene, s.material, s.field)});
    ++counts.slabs;
  }
  for (const CylinderSolid& c : scene.cylinders) {
    fields.push_back(c.field);
    Cylinder cyl;
    cyl.axis = c.axis.normalized();
    cyl.centre_mm = c.base_centre_mm + 0.5 * c.length_mm * cyl.axis;
    cyl.radius_mm = c.radius_mm;
    cyl.half_length_mm = 0.5 * c.length_mm;
    out.solids.push_back({cyl, trace_material(scene, c.material, c.field)});
    ++counts.cylinders;
  }
  for (const MeshSolid& m : scene.meshes) {
    fields.push_back(m.field);
    out.solids.push_back({load_scene_mesh(scene, m), trace_material(scene, m.material, m.field)});
    ++counts.meshes;
  }
  for (const RectangleSolid& r : scene.rectangles) {
    TraceMaterial material = TraceMaterial::opaque(1.0);
    if (!r.material.empty()) {
      const Material m = scene.material(r.material, r.field + ".material");
      if (m.kind != MaterialKind::opaque)
        throw InputError(scene.source, r.field + ".material",
                         "a rectangle has no thickness, so it must be opaque (got '" + r.material + "')");
      material = TraceMaterial::opaque(m.albedo.value_or(1.0));
    }
    Rectangle rect;
    rect.centre_mm = r.centre_mm;
    rect.up = r.up.normalized();
    rect.right = rect.up.cross(r.normal.normalized()).normalized();
    rect.up = r.normal.normalized().cross(rect.right);  // exactly orthonormal
    rect.half_width_mm = 0.5 * r.size_mm[0];
    rect.half_height_mm = 0.5 * r.size_mm[1];
    fields.push_back(r.field);
    counts.rectangle_solids.push_back(static_cast<int>(out.solids.size()));
    out.solids.push_back({rect, material});
    ++counts.rectangles;
  }

  std::vector<Shape> shapes;
  shapes.reserve(out.solids.size());
  for (const TraceSolid& solid : out.solids) shapes.push_back(solid.shape);
  if (const auto pair = find_overlap(shapes, kSphereOverlapTolerance_mm))
    throw InputError(scene.source, fields[static_cast<std::size_t>(pair->first)],
                     "overlaps " + fields[static_cast<std::size_t>(pair->second)] +
                         " (solids may touch but not overlap: the tracer follows a ray inside one solid only)");

  const Sheet& sh = *scene.sheet;
  out.sheet.origin_mm = sh.origin_mm;
  out.sheet.s_axis = sh.s_axis;
  out.sheet.t_axis = sh.t_axis;
  out.sheet.extent_s_mm = sh.extent_mm[0];
  out.sheet.extent_t_mm = sh.extent_mm[1];
  if (info) *info = counts;
  return out;
}

std::optional<WorldRay> pixel_world_ray(const CameraModel& model, const RigidTransform& camera_from_world,
                                        const Eigen::Vector2d& pixel) {
  const UnprojectResult u = model.unproject(pixel);
  if (!u.ok()) return std::nullopt;
  WorldRay r;
  const Eigen::Matrix3d world_from_camera = camera_from_world.rotation.transpose();
  r.origin_mm = -(world_from_camera * camera_from_world.translation_mm);
  r.direction = (world_from_camera * u.ray_camera).normalized();
  return r;
}

namespace {

// The camera ray of an unprojected pixel, with its differentials.
std::optional<CameraRay> camera_ray_of(const UnprojectResult& u, const RigidTransform& camera_from_world) {
  if (!u.ok()) return std::nullopt;
  const Eigen::Matrix2d& dpixel_dnormalized = u.dpixel_dnormalized;
  const double det = dpixel_dnormalized.determinant();
  if (!(std::abs(det) > 0) || !std::isfinite(det)) return std::nullopt;  // singular: at a fold
  Eigen::Matrix<double, 3, 2> dray_dpixel = Eigen::Matrix<double, 3, 2>::Zero();
  dray_dpixel.topRows<2>() = dpixel_dnormalized.inverse();
  const Eigen::Matrix3d world_from_camera = camera_from_world.rotation.transpose();
  CameraRay r;
  r.origin_mm = -(world_from_camera * camera_from_world.translation_mm);
  r.direction = world_from_camera * Eigen::Vector3d(u.normalized.x(), u.normalized.y(), 1.0);
  r.ddirection_dpixel = world_from_camera * dray_dpixel;
  return r;
}

}  // namespace

std::optional<CameraRay> pixel_camera_ray(const CameraModel& model, const RigidTransform& camera_from_world,
                                          const Eigen::Vector2d& pixel) {
  return camera_ray_of(model.unproject(pixel), camera_from_world);
}

void pixel_camera_rays(const CameraModel& model, const RigidTransform& camera_from_world,
                       const std::vector<Eigen::Vector2d>& pixels, std::vector<std::optional<CameraRay>>* rays,
                       CameraRayWarmStart* warm) {
  constexpr int kBatch = CameraModel::kUnprojectBatch;
  rays->resize(pixels.size());
  UnprojectResult u[kBatch];
  for (std::size_t first = 0; first < pixels.size(); first += kBatch) {
    const int count = static_cast<int>(std::min<std::size_t>(kBatch, pixels.size() - first));
    // Lane l starts from the previous batch's lane l (none yet: cold).
    model.unproject_batch_near(pixels.data() + first, count, warm->pixels, warm->results, u);
    for (int l = 0; l < count; ++l) {
      (*rays)[first + static_cast<std::size_t>(l)] = camera_ray_of(u[l], camera_from_world);
      warm->pixels[l] = pixels[first + static_cast<std::size_t>(l)];
      warm->results[l] = u[l];
    }
  }
}

std::optional<WorldRay> pixel_world_ray(const Scene& scene, int camera_index, const Eigen::Vector2d& pixel) {
  const SceneCamera& cam = scene.cameras.at(static_cast<std::size_t>(camera_index));
  if (!cam.camera.camera_from_world) throw std::invalid_argument("pixel_world_ray: camera '" + cam.name + "' has no pose");
  return pixel_world_ray(cam.camera.model, *cam.camera.camera_from_world, pixel);
}

}  // namespace glasspiv
