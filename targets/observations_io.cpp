#include "targets/observations_io.h"

#include <cctype>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <tuple>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include "calib/camera_model.h"
#include "util/atomic_file.h"
#include "util/input_error.h"
#include "util/json_document.h"
#include "util/text_number.h"
#include "util/yaml_fields.h"

namespace glasspiv {
namespace {


constexpr int kVersion = 1;
const char* const kTopKeys[] = {"glasspiv_observations", "image_size_px", "target", "views"};
const char* const kViewKeys[] = {"source", "corners"};
constexpr const char* kCornerColumns = "[id, x_px, y_px, board_x_mm, board_y_mm, board_z_mm]";

bool known(const char* const* begin, const char* const* end, const std::string& key) {
  for (auto it = begin; it != end; ++it)
    if (key == *it) return true;
  return false;
}

// Semantic checks shared by both formats and by the writers.
// The image size as read (before narrowing to int): the camera models' limits
// (calib/camera_model.h: kMaxImageSidePx a side, kMaxImagePixels in all).
std::pair<int, int> image_size(double width, double height, const std::string& path, const std::string& where = "") {
  try {
    check_image_size(width, height, "image_size_px");
  } catch (const InputError& e) {
    throw InputError(path, e.field(), where + e.problem());
  }
  return {static_cast<int>(width), static_cast<int>(height)};
}

void check(const Observations& o, const std::string& path) {
  image_size(o.image_width_px, o.image_height_px, path);
  for (std::size_t v = 0; v < o.views.size(); ++v) {
    std::set<int> ids;
    for (std::size_t c = 0; c < o.views[v].corners.size(); ++c) {
      const CornerObservation& k = o.views[v].corners[c];
      const std::string field = fmt::format("views[{}].corners[{}]", v, c);
      if (k.id < 0) throw InputError(path, field, fmt::format("id {} is negative", k.id));
      if (!ids.insert(k.id).second)
        throw InputError(path, field, fmt::format("id {} appears twice in view '{}'", k.id, o.views[v].source));
      if (!k.pixel_px.allFinite() || !k.board_point_mm.allFinite())
        throw InputError(path, field, "has a non-finite number");
      if (k.pixel_px.x() < -0.5 || k.pixel_px.y() < -0.5 || k.pixel_px.x() > o.image_width_px - 0.5 ||
          k.pixel_px.y() > o.image_height_px - 0.5)
        throw InputError(path, field,
                         fmt::format("pixel ({}, {}) is outside the {} x {} px image", k.pixel_px.x(), k.pixel_px.y(),
                                     o.image_width_px, o.image_height_px));
    }
  }
}

// ---------------------------------------------------------------- YAML

class YamlReader : public YamlFields {
 public:
  using YamlFields::YamlFields;
  int whole(const YAML::Node& node, const std::string& field) const {
    return YamlFields::whole(node, field, std::numeric_limits<int>::min());
  }
  std::map<std::string, YAML::Node> map(const YAML::Node& node, const std::string& field, const char* const* begin,
                                        const char* const* end) const {
    if (!node.IsMap()) fail(field, node, "must be a mapping");
    std::map<std::string, YAML::Node> fields;
    for (auto it = node.begin(); it != node.end(); ++it) {
      const std::string key = it->first.IsScalar() ? it->first.Scalar() : "?";
      const std::string name = field.empty() ? key : field + "." + key;
      if (!known(begin, end, key)) {
        std::string list;
        for (auto k = begin; k != end; ++k) list += (list.empty() ? "" : ", ") + std::string(*k);
        fail(name, it->first, "unknown field (expected " + list + ")");
      }
      if (fields.count(key)) fail(name, it->first, "appears twice");
      fields[key] = it->second;
    }
    for (auto k = begin; k != end; ++k)
      if (!fields.count(*k)) fail(field.empty() ? *k : field + "." + *k, node, "missing (required)");
    return fields;
  }
};

Observations parse_yaml(std::string_view contents, const std::string& path) {
  const YamlReader r(path);
  const YAML::Node root = r.load_mapping(contents, "glasspiv observation fields");
  auto top = r.map(root, "", std::begin(kTopKeys), std::end(kTopKeys));
  if (r.real(top["glasspiv_observations"], "glasspiv_observations") != kVersion)
    r.fail("glasspiv_observations", top["glasspiv_observations"],
           fmt::format("format version {} is not supported (this glasspiv reads version {})",
                       top["glasspiv_observations"].Scalar(), kVersion));
  Observations o;
  const YAML::Node size = top["image_size_px"];
  if (!size.IsSequence() || size.size() != 2) r.fail("image_size_px", size, "must be [width, height]");
  std::tie(o.image_width_px, o.image_height_px) =
      image_size(r.real(size[0], "image_size_px[0]"), r.real(size[1], "image_size_px[1]"), path,
                 fmt::format("line {}: ", size.Mark().line + 1));
  o.target_name = r.text(top["target"], "target");
  const YAML::Node views = top["views"];
  if (!views.IsSequence()) r.fail("views", views, "must be a list of views");
  for (std::size_t v = 0; v < views.size(); ++v) {
    const std::string vf = fmt::format("views[{}]", v);
    auto fields = r.map(views[v], vf, std::begin(kViewKeys), std::end(kViewKeys));
    ViewObservations view;
    view.source = r.text(fields["source"], vf + ".source");
    const YAML::Node corners = fields["corners"];
    if (!corners.IsSequence()) r.fail(vf + ".corners", corners, std::string("must be a list of ") + kCornerColumns);
    for (std::size_t c = 0; c < corners.size(); ++c) {
      const std::string cf = fmt::format("{}.corners[{}]", vf, c);
      const YAML::Node k = corners[c];
      if (!k.IsSequence() || k.size() != 6) r.fail(cf, k, std::string("must be ") + kCornerColumns);
      CornerObservation obs;
      obs.id = r.whole(k[0], cf + "[0]");
      obs.pixel_px = Eigen::Vector2d(r.real(k[1], cf + "[1]"), r.real(k[2], cf + "[2]"));
      obs.board_point_mm = Eigen::Vector3d(r.real(k[3], cf + "[3]"), r.real(k[4], cf + "[4]"), r.real(k[5], cf + "[5]"));
      view.corners.push_back(obs);
    }
    o.views.push_back(std::move(view));
  }
  return o;
}

std::string format_yaml(const Observations& o) {
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "glasspiv_observations" << YAML::Value << kVersion;
  out << YAML::Key << "image_size_px" << YAML::Value << YAML::Flow << YAML::BeginSeq << o.image_width_px
      << o.image_height_px << YAML::EndSeq;
  out << YAML::Key << "target" << YAML::Value << YAML::DoubleQuoted << o.target_name;
  out << YAML::Key << "views" << YAML::Value << YAML::BeginSeq;
  for (const ViewObservations& view : o.views) {
    out << YAML::BeginMap;
    out << YAML::Key << "source" << YAML::Value << YAML::DoubleQuoted << view.source;
    out << YAML::Key << "corners" << YAML::Value;
    if (view.corners.empty()) {
      out << YAML::Flow << YAML::BeginSeq << YAML::EndSeq;
    } else {
      out << YAML::BeginSeq;
      for (const CornerObservation& k : view.corners) {
        out << YAML::Flow << YAML::BeginSeq << k.id << format_number(k.pixel_px.x()) << format_number(k.pixel_px.y())
            << format_number(k.board_point_mm.x()) << format_number(k.board_point_mm.y())
            << format_number(k.board_point_mm.z()) << YAML::EndSeq;
      }
      out << YAML::EndSeq;
    }
    out << YAML::EndMap;
  }
  out << YAML::EndSeq << YAML::EndMap;
  return std::string("# glasspiv observations (docs/targets.md): detected target corners per view,\n# each ") +
         kCornerColumns + "; pixel (0, 0) = centre of the top-left pixel\n" + out.c_str() + "\n";
}

// ---------------------------------------------------------------- JSON

Observations parse_json(std::string_view contents, const std::string& path) {
  using nlohmann::json;
  json root = parse_json_document(contents, path);
  auto fail = [&](const std::string& field, const std::string& problem) -> void {
    throw InputError(path, field, problem);
  };
  auto object = [&](const json& node, const std::string& field, const char* const* begin, const char* const* end) {
    if (!node.is_object()) fail(field.empty() ? "" : field, "must be an object");
    for (auto it = node.begin(); it != node.end(); ++it)
      if (!known(begin, end, it.key())) fail(field.empty() ? it.key() : field + "." + it.key(), "unknown field");
    for (auto k = begin; k != end; ++k)
      if (!node.contains(*k)) fail(field.empty() ? *k : field + "." + *k, "missing (required)");
  };
  auto real = [&](const json& node, const std::string& field) {
    if (!node.is_number()) fail(field, "must be a number");
    return node.get<double>();
  };
  auto whole = [&](const json& node, const std::string& field) {
    const double v = real(node, field);
    if (v != std::floor(v) || std::fabs(v) > 2e9) fail(field, fmt::format("must be a whole number, got {}", v));
    return static_cast<int>(v);
  };
  auto text = [&](const json& node, const std::string& field) {
    if (!node.is_string()) fail(field, "must be a text");
    return node.get<std::string>();
  };

  object(root, "", std::begin(kTopKeys), std::end(kTopKeys));
  if (real(root["glasspiv_observations"], "glasspiv_observations") != kVersion)
    fail("glasspiv_observations",
         fmt::format("format version {} is not supported (this glasspiv reads version {})",
                     root["glasspiv_observations"].dump(), kVersion));
  Observations o;
  const json& size = root["image_size_px"];
  if (!size.is_array() || size.size() != 2) fail("image_size_px", "must be [width, height]");
  std::tie(o.image_width_px, o.image_height_px) =
      image_size(real(size[0], "image_size_px[0]"), real(size[1], "image_size_px[1]"), path);
  o.target_name = text(root["target"], "target");
  const json& views = root["views"];
  if (!views.is_array()) fail("views", "must be a list of views");
  for (std::size_t v = 0; v < views.size(); ++v) {
    const std::string vf = fmt::format("views[{}]", v);
    object(views[v], vf, std::begin(kViewKeys), std::end(kViewKeys));
    ViewObservations view;
    view.source = text(views[v]["source"], vf + ".source");
    const json& corners = views[v]["corners"];
    if (!corners.is_array()) fail(vf + ".corners", std::string("must be a list of ") + kCornerColumns);
    for (std::size_t c = 0; c < corners.size(); ++c) {
      const std::string cf = fmt::format("{}.corners[{}]", vf, c);
      const json& k = corners[c];
      if (!k.is_array() || k.size() != 6) fail(cf, std::string("must be ") + kCornerColumns);
      CornerObservation obs;
      obs.id = whole(k[0], cf + "[0]");
      obs.pixel_px = Eigen::Vector2d(real(k[1], cf + "[1]"), real(k[2], cf + "[2]"));
      obs.board_point_mm = Eigen::Vector3d(real(k[3], cf + "[3]"), real(k[4], cf + "[4]"), real(k[5], cf + "[5]"));
      view.corners.push_back(obs);
    }
    o.views.push_back(std::move(view));
  }
  return o;
}

std::string json_text(const std::string& s) { return nlohmann::json(s).dump(); }

std::string format_json(const Observations& o) {
  std::string out = "{\n";
  out += fmt::format("  \"glasspiv_observations\": {},\n", kVersion);
  out += fmt::format("  \"image_size_px\": [{}, {}],\n", o.image_width_px, o.image_height_px);
  out += fmt::format("  \"target\": {},\n", json_text(o.target_name));
  out += "  \"views\": [";
  for (std::size_t v = 0; v < o.views.size(); ++v) {
    const ViewObservations& view = o.views[v];
    out += v == 0 ? "\n" : ",\n";
    out += fmt::format("    {{\"source\": {}, \"corners\": [", json_text(view.source));
    for (std::size_t c = 0; c < view.corners.size(); ++c) {
      const CornerObservation& k = view.corners[c];
      out += c == 0 ? "\n" : ",\n";
      out += fmt::format("      [{}, {}, {}, {}, {}, {}]", k.id, format_number(k.pixel_px.x()),
                         format_number(k.pixel_px.y()), format_number(k.board_point_mm.x()),
                         format_number(k.board_point_mm.y()), format_number(k.board_point_mm.z()));
    }
    out += view.corners.empty() ? "]}" : "\n    ]}";
  }
  out += o.views.empty() ? "]\n}\n" : "\n  ]\n}\n";
  return out;
}

}  // namespace

ObservationsFormat observations_format_for_path(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".yaml" || ext == ".yml") return ObservationsFormat::yaml;
  if (ext == ".json") return ObservationsFormat::json;
  throw InputError(path, "", "unknown observations file type '" + ext + "' (use .yaml, .yml or .json)");
}

