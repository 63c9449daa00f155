#include "render/scene.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <set>
#include <unordered_map>
#include <utility>

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

void check_solid_count(const Scene& scene) {
  // total <= kMaxSceneSolids throughout, so nothing below overflows.
  std::uint64_t total = 0;
  auto add = [&](const std::string& field, std::uint64_t n, const char* what) {
    if (n > kMaxSceneSolids - total)
      throw InputError(scene.source, field,
                       fmt::format("{} {}; with the {} solids before it that is more than the {} solids a scene may "
                                   "hold (packings' spheres included)",
                                   what, n, total, kMaxSceneSolids));
    total += n;
  };
  const std::size_t listed = scene.spheres.size() + scene.boxes.size() + scene.slabs.size() + scene.cylinders.size() +
                             scene.rectangles.size();
  add("solids", listed, "lists solids:");
  add("meshes", scene.meshes.size(), "lists meshes:");
  for (const Packing& p : scene.packings)
    add(p.field.empty() ? "packings" : p.field, packing_sphere_count(p), "expands to spheres:");
}

std::vector<SphereSolid> Scene::all_spheres() const {
  check_solid_count(*this);
  std::vector<SphereSolid> all = spheres;
  for (const Packing& packing : packings) {
    std::vector<SphereSolid> expanded = expand_packing(packing);
    all.insert(all.end(), expanded.begin(), expanded.end());
  }
  return all;
}

