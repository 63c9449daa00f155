#include "align/fitted_scene.h"

#include <map>
#include <stdexcept>

#include "align/model_adjustment.h"
#include "render/material.h"

namespace glasspiv {

Scene fitted_scene(const Scene& drawing, const TraceScene& fitted, const std::vector<FittedCamera>& cameras) {
  Scene out = drawing;
  std::vector<SphereSolid> spheres = drawing.all_spheres();
  if (spheres.size() > fitted.solids.size())
    throw std::invalid_argument("fitted_scene: the fitted model has fewer solids than the drawing");
  // Each glass material's fitted absolute index, from the first solid that uses it.
  std::map<std::string, double> index_of;
  auto note = [&](const std::string& material, std::size_t solid) {
    const TraceSolid& s = fitted.solids[solid];
    if (s.material.kind == TraceMaterial::Kind::glass && !index_of.count(material))
      index_of[material] = s.material.refractive_index;
  };
  for (std::size_t i = 0; i < spheres.size(); ++i) {
    note(spheres[i].material, i);
    if (const Sphere* s = std::get_if<Sphere>(&fitted.solids[i].shape)) {
      spheres[i].centre_mm = s->centre_mm;
      spheres[i].diameter_mm = 2 * s->radius_mm;
    }
  }
  std::size_t k = spheres.size();
  for (const BoxSolid& b : drawing.boxes) note(b.material, k++);
  for (const SlabSolid& b : drawing.slabs) note(b.material, k++);
  for (const CylinderSolid& b : drawing.cylinders) note(b.material, k++);
  for (const MeshSolid& b : drawing.meshes) note(b.material, k++);
  out.spheres = spheres;
  out.packings.clear();
  const double air = standard_air_index(drawing.wavelength_nm);
  std::map<std::string, std::string> renamed;
  for (const auto& [name, n_abs] : index_of) {
    const std::string fitted_name = name + "_fitted";
    out.materials[fitted_name] = material_with_index(fitted_name, n_abs / air);
    renamed[name] = fitted_name;
  }
  auto rename = [&](std::string& m) {
    const auto it = renamed.find(m);
    if (it != renamed.end()) m = it->second;
  };
  for (SphereSolid& s : out.spheres) rename(s.material);
  for (BoxSolid& s : out.boxes) rename(s.material);
  for (SlabSolid& s : out.slabs) rename(s.material);
  for (CylinderSolid& s : out.cylinders) rename(s.material);
  for (MeshSolid& s : out.meshes) rename(s.material);
  if (out.sheet) {
    out.sheet->origin_mm = fitted.sheet.origin_mm;
    out.sheet->s_axis = fitted.sheet.s_axis;
    out.sheet->t_axis = fitted.sheet.t_axis;
  }
  for (const FittedCamera& c : cameras) {
    SceneCamera& sc = out.cameras.at(static_cast<std::size_t>(c.scene_camera));
    sc.camera.camera_from_world = c.camera_from_world;
    if (c.focal_scale != 1) {
      sc.camera.model = scaled_focal(sc.camera.model, c.focal_scale);
      sc.file.clear();  // written inline: the camera file holds the drawing's focal length
    }
  }
  return out;
}

}  // namespace glasspiv
