#include "render/scene.h"

#include <cmath>
#include <set>

#include <Eigen/Geometry>
#include <fmt/format.h>

#include "render/packing.h"
#include "util/input_error.h"

namespace glasspiv {

const char* lattice_name(Lattice lattice) {
  switch (lattice) {
    case Lattice::sc: return "sc";
    case Lattice::bcc: return "bcc";
    case Lattice::fcc: return "fcc";
  }
  return "?";
}

std::optional<Lattice> lattice_from_name(const std::string& name) {
  if (name == "sc") return Lattice::sc;
  if (name == "bcc") return Lattice::bcc;
  if (name == "fcc") return Lattice::fcc;
  return std::nullopt;
}

double Sheet::fwhm_mm() const { return sigma_mm() * 2 * std::sqrt(2 * std::log(2.0)); }

BoxSolid SlabSolid::to_box() const {
  const Eigen::Vector3d n = normal.normalized();
  const Eigen::Vector3d v = (up - up.dot(n) * n).normalized();
  const Eigen::Vector3d u = v.cross(n);
  BoxSolid box;
  box.centre_mm = point_mm + n * (thickness_mm / 2);
  box.size_mm = Eigen::Vector3d(extent_mm[0], extent_mm[1], thickness_mm);
  box.world_from_box.col(0) = u;
  box.world_from_box.col(1) = v;
  box.world_from_box.col(2) = n;
  box.material = material;
  box.field = field;
  return box;
}

Material Scene::material(const std::string& name, const std::string& field) const {
  const auto it = materials.find(name);
  if (it != materials.end()) return it->second;
  try {
    return material_from_name(name);
  } catch (const InputError& e) {
    std::string own;
    for (const auto& entry : materials) own += (own.empty() ? "" : ", ") + entry.first;
    throw InputError(source, field,
                     e.problem() + (own.empty() ? "" : "; the scene's materials: " + own));
  }
}

std::vector<SphereSolid> Scene::all_spheres() const {
  std::vector<SphereSolid> all = spheres;
  for (const Packing& packing : packings) {
    std::vector<SphereSolid> expanded = expand_packing(packing);
    all.insert(all.end(), expanded.begin(), expanded.end());
  }
  return all;
}

namespace {

class Checker {
 public:
  explicit Checker(const Scene& scene) : scene_(scene) {}
  [[noreturn]] void fail(const std::string& field, const std::string& problem) const {
    throw InputError(scene_.source, field, problem);
  }
  void positive(double value, const std::string& field) const {
    if (!std::isfinite(value) || value <= 0) fail(field, fmt::format("must be positive, got {}", value));
  }
  void finite(const Eigen::Vector3d& v, const std::string& field) const {
    if (!v.allFinite()) fail(field, "must be finite");
  }
  void unit(const Eigen::Vector3d& v, const std::string& field) const {
    finite(v, field);
    if (v.norm() == 0) fail(field, "must not be a zero-length vector");
    if (std::fabs(v.norm() - 1) > kAxisLengthTolerance)
      fail(field, fmt::format("must be a unit vector, has length {}", v.norm()));
  }
  Material material(const std::string& name, const std::string& field, bool solid = true) const {
    const Material m = scene_.material(name, field);
    if (m.kind != MaterialKind::opaque) {
      try {
        (void)m.refractive_index(scene_.wavelength_nm);
      } catch (const InputError& e) {
        fail(field, "material '" + name + "' at wavelength_nm: " + e.problem());
      }
    }
    (void)solid;
    return m;
  }

