#include "targets/target_yaml.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <vector>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "util/atomic_file.h"
#include "util/input_error.h"
#include "util/text_number.h"
#include "util/yaml_fields.h"

namespace glasspiv {
namespace {


constexpr int kVersion = 1;

// The keys each kind reads, in the order they are written.
const std::vector<std::string> kCommonKeys = {"glasspiv_target", "name", "kind"};
const std::vector<std::string> kChessboardKeys = {"squares", "square_size_mm"};
const std::vector<std::string> kCharucoKeys = {"squares",    "square_size_mm", "marker_size_mm",
                                               "dictionary", "first_id",       "charuco_layout"};
const std::vector<std::string> kAprilgridKeys = {"tags", "tag_size_mm", "tag_spacing_mm", "dictionary", "first_id"};
const std::vector<std::string> kArucoMarkerKeys = {"dictionary", "marker_id", "marker_size_mm"};
const std::vector<std::string> kAprilTagKeys = {"dictionary", "tag_id", "tag_size_mm"};
const std::vector<std::string> kSpeckleKeys = {"plate_size_mm", "dot_diameter_mm", "fill", "seed"};
const TargetKind kKinds[] = {TargetKind::chessboard, TargetKind::charuco,  TargetKind::aprilgrid,
                             TargetKind::aruco_marker, TargetKind::apriltag, TargetKind::speckle};

const std::vector<std::string>& kind_keys(TargetKind kind) {
  switch (kind) {
    case TargetKind::chessboard: return kChessboardKeys;
    case TargetKind::charuco: return kCharucoKeys;
    case TargetKind::aprilgrid: return kAprilgridKeys;
    case TargetKind::aruco_marker: return kArucoMarkerKeys;
    case TargetKind::apriltag: return kAprilTagKeys;
    case TargetKind::speckle: return kSpeckleKeys;
  }
  return kCharucoKeys;
}

bool contains(const std::vector<std::string>& keys, const std::string& key) {
  for (const auto& k : keys)
    if (k == key) return true;
  return false;
}

std::string join(const std::vector<std::string>& keys) {
  std::string list;
  for (const auto& k : keys) list += (list.empty() ? "" : ", ") + k;
  return list;
}

class Reader : public YamlFields {
 public:
  using YamlFields::YamlFields;

  double length(const YAML::Node& node, const std::string& field) const {
    const double value = real(node, field);
    if (!(value > 0)) fail(field, node, "must be a positive length in mm, got " + node.Scalar());
    return value;
  }

  // An unsigned 64-bit integer written in decimal digits (no sign, point,
  // exponent or other base): a seed must read back as the same integer.
  std::uint64_t unsigned64(const YAML::Node& node, const std::string& field) const {
    const std::string text = node.IsScalar() ? node.Scalar() : std::string();
    const bool digits = !text.empty() && text.size() <= 20 &&
                        std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; });
    std::uint64_t value = 0;
    bool fits = digits;
    for (std::size_t i = 0; fits && i < text.size(); ++i) {
      const std::uint64_t digit = static_cast<std::uint64_t>(text[i] - '0');
      if (value > (UINT64_MAX - digit) / 10) fits = false;
      else value = value * 10 + digit;
    }
    if (!fits)
      fail(field, node, fmt::format("must be a whole number from 0 to {} written in digits, got '{}'", UINT64_MAX,
                                    node.IsScalar() ? node.Scalar() : std::string("a ") + (node.IsSequence() ? "list" : "mapping")));
    return value;
  }

  std::pair<int, int> pair(const YAML::Node& node, const std::string& field, const char* what) const {
    if (!node.IsSequence() || node.size() != 2)
      fail(field, node, fmt::format("must be a list of two whole numbers, [{} across, {} down]", what, what));
    return {whole(node[0], field + "[0]", 1), whole(node[1], field + "[1]", 1)};
  }
};

// The comment line may not break: a name with a newline would end it.
std::string one_line(std::string text) {
  for (char& c : text)
    if (c == '\n' || c == '\r') c = ' ';
  return text;
}

std::string default_name(const std::string& path) {
  if (path.empty()) return "";
  return std::filesystem::path(path).stem().string();
}

}  // namespace

