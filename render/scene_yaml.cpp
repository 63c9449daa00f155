#include "render/scene_yaml.h"

#include <cmath>
#include <filesystem>
#include <map>
#include <optional>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "calib/io/camera_file.h"
#include "util/atomic_file.h"
#include "util/input_error.h"
#include "util/yaml_fields.h"

namespace glasspiv {
namespace {

namespace fs = std::filesystem;

const std::vector<std::string> kTopLevel = {"glasspiv_scene", "wavelength_nm", "fluid",      "materials",
                                            "solids",         "meshes",        "packings",   "sheet",
                                            "background",     "cameras"};
const std::vector<std::string> kMeshKeys = {"file",         "material", "scale", "position_mm", "rotation_deg",
                                            "normals",      "crease_angle_deg"};

std::string join(const std::vector<std::string>& keys) {
  std::string out;
  for (const std::string& k : keys) out += (out.empty() ? "" : ", ") + k;
  return out;
}

class Reader : public YamlFields {
 public:
  explicit Reader(const std::string& path) : YamlFields(path) {}

  // Records where a field path lives, so validation errors can quote its line.
  void note(const std::string& field, const YAML::Node& node) {
    if (node.IsDefined() && node.Mark().line >= 0) lines_[field] = node.Mark().line + 1;
  }
  // The line of `field` or of its nearest recorded parent, 0 if none.
  int line_of(std::string field) const {
    while (!field.empty()) {
      const auto it = lines_.find(field);
      if (it != lines_.end()) return it->second;
      const std::size_t cut = field.find_last_of(".[");
      if (cut == std::string::npos) break;
      field = field.substr(0, cut);
    }
    return 0;
  }

 private:
  std::map<std::string, int> lines_;
};

std::string child(const std::string& parent, const std::string& key) {
  return parent.empty() ? key : parent + "." + key;
}

// A mapping whose keys are checked against the allowed ones.
class Map {
 public:
  Map(Reader& r, const YAML::Node& node, std::string field, const std::vector<std::string>& allowed)
      : r_(r), node_(node), field_(std::move(field)) {
    if (!node.IsMap()) r.fail(field_.empty() ? "" : field_, node, "must be a mapping of fields");
    r.note(field_, node);
    for (auto it = node.begin(); it != node.end(); ++it) {
      const std::string key = it->first.IsScalar() ? it->first.Scalar() : std::string("?");
      const std::string path = child(field_, key);
      bool known = false;
      for (const std::string& a : allowed) known = known || a == key;
      if (!known) r.fail(path, it->first, "unknown key '" + key + "' (expected one of: " + join(allowed) + ")");
      if (fields_.count(key)) r.fail(path, it->first, "appears twice");
      fields_[key] = it->second;
      r.note(path, it->second);
    }
  }
  bool has(const std::string& key) const { return fields_.count(key) > 0; }
  std::optional<YAML::Node> optional(const std::string& key) const {
    const auto it = fields_.find(key);
    if (it == fields_.end()) return std::nullopt;
    return it->second;
  }
  YAML::Node required(const std::string& key) const {
    const auto it = fields_.find(key);
    if (it == fields_.end()) r_.fail(child(field_, key), node_, "missing (required)");
    return it->second;
  }
  std::string path(const std::string& key) const { return child(field_, key); }
  const std::string& field() const { return field_; }

  double real(const std::string& key) const { return r_.real(required(key), path(key)); }
  double real_or(const std::string& key, double fallback) const {
    const auto n = optional(key);
    return n ? r_.real(*n, path(key)) : fallback;
  }
  std::string text(const std::string& key) const { return r_.text(required(key), path(key)); }
  Eigen::Vector3d vec3(const std::string& key) const { return vec3_of(required(key), path(key)); }
  Eigen::Vector3d vec3_of(const YAML::Node& n, const std::string& field) const {
    const std::vector<double> v = r_.reals(n, field, 3);
    return Eigen::Vector3d(v[0], v[1], v[2]);
  }
  // A direction: lengths within kAxisLengthTolerance of 1 are normalised; the rest
  // is left for validate() to reject (zero, far from unit).
  Eigen::Vector3d axis(const std::string& key) const { return normalise(vec3(key)); }
  static Eigen::Vector3d normalise(const Eigen::Vector3d& v) {
    const double norm = v.norm();
    return norm > 0 && std::fabs(norm - 1) <= kAxisLengthTolerance ? Eigen::Vector3d(v / norm) : v;
  }
  std::array<double, 2> pair(const std::string& key) const {
    const std::vector<double> v = r_.reals(required(key), path(key), 2);
    return {v[0], v[1]};
  }