 private:
  const Scene& scene_;
};

}  // namespace

void validate(const Scene& scene) {
  const Checker c(scene);
  if (!std::isfinite(scene.wavelength_nm) || scene.wavelength_nm <= 0)
    c.fail("wavelength_nm", fmt::format("must be positive, got {}", scene.wavelength_nm));
  if (c.material(scene.fluid, "fluid").kind == MaterialKind::opaque)
    c.fail("fluid", "'" + scene.fluid + "' is opaque; the fluid must be transparent");
  for (const auto& [name, m] : scene.materials) c.material(name, "materials." + name);

  for (const SphereSolid& s : scene.spheres) {
    c.finite(s.centre_mm, s.field + ".centre_mm");
    c.positive(s.diameter_mm, s.field + ".diameter_mm");
    c.material(s.material, s.field + ".material");
  }
  for (const BoxSolid& b : scene.boxes) {
    c.finite(b.centre_mm, b.field + ".centre_mm");
    for (int k = 0; k < 3; ++k) c.positive(b.size_mm[k], fmt::format("{}.size_mm[{}]", b.field, k));
    const Eigen::Matrix3d rtr = b.world_from_box.transpose() * b.world_from_box;
    if (!b.world_from_box.allFinite() || !rtr.isIdentity(1e-9) || b.world_from_box.determinant() < 0)
      c.fail(b.field + ".rotation", "must be a rotation");
    c.material(b.material, b.field + ".material");
  }
  for (const SlabSolid& s : scene.slabs) {
    c.finite(s.point_mm, s.field + ".point_mm");
    c.unit(s.normal, s.field + ".normal");
    c.unit(s.up, s.field + ".up");
    if (s.up.normalized().cross(s.normal.normalized()).norm() < 1e-6)
      c.fail(s.field + ".up", "must not be parallel to the normal");
    c.positive(s.thickness_mm, s.field + ".thickness_mm");
    for (int k = 0; k < 2; ++k) c.positive(s.extent_mm[k], fmt::format("{}.extent_mm[{}]", s.field, k));
    c.material(s.material, s.field + ".material");
  }
  for (const CylinderSolid& s : scene.cylinders) {
    c.finite(s.base_centre_mm, s.field + ".base_centre_mm");
    c.unit(s.axis, s.field + ".axis");
    c.positive(s.radius_mm, s.field + ".radius_mm");
    c.positive(s.length_mm, s.field + ".length_mm");
    c.material(s.material, s.field + ".material");
  }
  for (const RectangleSolid& r : scene.rectangles) {
    c.finite(r.centre_mm, r.field + ".centre_mm");
    c.unit(r.normal, r.field + ".normal");
    c.unit(r.up, r.field + ".up");
    if (r.up.normalized().cross(r.normal.normalized()).norm() < 1e-6)
      c.fail(r.field + ".up", "must not be parallel to the normal");
    for (int k = 0; k < 2; ++k) c.positive(r.size_mm[k], fmt::format("{}.size_mm[{}]", r.field, k));
    if (!r.material.empty() && c.material(r.material, r.field + ".material").kind != MaterialKind::opaque)
      c.fail(r.field + ".material", "a rectangle is a thin opaque surface; '" + r.material + "' is not opaque");
  }
  for (const MeshSolid& m : scene.meshes) {
    if (m.file.empty()) c.fail(m.field + ".file", "must name a mesh file");
    c.positive(m.placement.scale, m.field + ".scale");
    c.finite(m.placement.position_mm, m.field + ".position_mm");
    const Eigen::Matrix3d& r = m.placement.world_from_mesh;
    if (!r.allFinite() || !(r.transpose() * r).isIdentity(1e-9) || r.determinant() < 0)
      c.fail(m.field + ".rotation_deg", "must be a rotation");
    const double crease = m.options.crease_angle_deg;
    if (!(crease > 0 && crease <= 180))
      c.fail(m.field + ".crease_angle_deg", fmt::format("must lie in (0, 180] degrees, got {}", crease));
    c.material(m.material, m.field + ".material");
  }
  for (const Packing& p : scene.packings) {
    c.positive(p.diameter_mm, p.field + ".diameter_mm");
    c.finite(p.origin_mm, p.field + ".origin_mm");
    if (p.layers < 1) c.fail(p.field + ".layers", fmt::format("must be 1 or more, got {}", p.layers));
    for (int k = 0; k < 2; ++k)
      if (p.layer_size[k] < 1)
        c.fail(fmt::format("{}.layer_size[{}]", p.field, k), fmt::format("must be 1 or more, got {}", p.layer_size[k]));
    c.material(p.material, p.field + ".material");
    for (const PackingOverride& o : p.overrides) {
      if (o.sphere.has_value() == o.region_mm.has_value())
        c.fail(o.field, "needs exactly one of 'sphere' and 'region'");
      c.material(o.material, o.field + ".material");
      if (o.sphere) {
        const auto [layer, i, j] = *o.sphere;
        const int shrink = lattice_geometry(p.lattice, p.diameter_mm).odd_layers_shifted && layer % 2 == 1 ? 1 : 0;
        if (layer < 0 || layer >= p.layers || i < 0 || j < 0 || i >= p.layer_size[0] - shrink ||
            j >= p.layer_size[1] - shrink)
          c.fail(o.field + ".sphere", fmt::format("no sphere [{}, {}, {}] in this packing", layer, i, j));
      } else {
        const auto& [lo, hi] = *o.region_mm;
        if (!(lo.array() <= hi.array()).all()) c.fail(o.field + ".region", "min_mm must not exceed max_mm");
      }
    }
  }

  // Spheres may touch but not overlap (O(n^2): packings here hold hundreds of spheres).
  const std::vector<SphereSolid> spheres = scene.all_spheres();
  for (std::size_t a = 0; a < spheres.size(); ++a)
    for (std::size_t b = a + 1; b < spheres.size(); ++b) {
      const double distance = (spheres[a].centre_mm - spheres[b].centre_mm).norm();
      const double touching = (spheres[a].diameter_mm + spheres[b].diameter_mm) / 2;
      if (distance < touching - kSphereOverlapTolerance_mm)
        c.fail(spheres[b].field, fmt::format("overlaps {}: centres {:.6g} mm apart, radii sum to {:.6g} mm",
                                             spheres[a].field, distance, touching));
    }

  if (scene.sheet) {
    const Sheet& s = *scene.sheet;
    c.finite(s.origin_mm, "sheet.origin_mm");
    c.unit(s.s_axis, "sheet.s_axis");
    c.unit(s.t_axis, "sheet.t_axis");
    const double dot = s.s_axis.normalized().dot(s.t_axis.normalized());
    if (std::fabs(dot) > kAxisOrthogonalityTolerance)
      c.fail("sheet.t_axis", fmt::format("must be orthogonal to s_axis (dot product {:.6g})", dot));
    for (int k = 0; k < 2; ++k) c.positive(s.extent_mm[k], fmt::format("sheet.extent_mm[{}]", k));
    c.positive(s.thickness_mm, "sheet.thickness_mm");
  }
  if (!std::isfinite(scene.background.radiance) || scene.background.radiance < 0)
    c.fail("background.radiance", fmt::format("must be 0 or more, got {}", scene.background.radiance));

  std::set<std::string> names;
  for (const SceneCamera& cam : scene.cameras) {
    if (!names.insert(cam.name).second) c.fail(cam.field + ".name", "camera name '" + cam.name + "' appears twice");
    if (!cam.camera.camera_from_world) c.fail(cam.field + ".pose", "missing: the camera has no pose");
    const RigidTransform& pose = *cam.camera.camera_from_world;
    if (!pose.rotation.allFinite() || !pose.translation_mm.allFinite() ||
        !(pose.rotation.transpose() * pose.rotation).isIdentity(1e-9))
      c.fail(cam.field + ".pose", "must be a finite rigid transform");
  }
}

RigidTransform camera_from_world_look_at(const Eigen::Vector3d& position_mm, const Eigen::Vector3d& look_at_mm,
                                         const Eigen::Vector3d& up) {
  const Eigen::Vector3d forward = look_at_mm - position_mm;
  if (!forward.allFinite() || forward.norm() == 0)
    throw InputError("", "pose.look_at_mm", "must differ from position_mm");
  const Eigen::Vector3d z = forward.normalized();
  const Eigen::Vector3d up_perp = up - up.dot(z) * z;
  if (!up.allFinite() || up.norm() == 0 || up_perp.norm() < 1e-9 * up.norm())
    throw InputError("", "pose.up", "must be non-zero and not parallel to the view direction");
  const Eigen::Vector3d y = -up_perp.normalized();  // image y points down
  const Eigen::Vector3d x = y.cross(z);
  RigidTransform t;
  t.rotation.row(0) = x;
  t.rotation.row(1) = y;
  t.rotation.row(2) = z;
  t.translation_mm = -t.rotation * position_mm;
  return t;
}

Eigen::Matrix3d rotation_from_rvec_deg(const Eigen::Vector3d& rvec_deg) {
  const double angle = rvec_deg.norm() * M_PI / 180;
  if (angle == 0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, rvec_deg.normalized()).toRotationMatrix();
}

Eigen::Matrix3d rotation_from_euler_deg(const Eigen::Vector3d& euler_deg) {
  const Eigen::Vector3d r = euler_deg * (M_PI / 180);
  return rotation_from_euler_zyx(r[0], r[1], r[2]);
}

}  // namespace glasspiv