TargetSpec parse_target_yaml(std::string_view contents, const std::string& path) {
  const Reader r(path);
  const YAML::Node root = r.load_mapping(contents, "glasspiv target fields");

  std::map<std::string, YAML::Node> fields;
  std::vector<std::pair<std::string, YAML::Node>> order;
  for (auto it = root.begin(); it != root.end(); ++it) {
    const std::string key = it->first.IsScalar() ? it->first.Scalar() : std::string("?");
    if (fields.count(key)) r.fail(key, it->first, "appears twice");
    fields[key] = it->second;
    order.emplace_back(key, it->first);
  }
  auto required = [&](const std::string& key) {
    const auto it = fields.find(key);
    if (it == fields.end()) throw InputError(path, key, "missing (required)");
    return it->second;
  };
  auto optional = [&](const std::string& key) -> std::optional<YAML::Node> {
    const auto it = fields.find(key);
    if (it == fields.end()) return std::nullopt;
    return it->second;
  };

  const YAML::Node version = required("glasspiv_target");
  if (r.real(version, "glasspiv_target") != kVersion)
    r.fail("glasspiv_target", version,
           fmt::format("format version {} is not supported (this glasspiv reads version {})", version.Scalar(),
                       kVersion));

  TargetSpec spec;
  const YAML::Node kind_node = required("kind");
  const std::string kind = r.text(kind_node, "kind");
  bool known = false;
  std::string kinds;
  for (const TargetKind k : kKinds) {
    kinds += (kinds.empty() ? "" : ", ") + target_kind_name(k);
    if (kind == target_kind_name(k)) spec.kind = k, known = true;
  }
  if (!known) r.fail("kind", kind_node, "'" + kind + "' is not a target kind (" + kinds + ")");

  const std::vector<std::string>& keys = kind_keys(spec.kind);
  for (const auto& [key, key_node] : order) {
    if (contains(kCommonKeys, key) || contains(keys, key)) continue;
    for (const TargetKind other : kKinds)
      if (contains(kind_keys(other), key))
        r.fail(key, key_node,
               fmt::format("{} targets do not use it (they have {}, {})", kind, join(kCommonKeys), join(keys)));
    r.fail(key, key_node, fmt::format("unknown field ({} targets have {}, {})", kind, join(kCommonKeys), join(keys)));
  }

  spec.name = optional("name") ? r.text(*optional("name"), "name") : default_name(path);

  if (spec.kind == TargetKind::speckle) {
    const std::vector<double> size = r.reals(required("plate_size_mm"), "plate_size_mm", 2);
    for (int k = 0; k < 2; ++k)
      if (!(size[k] > 0))
        r.fail(fmt::format("plate_size_mm[{}]", k), *optional("plate_size_mm"),
               fmt::format("must be a positive length in mm, got {}", size[k]));
    spec.plate_size_mm = Eigen::Vector2d(size[0], size[1]);
    spec.dot_diameter_mm = r.length(required("dot_diameter_mm"), "dot_diameter_mm");
    spec.fill = r.real(required("fill"), "fill");
    spec.seed = r.unsigned64(required("seed"), "seed");
  } else if (spec.kind == TargetKind::aruco_marker || spec.kind == TargetKind::apriltag) {
    const bool aruco = spec.kind == TargetKind::aruco_marker;
    const std::string id = aruco ? "marker_id" : "tag_id", size = aruco ? "marker_size_mm" : "tag_size_mm";
    spec.dictionary = r.text(required("dictionary"), "dictionary");
    spec.first_id = r.whole(required(id), id, 0);
    spec.marker_size_mm = r.length(required(size), size);
  } else if (spec.kind == TargetKind::aprilgrid) {
    std::tie(spec.squares_x, spec.squares_y) = r.pair(required("tags"), "tags", "tags");
    spec.square_size_mm = r.length(required("tag_size_mm"), "tag_size_mm");
    spec.marker_size_mm = r.length(required("tag_spacing_mm"), "tag_spacing_mm");
    spec.dictionary = optional("dictionary") ? r.text(*optional("dictionary"), "dictionary") : "tag36h11";
  } else {
    std::tie(spec.squares_x, spec.squares_y) = r.pair(required("squares"), "squares", "squares");
    spec.square_size_mm = r.length(required("square_size_mm"), "square_size_mm");
    if (spec.kind == TargetKind::charuco) {
      spec.marker_size_mm = r.length(required("marker_size_mm"), "marker_size_mm");
      spec.dictionary = r.text(required("dictionary"), "dictionary");
      if (const auto layout = optional("charuco_layout")) {
        const std::string name = r.text(*layout, "charuco_layout");
        if (name == "opencv") spec.charuco_layout = CharucoLayout::opencv;
        else if (name == "legacy") spec.charuco_layout = CharucoLayout::legacy;
        else r.fail("charuco_layout", *layout, "'" + name + "' is not a layout (opencv or legacy)");
      }
    }
  }
  if (const auto first = optional("first_id")) spec.first_id = r.whole(*first, "first_id", 0);

  validate_target(spec, path);
  return spec;
}