 private:
  Reader& r_;
  YAML::Node node_;
  std::string field_;
  std::map<std::string, YAML::Node> fields_;
};

std::string resolve(const std::string& scene_path, const std::string& name) {
  const fs::path p(name);
  if (p.is_absolute()) return name;
  return (fs::path(scene_path).parent_path() / p).lexically_normal().string();
}

// A name for a message: control characters as '?', long names shortened, so
// that the message stays one readable line.
std::string shown(const std::string& name) {
  std::string out;
  for (const char ch : name) out += static_cast<unsigned char>(ch) < 0x20 || ch == 0x7f ? '?' : ch;
  if (out.size() > 120) out = out.substr(0, 60) + "..." + out.substr(out.size() - 40);
  return "'" + out + "'" + (name.size() > 120 ? fmt::format(" ({} characters)", name.size()) : "");
}

// The file a scene names at `key` (camera, mesh, texture), resolved against
// the scene file's folder. InputError naming the scene file and the field
// unless it names an existing regular file: empty, too long or otherwise
// refused by the system, missing, a folder.
std::string existing_file(Reader& r, const Map& m, const std::string& key, const std::string& what) {
  const YAML::Node node = m.required(key);
  const std::string field = m.path(key);
  const std::string name = r.text(node, field);
  if (name.empty()) r.fail(field, node, "must name a " + what);
  const std::string file = resolve(r.path(), name);
  const std::string where = file == name ? "" : " (resolved to " + shown(file) + ")";
  std::error_code ec;
  const fs::file_status status = fs::status(file, ec);
  if (status.type() == fs::file_type::not_found)
    r.fail(field, node, what + " " + shown(name) + " does not exist" + where);
  if (ec) r.fail(field, node, what + " " + shown(name) + " cannot be used: " + ec.message() + where);
  if (status.type() == fs::file_type::directory)
    r.fail(field, node, what + " " + shown(name) + " is a folder, expected a file" + where);
  if (status.type() != fs::file_type::regular)
    r.fail(field, node, what + " " + shown(name) + " is not a regular file" + where);
  return file;
}

Material read_material(Reader& r, const std::string& name, const YAML::Node& node, const std::string& field) {
  try {
    if (node.IsScalar()) {
      Material m = material_from_name(node.Scalar());
      return m;
    }
  } catch (const InputError& e) {
    r.fail(field, node, e.problem());
  }
  const Map m(r, node, field, {"index", "absorption_per_mm", "opaque"});
  if (m.has("index") == m.has("opaque")) r.fail(field, node, "needs a catalogue name, {index: n} or {opaque: albedo}");
  if (m.has("opaque")) {
    if (m.has("absorption_per_mm")) r.fail(m.path("absorption_per_mm"), node, "an opaque material has no absorption");
    const double albedo = m.real("opaque");
    if (albedo < 0 || albedo > 1) r.fail(m.path("opaque"), m.required("opaque"), "albedo must lie in [0, 1]");
    return opaque_material(name, albedo);
  }
  const double n = m.real("index");
  if (n <= 0) r.fail(m.path("index"), m.required("index"), "must be positive");
  if (n < kMinRefractiveIndex || n > kMaxRefractiveIndex)
    r.fail(m.path("index"), m.required("index"),
           fmt::format("must lie in [{}, {}], got {}", kMinRefractiveIndex, kMaxRefractiveIndex, n));
  Material mat = material_with_index(name, n);
  if (m.has("absorption_per_mm")) {
    const double a = m.real("absorption_per_mm");
    if (a < 0) r.fail(m.path("absorption_per_mm"), m.required("absorption_per_mm"), "must be 0 or more");
    if (a > kMaxAbsorption_per_mm)
      r.fail(m.path("absorption_per_mm"), m.required("absorption_per_mm"),
             fmt::format("must lie in [0, {}] per mm, got {}", kMaxAbsorption_per_mm, a));
    mat.absorption_per_mm = a;
  }
  return mat;
}

Eigen::Matrix3d read_rotation(Reader& r, const YAML::Node& node, const std::string& field) {
  const Map m(r, node, field, {"rvec_deg", "euler_deg"});
  if (m.has("rvec_deg") == m.has("euler_deg")) r.fail(field, node, "needs exactly one of rvec_deg and euler_deg");
  if (m.has("rvec_deg")) return rotation_from_rvec_deg(m.vec3("rvec_deg"));
  return rotation_from_euler_deg(m.vec3("euler_deg"));
}

// A mesh entry (of `meshes`, or a solid of type mesh with `type` among `keys`).
MeshSolid read_mesh(Reader& r, const YAML::Node& node, const std::string& field, const std::vector<std::string>& keys) {
  const Map m(r, node, field, keys);
  MeshSolid mesh;
  mesh.field = field;
  mesh.file = existing_file(r, m, "file", "mesh file");
  mesh.placement.scale = m.real_or("scale", 1);
  if (m.has("position_mm")) mesh.placement.position_mm = m.vec3("position_mm");
  if (m.has("rotation_deg")) mesh.placement.world_from_mesh = rotation_from_rvec_deg(m.vec3("rotation_deg"));
  if (m.has("normals")) {
    const std::string normals = m.text("normals");
    const auto n = mesh_normals_from_name(normals);
    if (!n) r.fail(m.path("normals"), m.required("normals"), "unknown normals '" + normals + "' (flat, smooth or file)");
    mesh.options.normals = *n;
  }
  mesh.options.crease_angle_deg = m.real_or("crease_angle_deg", mesh.options.crease_angle_deg);
  mesh.material = m.text("material");
  return mesh;
}

void read_solid(Reader& r, const YAML::Node& node, const std::string& field, Scene& scene) {
  if (!node.IsMap()) r.fail(field, node, "must be a mapping with a 'type'");
  const YAML::Node type_node = node["type"];
  if (!type_node) r.fail(field + ".type", node, "missing (required: sphere, box, slab, cylinder, rectangle or mesh)");
  const std::string type = r.text(type_node, field + ".type");
  if (type == "mesh") {
    std::vector<std::string> keys{"type"};
    keys.insert(keys.end(), kMeshKeys.begin(), kMeshKeys.end());
    scene.meshes.push_back(read_mesh(r, node, field, keys));
  } else if (type == "sphere") {
    const Map m(r, node, field, {"type", "centre_mm", "diameter_mm", "material"});
    scene.spheres.push_back({m.vec3("centre_mm"), m.real("diameter_mm"), m.text("material"), field});
  } else if (type == "box") {
    const Map m(r, node, field, {"type", "centre_mm", "size_mm", "rotation", "material"});
    BoxSolid b;
    b.centre_mm = m.vec3("centre_mm");
    b.size_mm = m.vec3("size_mm");
    if (const auto rot = m.optional("rotation")) b.world_from_box = read_rotation(r, *rot, m.path("rotation"));
    b.material = m.text("material");
    b.field = field;
    scene.boxes.push_back(b);
  } else if (type == "slab") {
    const Map m(r, node, field, {"type", "point_mm", "normal", "thickness_mm", "extent_mm", "up", "material"});
    SlabSolid s;
    s.point_mm = m.vec3("point_mm");
    s.normal = m.axis("normal");
    s.thickness_mm = m.real("thickness_mm");
    s.extent_mm = m.pair("extent_mm");
    if (m.has("up")) {
      s.up = m.axis("up");
    } else {  // world y, or world z for a slab facing y
      s.up = std::fabs(s.normal.normalized().y()) > 0.9 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitY();
    }
    s.material = m.text("material");
    s.field = field;
    scene.slabs.push_back(s);
  } else if (type == "cylinder") {
    const Map m(r, node, field, {"type", "base_centre_mm", "axis", "radius_mm", "length_mm", "material"});
    scene.cylinders.push_back(
        {m.vec3("base_centre_mm"), m.axis("axis"), m.real("radius_mm"), m.real("length_mm"), m.text("material"), field});
  } else if (type == "rectangle") {
    const Map m(r, node, field, {"type", "centre_mm", "size_mm", "normal", "up", "texture", "material"});
    RectangleSolid rect;
    rect.centre_mm = m.vec3("centre_mm");
    rect.size_mm = m.pair("size_mm");
    rect.normal = m.axis("normal");
    rect.up = m.axis("up");
    if (m.has("texture")) {
      rect.texture = existing_file(r, m, "texture", "texture image");
    }
    if (m.has("material")) rect.material = m.text("material");
    rect.field = field;
    scene.rectangles.push_back(rect);
  } else {
    r.fail(field + ".type", type_node,
           "unknown solid type '" + type + "' (sphere, box, slab, cylinder, rectangle, mesh)");
  }
}

Packing read_packing(Reader& r, const YAML::Node& node, const std::string& field) {
  const Map m(r, node, field, {"lattice", "diameter_mm", "layers", "layer_size", "origin_mm", "material", "overrides"});
  Packing p;
  p.field = field;
  const std::string lattice = m.text("lattice");
  const auto l = lattice_from_name(lattice);
  if (!l) r.fail(m.path("lattice"), m.required("lattice"), "unknown lattice '" + lattice + "' (bcc, fcc or sc)");
  p.lattice = *l;
  p.diameter_mm = m.real("diameter_mm");
  p.layers = r.whole(m.required("layers"), m.path("layers"), 1);
  const YAML::Node size = m.required("layer_size");
  if (!size.IsSequence() || size.size() != 2) r.fail(m.path("layer_size"), size, "must be a list [nx, ny]");
  for (int k = 0; k < 2; ++k) p.layer_size[k] = r.whole(size[k], fmt::format("{}[{}]", m.path("layer_size"), k), 1);
  p.origin_mm = m.vec3("origin_mm");
  p.material = m.text("material");
  if (const auto overrides = m.optional("overrides")) {
    if (!overrides->IsSequence()) r.fail(m.path("overrides"), *overrides, "must be a list");
    for (std::size_t k = 0; k < overrides->size(); ++k) {
      const std::string of = fmt::format("{}[{}]", m.path("overrides"), k);
      const Map o(r, (*overrides)[k], of, {"sphere", "region", "material"});
      PackingOverride po;
      po.field = of;
      po.material = o.text("material");
      if (o.has("sphere") == o.has("region"))
        r.fail(of, (*overrides)[k], "needs exactly one of 'sphere' [layer, i, j] and 'region' {min_mm, max_mm}");
      if (const auto s = o.optional("sphere")) {
        if (!s->IsSequence() || s->size() != 3) r.fail(o.path("sphere"), *s, "must be a list [layer, i, j]");
        std::array<int, 3> index{};
        for (int q = 0; q < 3; ++q) index[q] = r.whole((*s)[q], fmt::format("{}[{}]", o.path("sphere"), q), 0);
        po.sphere = index;
      } else {
        const Map region(r, *o.optional("region"), o.path("region"), {"min_mm", "max_mm"});
        po.region_mm = std::array<Eigen::Vector3d, 2>{region.vec3("min_mm"), region.vec3("max_mm")};
      }
      p.overrides.push_back(po);
    }
  }
  return p;
}

RigidTransform read_pose(Reader& r, const YAML::Node& node, const std::string& field) {
  const Map m(r, node, field, {"rvec", "tvec_mm", "position_mm", "look_at_mm", "up"});
  const bool explicit_pose = m.has("rvec") || m.has("tvec_mm");
  const bool look_at = m.has("position_mm") || m.has("look_at_mm") || m.has("up");
  if (explicit_pose == look_at)
    r.fail(field, node, "needs either {rvec, tvec_mm} (camera_from_world) or {position_mm, look_at_mm, up}");
  if (explicit_pose) return RigidTransform::from_rvec_tvec(m.vec3("rvec"), m.vec3("tvec_mm"));
  const Eigen::Vector3d position = m.vec3("position_mm"), target = m.vec3("look_at_mm"), up = m.vec3("up");
  try {
    return camera_from_world_look_at(position, target, up);
  } catch (const InputError& e) {
    const std::string key = e.field().substr(e.field().find('.') + 1);
    r.fail(m.path(key), m.required(key), e.problem());
  }
}

SceneCamera read_camera_entry(Reader& r, const YAML::Node& node, const std::string& field) {
  const Map m(r, node, field, {"name", "file", "model", "pose"});
  if (m.has("file") == m.has("model")) r.fail(field, node, "needs exactly one of 'file' and 'model' (inline)");
  std::optional<Camera> camera;
  std::string file;
  if (m.has("file")) {
    file = existing_file(r, m, "file", "camera file");
    try {
      camera = read_camera(file);
    } catch (const InputError& e) {
      // A problem of the file as a whole (it cannot be read) is the scene's field's;
      // one inside it names the camera file and its field.
      if (!e.field().empty()) throw;
      r.fail(m.path("file"), m.required("file"), "camera file " + shown(m.text("file")) + ": " + e.problem());
    }
  } else {
    YAML::Node model = YAML::Clone(m.required("model"));
    if (!model.IsMap()) r.fail(m.path("model"), m.required("model"), "must be a mapping of glasspiv camera fields");
    if (!model["glasspiv_camera"]) model["glasspiv_camera"] = 1;
    if (!model["name"]) model["name"] = m.has("name") ? m.text("name") : std::string("camera");
    YAML::Emitter out;
    out << model;
    try {
      camera = parse_cameras(out.c_str(), CameraFileFormat::Glasspiv, r.path()).at(0);
    } catch (const InputError& e) {
      r.fail(child(m.path("model"), e.field()), m.required("model"), "inline camera model: " + e.problem());
    }
  }
  if (m.has("name")) camera->name = m.text("name");
  if (const auto pose = m.optional("pose")) camera->camera_from_world = read_pose(r, *pose, m.path("pose"));
  if (!camera->camera_from_world)
    r.fail(m.path("pose"), node, "missing: the camera file has no pose, so the scene must give one");
  return SceneCamera{camera->name, file, *camera, field};
}

Scene parse(std::string_view contents, const std::string& path) {
  Reader r(path);
  const YAML::Node root = r.load_mapping(contents, "glasspiv scene fields");
  const Map top(r, root, "", kTopLevel);
  const YAML::Node version = top.required("glasspiv_scene");
  if (r.real(version, "glasspiv_scene") != kSceneFormatVersion)
    r.fail("glasspiv_scene", version,
           fmt::format("format version {} is not supported (this glasspiv reads version {})", version.Scalar(),
                       kSceneFormatVersion));

  Scene scene;
  scene.source = path;
  scene.wavelength_nm = top.real_or("wavelength_nm", scene.wavelength_nm);
  if (top.has("fluid")) scene.fluid = top.text("fluid");
  if (const auto materials = top.optional("materials")) {
    if (!materials->IsMap()) r.fail("materials", *materials, "must be a mapping name -> material");
    for (auto it = materials->begin(); it != materials->end(); ++it) {
      const std::string name = r.text(it->first, "materials");
      const std::string field = "materials." + name;
      if (scene.materials.count(name)) r.fail(field, it->first, "appears twice");
      r.note(field, it->second);
      scene.materials[name] = read_material(r, name, it->second, field);
    }
  }
  auto list = [&](const char* key) -> std::optional<YAML::Node> {
    const auto node = top.optional(key);
    if (node && !node->IsSequence()) r.fail(key, *node, "must be a list");
    return node;
  };
  if (const auto solids = list("solids"))
    for (std::size_t k = 0; k < solids->size(); ++k) read_solid(r, (*solids)[k], fmt::format("solids[{}]", k), scene);
  if (const auto meshes = list("meshes"))
    for (std::size_t k = 0; k < meshes->size(); ++k)
      scene.meshes.push_back(read_mesh(r, (*meshes)[k], fmt::format("meshes[{}]", k), kMeshKeys));
  if (const auto packings = list("packings"))
    for (std::size_t k = 0; k < packings->size(); ++k)
      scene.packings.push_back(read_packing(r, (*packings)[k], fmt::format("packings[{}]", k)));
  if (const auto sheet_node = top.optional("sheet")) {
    const Map m(r, *sheet_node, "sheet", {"origin_mm", "s_axis", "t_axis", "extent_mm", "thickness_mm"});
    Sheet sheet;
    sheet.origin_mm = m.vec3("origin_mm");
    sheet.s_axis = m.axis("s_axis");
    sheet.t_axis = m.axis("t_axis");
    const double dot = sheet.s_axis.dot(sheet.t_axis);
    if (std::fabs(sheet.s_axis.norm() - 1) < 1e-12 && std::fabs(sheet.t_axis.norm() - 1) < 1e-12 &&
        std::fabs(dot) <= kAxisOrthogonalityTolerance)
      sheet.t_axis = (sheet.t_axis - dot * sheet.s_axis).normalized();
    sheet.extent_mm = m.pair("extent_mm");
    sheet.thickness_mm = m.real("thickness_mm");
    scene.sheet = sheet;
  }
  if (const auto background = top.optional("background")) {
    const Map m(r, *background, "background", {"radiance"});
    scene.background.radiance = m.real("radiance");
  }
  if (const auto cameras = list("cameras"))
    for (std::size_t k = 0; k < cameras->size(); ++k)
      scene.cameras.push_back(read_camera_entry(r, (*cameras)[k], fmt::format("cameras[{}]", k)));

  try {
    validate(scene);
  } catch (const InputError& e) {
    const int line = r.line_of(e.field());
    if (line > 0) throw InputError(e.file(), e.field(), fmt::format("line {}: {}", line, e.problem()));
    throw;
  }
  return scene;
}

}  // namespace

Scene parse_scene(std::string_view contents, const std::string& path) { return parse(contents, path); }

Scene read_scene(const std::string& path) { return parse(read_file(path), path); }

namespace {

YAML::Node vec(const Eigen::Vector3d& v) {
  YAML::Node n;
  for (int k = 0; k < 3; ++k) n.push_back(v[k]);
  n.SetStyle(YAML::EmitterStyle::Flow);
  return n;
}
YAML::Node vec(const std::array<double, 2>& v) {
  YAML::Node n;
  n.push_back(v[0]);
  n.push_back(v[1]);
  n.SetStyle(YAML::EmitterStyle::Flow);
  return n;
}

YAML::Node material_node(const Material& m) {
  YAML::Node n;
  if (m.kind == MaterialKind::opaque) {
    n["opaque"] = m.albedo.value_or(1.0);
  } else if (m.dispersion.formula == Dispersion::Formula::constant && !m.dispersion.b.empty()) {
    n["index"] = m.dispersion.b[0];
    if (m.absorption_per_mm) n["absorption_per_mm"] = *m.absorption_per_mm;
  } else {
    return YAML::Node(m.name);
  }
  n.SetStyle(YAML::EmitterStyle::Flow);
  return n;
}

}  // namespace

std::string format_scene(const Scene& scene, const std::string& path) {
  YAML::Node root;
  root["glasspiv_scene"] = kSceneFormatVersion;
  root["wavelength_nm"] = scene.wavelength_nm;
  root["fluid"] = scene.fluid;
  for (const auto& [name, m] : scene.materials) root["materials"][name] = material_node(m);
  auto solid = [](const char* type) {
    YAML::Node n;
    n["type"] = type;
    return n;
  };
  for (const SphereSolid& s : scene.spheres) {
    YAML::Node n = solid("sphere");
    n["centre_mm"] = vec(s.centre_mm);
    n["diameter_mm"] = s.diameter_mm;
    n["material"] = s.material;
    root["solids"].push_back(n);
  }
  for (const BoxSolid& b : scene.boxes) {
    YAML::Node n = solid("box");
    n["centre_mm"] = vec(b.centre_mm);
    n["size_mm"] = vec(b.size_mm);
    const Eigen::AngleAxisd aa(b.world_from_box);
    if (aa.angle() != 0) n["rotation"]["rvec_deg"] = vec(Eigen::Vector3d(aa.axis() * aa.angle() * 180 / M_PI));
    n["material"] = b.material;
    root["solids"].push_back(n);
  }
  for (const SlabSolid& s : scene.slabs) {
    YAML::Node n = solid("slab");
    n["point_mm"] = vec(s.point_mm);
    n["normal"] = vec(s.normal);
    n["thickness_mm"] = s.thickness_mm;
    n["extent_mm"] = vec(s.extent_mm);
    n["up"] = vec(s.up);
    n["material"] = s.material;
    root["solids"].push_back(n);
  }
  for (const CylinderSolid& c : scene.cylinders) {
    YAML::Node n = solid("cylinder");
    n["base_centre_mm"] = vec(c.base_centre_mm);
    n["axis"] = vec(c.axis);
    n["radius_mm"] = c.radius_mm;
    n["length_mm"] = c.length_mm;
    n["material"] = c.material;
    root["solids"].push_back(n);
  }
  const fs::path folder = fs::path(path).parent_path();
  auto relative = [&](const std::string& file) {
    const fs::path base = folder.empty() ? fs::path(".") : folder;
    return fs::path(file).lexically_proximate(base).generic_string();
  };
  for (const RectangleSolid& r : scene.rectangles) {
    YAML::Node n = solid("rectangle");
    n["centre_mm"] = vec(r.centre_mm);
    n["size_mm"] = vec(r.size_mm);
    n["normal"] = vec(r.normal);
    n["up"] = vec(r.up);
    if (!r.texture.empty()) n["texture"] = relative(r.texture);
    if (!r.material.empty()) n["material"] = r.material;
    root["solids"].push_back(n);
  }
  for (const MeshSolid& m : scene.meshes) {
    YAML::Node n;
    n["file"] = relative(m.file);
    n["material"] = m.material;
    n["scale"] = m.placement.scale;
    n["position_mm"] = vec(m.placement.position_mm);
    const Eigen::AngleAxisd aa(m.placement.world_from_mesh);
    if (aa.angle() != 0) n["rotation_deg"] = vec(Eigen::Vector3d(aa.axis() * aa.angle() * 180 / M_PI));
    n["normals"] = mesh_normals_name(m.options.normals);
    if (m.options.crease_angle_deg != MeshLoadOptions{}.crease_angle_deg)
      n["crease_angle_deg"] = m.options.crease_angle_deg;
    root["meshes"].push_back(n);
  }
  for (const Packing& p : scene.packings) {
    YAML::Node n;
    n["lattice"] = lattice_name(p.lattice);
    n["diameter_mm"] = p.diameter_mm;
    n["layers"] = p.layers;
    YAML::Node size;
    size.push_back(p.layer_size[0]);
    size.push_back(p.layer_size[1]);
    size.SetStyle(YAML::EmitterStyle::Flow);
    n["layer_size"] = size;
    n["origin_mm"] = vec(p.origin_mm);
    n["material"] = p.material;
    for (const PackingOverride& o : p.overrides) {
      YAML::Node on;
      if (o.sphere) {
        YAML::Node index;
        for (int k : *o.sphere) index.push_back(k);
        index.SetStyle(YAML::EmitterStyle::Flow);
        on["sphere"] = index;
      }
      if (o.region_mm) {
        on["region"]["min_mm"] = vec((*o.region_mm)[0]);
        on["region"]["max_mm"] = vec((*o.region_mm)[1]);
      }
      on["material"] = o.material;
      n["overrides"].push_back(on);
    }
    root["packings"].push_back(n);
  }
  if (scene.sheet) {
    YAML::Node n;
    n["origin_mm"] = vec(scene.sheet->origin_mm);
    n["s_axis"] = vec(scene.sheet->s_axis);
    n["t_axis"] = vec(scene.sheet->t_axis);
    n["extent_mm"] = vec(scene.sheet->extent_mm);
    n["thickness_mm"] = scene.sheet->thickness_mm;
    root["sheet"] = n;
  }
  root["background"]["radiance"] = scene.background.radiance;
  for (const SceneCamera& c : scene.cameras) {
    YAML::Node n;
    n["name"] = c.name;
    if (!c.file.empty()) {
      n["file"] = relative(c.file);
    } else {
      Camera bare = c.camera;
      bare.camera_from_world.reset();
      YAML::Node model = YAML::Load(format_cameras({bare}, CameraFileFormat::Glasspiv, path));
      model.remove("glasspiv_camera");
      model.remove("name");
      n["model"] = model;
    }
    if (c.camera.camera_from_world) {
      n["pose"]["rvec"] = vec(c.camera.camera_from_world->rvec());
      n["pose"]["tvec_mm"] = vec(c.camera.camera_from_world->translation_mm);
    }
    root["cameras"].push_back(n);
  }
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  out << YAML::Comment("glasspiv scene (docs/scene.md): mm, nm; rotations of solids in degrees, camera rvec in radians")
      << YAML::Newline << root;
  return std::string(out.c_str()) + "\n";
}

void write_scene(const std::string& path, const Scene& scene) {
  write_file_atomically(path, format_scene(scene, path));
}

std::vector<std::string> scene_top_level_keys() { return kTopLevel; }

}  // namespace glasspiv