Observations parse_observations(std::string_view contents, ObservationsFormat format, const std::string& path) {
  Observations o = format == ObservationsFormat::json ? parse_json(contents, path) : parse_yaml(contents, path);
  check(o, path);
  return o;
}

std::string format_observations(const Observations& observations, ObservationsFormat format) {
  check(observations, "");
  return format == ObservationsFormat::json ? format_json(observations) : format_yaml(observations);
}

Observations read_observations(const std::string& path) {
  return parse_observations(read_file(path), observations_format_for_path(path), path);
}

void write_observations(const std::string& path, const Observations& observations) {
  const ObservationsFormat format = observations_format_for_path(path);
  check(observations, path);
  write_file_atomically(path, format_observations(observations, format));
}

std::string format_mrcal_corners_vnl(const Observations& o, const TargetSpec& spec, const std::string& path) {
  int width = 0, height = 0;
  double spacing = 0;
  if (!corner_grid(spec, width, height, spacing))
    throw InputError(path, "", fmt::format("mrcal's corners.vnl holds a regular grid of corners; a {}'s tag corners "
                                           "are not one (write the glasspiv YAML or JSON instead)",
                                           target_kind_name(spec.kind)));
  check(o, path);
  std::string out = "# filename x y level\n";
  out += fmt::format(
      "## glasspiv target '{}': a {} x {} grid of corners {} mm apart, row-major from the board's top-left\n"
      "## (mrcal-calibrate-cameras --object-width-n {} --object-height-n {} --object-spacing {})\n",
      o.target_name, width, height, format_number(spacing), width, height, format_number(spacing));
  const int n = width * height;
  for (std::size_t v = 0; v < o.views.size(); ++v) {
    const ViewObservations& view = o.views[v];
    const std::string field = fmt::format("views[{}].source", v);
    if (view.source.empty()) throw InputError(path, field, "is empty; mrcal's corners.vnl needs a file name");
    for (const char c : view.source)
      if (std::isspace(static_cast<unsigned char>(c)))
        throw InputError(path, field,
                         fmt::format("'{}' has white space, which mrcal's corners.vnl cannot hold", view.source));
    if (view.source[0] == '#')
      throw InputError(path, field, fmt::format("'{}' starts with '#', which mrcal reads as a comment", view.source));
    if (view.corners.empty()) {
      out += view.source + " - -\n";
      continue;
    }
    std::vector<const CornerObservation*> grid(static_cast<std::size_t>(n), nullptr);
    for (const CornerObservation& k : view.corners) {
      if (k.id >= n)
        throw InputError(path, field,
                         fmt::format("corner id {} of '{}' is not on the {} x {} grid", k.id, view.source, width,
                                     height));
      grid[static_cast<std::size_t>(k.id)] = &k;
    }
    for (const CornerObservation* k : grid)
      out += k ? fmt::format("{} {} {} 0\n", view.source, format_number(k->pixel_px.x()), format_number(k->pixel_px.y()))
               : view.source + " - - -\n";
  }
  return out;
}

void write_mrcal_corners_vnl(const std::string& path, const Observations& observations, const TargetSpec& spec) {
  write_file_atomically(path, format_mrcal_corners_vnl(observations, spec, path));
}

}  // namespace glasspiv