TargetSpec read_target_yaml(const std::string& path) { return parse_target_yaml(read_file(path), path); }

std::string format_target_yaml(const TargetSpec& spec) {
  validate_target(spec);
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "glasspiv_target" << YAML::Value << kVersion;
  if (!spec.name.empty()) out << YAML::Key << "name" << YAML::Value << spec.name;
  out << YAML::Key << "kind" << YAML::Value << target_kind_name(spec.kind);
  if (spec.kind == TargetKind::speckle) {
    out << YAML::Key << "plate_size_mm" << YAML::Value << YAML::Flow << YAML::BeginSeq
        << format_number(spec.plate_size_mm.x()) << format_number(spec.plate_size_mm.y()) << YAML::EndSeq;
    out << YAML::Key << "dot_diameter_mm" << YAML::Value << format_number(spec.dot_diameter_mm);
    out << YAML::Key << "fill" << YAML::Value << format_number(spec.fill);
    out << YAML::Key << "seed" << YAML::Value << std::to_string(spec.seed);
    out << YAML::EndMap;
    return "# glasspiv speckle plate (docs/targets.md): " + one_line(describe_target(spec)) + "\n" + out.c_str() + "\n";
  }
  if (is_single_marker(spec.kind)) {
    const bool aruco = spec.kind == TargetKind::aruco_marker;
    out << YAML::Key << "dictionary" << YAML::Value << spec.dictionary;
    out << YAML::Key << (aruco ? "marker_id" : "tag_id") << YAML::Value << spec.first_id;
    out << YAML::Key << (aruco ? "marker_size_mm" : "tag_size_mm") << YAML::Value
        << format_number(spec.marker_size_mm);
    out << YAML::EndMap;
    return "# glasspiv target (docs/targets.md): " + one_line(describe_target(spec)) + "\n" + out.c_str() + "\n";
  }
  const bool grid = spec.kind == TargetKind::aprilgrid;
  out << YAML::Key << (grid ? "tags" : "squares") << YAML::Value << YAML::Flow << YAML::BeginSeq << spec.squares_x
      << spec.squares_y << YAML::EndSeq;
  out << YAML::Key << (grid ? "tag_size_mm" : "square_size_mm") << YAML::Value
      << format_number(spec.square_size_mm);
  if (spec.kind != TargetKind::chessboard) {
    out << YAML::Key << (grid ? "tag_spacing_mm" : "marker_size_mm") << YAML::Value
        << format_number(spec.marker_size_mm);
    out << YAML::Key << "dictionary" << YAML::Value << spec.dictionary;
    out << YAML::Key << "first_id" << YAML::Value << spec.first_id;
  }
  if (spec.kind == TargetKind::charuco)
    out << YAML::Key << "charuco_layout" << YAML::Value << charuco_layout_name(spec.charuco_layout);
  out << YAML::EndMap;
  return "# glasspiv calibration target (docs/targets.md): " + one_line(describe_target(spec)) + "\n" + out.c_str() +
         "\n";
}

void write_target_yaml(const std::string& path, const TargetSpec& spec) {
  write_file_atomically(path, format_target_yaml(spec));
}

}  // namespace glasspiv