namespace {

std::string vector_text(const Eigen::Vector3d& v) { return fmt::format("[{}, {}, {}]", v.x(), v.y(), v.z()); }

class Checker {
 public:
  explicit Checker(const Scene& scene) : scene_(scene) {}
  [[noreturn]] void fail(const std::string& field, const std::string& problem) const {
    throw InputError(scene_.source, field, problem);
  }
  // A length in mm: finite, in [kMinSceneSize_mm, kMaxSceneSize_mm].
  void size(double value, const std::string& field) const {
    const std::string range = fmt::format("sizes lie in [{}, {}] mm", kMinSceneSize_mm, kMaxSceneSize_mm);
    if (!std::isfinite(value) || value <= 0) fail(field, fmt::format("must be positive, got {} ({})", value, range));
    if (value < kMinSceneSize_mm)
      fail(field, fmt::format("is {} mm, smaller than the {} mm a scene resolves ({})", value, kMinSceneSize_mm, range));
    if (value > kMaxSceneSize_mm)
      fail(field, fmt::format("is {} mm, larger than the {} mm a scene may span ({}; the unit is mm)", value,
                              kMaxSceneSize_mm, range));
  }
  // A point in mm: finite, every coordinate within +-kMaxSceneCoordinate_mm.
  void coordinate(const Eigen::Vector3d& v, const std::string& field) const {
    finite(v, field);
    if (v.cwiseAbs().maxCoeff() > kMaxSceneCoordinate_mm)
      fail(field, fmt::format("{} mm lies outside the scene's limit: every coordinate within +-{} mm of the origin "
                              "(the unit is mm)",
                              vector_text(v), kMaxSceneCoordinate_mm));
  }
  // A number in [lo, hi], finite.
  void within(double value, double lo, double hi, const std::string& field, const std::string& unit) const {
    if (!std::isfinite(value) || value < lo || value > hi)
      fail(field, fmt::format("must lie in [{}, {}]{}, got {}", lo, hi, unit, value));
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
  Material material(const std::string& name, const std::string& field) const {
    const Material m = scene_.material(name, field);
    if (m.kind != MaterialKind::opaque) {
      double n = 0;
      try {
        n = m.refractive_index(scene_.wavelength_nm);
      } catch (const InputError& e) {
        fail(field, "material '" + name + "' at wavelength_nm: " + e.problem());
      }
      if (!std::isfinite(n) || n < kMinRefractiveIndex || n > kMaxRefractiveIndex)
        fail(field, fmt::format("material '{}' has refractive index {} at {} nm; indices lie in [{}, {}]", name, n,
                                scene_.wavelength_nm, kMinRefractiveIndex, kMaxRefractiveIndex));
      if (m.absorption_per_mm)
        within(*m.absorption_per_mm, 0, kMaxAbsorption_per_mm, field, " per mm (absorption of '" + name + "')");
    } else if (m.albedo) {
      within(*m.albedo, 0, 1, field, " (albedo of '" + name + "')");
    }
    return m;
  }

 private:
  const Scene& scene_;
};

// The first sphere (in index order) that overlaps an earlier one by more than
// kSphereOverlapTolerance_mm, with the earliest sphere it overlaps: (earlier,
// later). Spheres are bucketed by size class (diameters in (2^(L-1), 2^L]) into
// hash grids of cell 2^L, and each sphere is tested against the earlier ones
// near it in every class (or all of a class when that is fewer), so that
// scenes of kMaxSceneSolids spheres validate in well under a second.
std::optional<std::pair<std::size_t, std::size_t>> first_sphere_overlap(const std::vector<SphereSolid>& spheres) {
  using Key = std::array<std::int64_t, 3>;
  struct KeyHash {
    std::size_t operator()(const Key& k) const {
      std::uint64_t h = 1469598103934665603ull;
      for (const std::int64_t v : k) h = (h ^ static_cast<std::uint64_t>(v)) * 1099511628211ull;
      return static_cast<std::size_t>(h ^ (h >> 29));
    }
  };
  struct SizeClass {
    double cell = 0;
    std::unordered_map<Key, std::vector<std::size_t>, KeyHash> grid;
    std::vector<std::size_t> members;
  };
  std::map<int, SizeClass> classes;
  auto key = [](const Eigen::Vector3d& p, double cell) {
    return Key{static_cast<std::int64_t>(std::floor(p.x() / cell)), static_cast<std::int64_t>(std::floor(p.y() / cell)),
               static_cast<std::int64_t>(std::floor(p.z() / cell))};
  };
  for (std::size_t i = 0; i < spheres.size(); ++i) {
    const SphereSolid& a = spheres[i];
    std::optional<std::size_t> earliest;
    auto test = [&](std::size_t j) {
      const SphereSolid& b = spheres[j];
      if ((!earliest || j < *earliest) &&
          (a.centre_mm - b.centre_mm).norm() < (a.diameter_mm + b.diameter_mm) / 2 - kSphereOverlapTolerance_mm)
        earliest = j;
    };
    for (const auto& [level, c] : classes) {
      const double reach = a.diameter_mm / 2 + c.cell / 2;  // no member's radius exceeds cell / 2
      const Key lo = key(a.centre_mm.array() - reach, c.cell), hi = key(a.centre_mm.array() + reach, c.cell);
      double cells = 1;
      for (int k = 0; k < 3; ++k) cells *= double(hi[k] - lo[k] + 1);
      if (cells > double(c.members.size())) {
        for (const std::size_t j : c.members) test(j);
        continue;
      }
      for (std::int64_t x = lo[0]; x <= hi[0]; ++x)
        for (std::int64_t y = lo[1]; y <= hi[1]; ++y)
          for (std::int64_t z = lo[2]; z <= hi[2]; ++z) {
            const auto it = c.grid.find(Key{x, y, z});
            if (it != c.grid.end())
              for (const std::size_t j : it->second) test(j);
          }
    }
    if (earliest) return std::make_pair(*earliest, i);
    const int level = static_cast<int>(std::ceil(std::log2(a.diameter_mm)));
    SizeClass& c = classes[level];
    if (c.members.empty()) c.cell = std::ldexp(1.0, level);
    c.members.push_back(i);
    c.grid[key(a.centre_mm, c.cell)].push_back(i);
  }
  return std::nullopt;
}

}  // namespace

void validate(const Scene& scene) {
  const Checker c(scene);
  c.within(scene.wavelength_nm, kMinWavelength_nm, kMaxWavelength_nm, "wavelength_nm", " nm");
  if (c.material(scene.fluid, "fluid").kind == MaterialKind::opaque)
    c.fail("fluid", "'" + scene.fluid + "' is opaque; the fluid must be transparent");
  for (const auto& [name, m] : scene.materials) c.material(name, "materials." + name);
  check_solid_count(scene);

  for (const SphereSolid& s : scene.spheres) {
    c.coordinate(s.centre_mm, s.field + ".centre_mm");
    c.size(s.diameter_mm, s.field + ".diameter_mm");
    c.material(s.material, s.field + ".material");
  }
  for (const BoxSolid& b : scene.boxes) {
    c.coordinate(b.centre_mm, b.field + ".centre_mm");
    for (int k = 0; k < 3; ++k) c.size(b.size_mm[k], fmt::format("{}.size_mm[{}]", b.field, k));
    const Eigen::Matrix3d rtr = b.world_from_box.transpose() * b.world_from_box;
    if (!b.world_from_box.allFinite() || !rtr.isIdentity(1e-9) || b.world_from_box.determinant() < 0)
      c.fail(b.field + ".rotation", "must be a rotation");
    c.material(b.material, b.field + ".material");
  }
  for (const SlabSolid& s : scene.slabs) {
    c.coordinate(s.point_mm, s.field + ".point_mm");
    c.unit(s.normal, s.field + ".normal");
    c.unit(s.up, s.field + ".up");
    if (s.up.normalized().cross(s.normal.normalized()).norm() < 1e-6)
      c.fail(s.field + ".up", "must not be parallel to the normal");
    c.size(s.thickness_mm, s.field + ".thickness_mm");
    for (int k = 0; k < 2; ++k) c.size(s.extent_mm[k], fmt::format("{}.extent_mm[{}]", s.field, k));
    c.material(s.material, s.field + ".material");
  }
  for (const CylinderSolid& s : scene.cylinders) {
    c.coordinate(s.base_centre_mm, s.field + ".base_centre_mm");
    c.unit(s.axis, s.field + ".axis");
    c.size(s.radius_mm, s.field + ".radius_mm");
    c.size(s.length_mm, s.field + ".length_mm");
    c.material(s.material, s.field + ".material");
  }
  for (const RectangleSolid& r : scene.rectangles) {
    c.coordinate(r.centre_mm, r.field + ".centre_mm");
    c.unit(r.normal, r.field + ".normal");
    c.unit(r.up, r.field + ".up");
    if (r.up.normalized().cross(r.normal.normalized()).norm() < 1e-6)
      c.fail(r.field + ".up", "must not be parallel to the normal");
    for (int k = 0; k < 2; ++k) c.size(r.size_mm[k], fmt::format("{}.size_mm[{}]", r.field, k));
    if (!r.material.empty() && c.material(r.material, r.field + ".material").kind != MaterialKind::opaque)
      c.fail(r.field + ".material", "a rectangle is a thin opaque surface; '" + r.material + "' is not opaque");
  }
  for (const MeshSolid& m : scene.meshes) {
    if (m.file.empty()) c.fail(m.field + ".file", "must name a mesh file");
    if (!std::isfinite(m.placement.scale) || m.placement.scale <= 0)
      c.fail(m.field + ".scale", fmt::format("must be positive, got {}", m.placement.scale));
    c.within(m.placement.scale, kMinMeshScale, kMaxMeshScale, m.field + ".scale", " (file units to mm)");
    c.coordinate(m.placement.position_mm, m.field + ".position_mm");
    const Eigen::Matrix3d& r = m.placement.world_from_mesh;
    if (!r.allFinite() || !(r.transpose() * r).isIdentity(1e-9) || r.determinant() < 0)
      c.fail(m.field + ".rotation_deg", "must be a rotation");
    const double crease = m.options.crease_angle_deg;
    if (!(crease > 0 && crease <= 180))
      c.fail(m.field + ".crease_angle_deg", fmt::format("must lie in (0, 180] degrees, got {}", crease));
    c.material(m.material, m.field + ".material");
  }
  for (const Packing& p : scene.packings) {
    c.size(p.diameter_mm, p.field + ".diameter_mm");
    c.coordinate(p.origin_mm, p.field + ".origin_mm");
    if (p.layers < 1) c.fail(p.field + ".layers", fmt::format("must be 1 or more, got {}", p.layers));
    for (int k = 0; k < 2; ++k)
      if (p.layer_size[k] < 1)
        c.fail(fmt::format("{}.layer_size[{}]", p.field, k), fmt::format("must be 1 or more, got {}", p.layer_size[k]));
    // The far corner of the lattice (its sites only grow from origin_mm along +x, +y, +z).
    const LatticeGeometry g = lattice_geometry(p.lattice, p.diameter_mm);
    const Eigen::Vector3d far = p.origin_mm + Eigen::Vector3d(double(p.layer_size[0] - 1) * g.pitch_mm,
                                                              double(p.layer_size[1] - 1) * g.pitch_mm,
                                                              double(p.layers - 1) * g.layer_spacing_mm);
    if (!far.allFinite() || far.cwiseAbs().maxCoeff() > kMaxSceneCoordinate_mm)
      c.fail(p.field, fmt::format("its last sphere lies at {} mm, outside the scene's limit: every coordinate within "
                                  "+-{} mm of the origin",
                                  vector_text(far), kMaxSceneCoordinate_mm));
    c.material(p.material, p.field + ".material");
    if (p.overrides.size() > kMaxPackingOverrides)
      c.fail(p.field + ".overrides", fmt::format("has {} entries, more than the {} a packing may have",
                                                 p.overrides.size(), kMaxPackingOverrides));
    for (const PackingOverride& o : p.overrides) {
      if (o.sphere.has_value() == o.region_mm.has_value())
        c.fail(o.field, "needs exactly one of 'sphere' and 'region'");
      c.material(o.material, o.field + ".material");
      if (o.sphere) {
        const auto [layer, i, j] = *o.sphere;
        const int shrink = g.odd_layers_shifted && layer % 2 == 1 ? 1 : 0;
        if (layer < 0 || layer >= p.layers || i < 0 || j < 0 || i >= p.layer_size[0] - shrink ||
            j >= p.layer_size[1] - shrink)
          c.fail(o.field + ".sphere", fmt::format("no sphere [{}, {}, {}] in this packing", layer, i, j));
      } else {
        const auto& [lo, hi] = *o.region_mm;
        c.coordinate(lo, o.field + ".region.min_mm");
        c.coordinate(hi, o.field + ".region.max_mm");
        if (!(lo.array() <= hi.array()).all()) c.fail(o.field + ".region", "min_mm must not exceed max_mm");
      }
    }
  }

  // Spheres may touch but not overlap: the first that overlaps an earlier one is named.
  const std::vector<SphereSolid> spheres = scene.all_spheres();
  if (const auto pair = first_sphere_overlap(spheres)) {
    const SphereSolid& a = spheres[pair->first];
    const SphereSolid& b = spheres[pair->second];
    c.fail(b.field, fmt::format("overlaps {}: centres {:.6g} mm apart, radii sum to {:.6g} mm", a.field,
                                (a.centre_mm - b.centre_mm).norm(), (a.diameter_mm + b.diameter_mm) / 2));
  }

  if (scene.sheet) {
    const Sheet& s = *scene.sheet;
    c.coordinate(s.origin_mm, "sheet.origin_mm");
    c.unit(s.s_axis, "sheet.s_axis");
    c.unit(s.t_axis, "sheet.t_axis");
    const double dot = s.s_axis.normalized().dot(s.t_axis.normalized());
    if (std::fabs(dot) > kAxisOrthogonalityTolerance)
      c.fail("sheet.t_axis", fmt::format("must be orthogonal to s_axis (dot product {:.6g})", dot));
    for (int k = 0; k < 2; ++k) c.size(s.extent_mm[k], fmt::format("sheet.extent_mm[{}]", k));
    c.size(s.thickness_mm, "sheet.thickness_mm");
  }
  if (!std::isfinite(scene.background.radiance) || scene.background.radiance < 0)
    c.fail("background.radiance", fmt::format("must be 0 or more, got {}", scene.background.radiance));
  c.within(scene.background.radiance, 0, kMaxBackgroundRadiance, "background.radiance", "");

  std::set<std::string> names;
  for (const SceneCamera& cam : scene.cameras) {
    if (!names.insert(cam.name).second) c.fail(cam.field + ".name", "camera name '" + cam.name + "' appears twice");
    if (!cam.camera.camera_from_world) c.fail(cam.field + ".pose", "missing: the camera has no pose");
    const RigidTransform& pose = *cam.camera.camera_from_world;
    if (!pose.rotation.allFinite() || !pose.translation_mm.allFinite() ||
        !(pose.rotation.transpose() * pose.rotation).isIdentity(1e-9))
      c.fail(cam.field + ".pose", "must be a finite rigid transform");
    const Eigen::Vector3d position = -(pose.rotation.transpose() * pose.translation_mm);
    if (position.cwiseAbs().maxCoeff() > kMaxSceneCoordinate_mm)
      c.fail(cam.field + ".pose",
             fmt::format("puts the camera at {} mm, outside the scene's limit: every coordinate within +-{} mm of the "
                         "origin",
                         vector_text(position), kMaxSceneCoordinate_mm));
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
