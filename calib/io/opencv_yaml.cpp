#include "calib/io/opencv_yaml.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <set>

#include <fmt/format.h>
#include <opencv2/core.hpp>
#include <yaml-cpp/yaml.h>

#include "calib/io/camera_file.h"
#include "calib/io/camera_yaml_fields.h"
#include "util/input_error.h"
#include "util/text_number.h"

namespace glasspiv {
namespace {

// yaml-cpp's parser recurses once per level of nesting, so a file nested deep
// enough overflows the stack (SIGSEGV): measure the depth on the text first.
// Every indentation step, "- " entry and '[' / '{' adds a level (also in
// comments and strings, which only overcounts), and a ']' / '}' ends one only
// outside comments and quotes on its line; quoted text spanning lines can hide
// a level, which yaml-cpp's own depth guard (2000 levels) then refuses.
void check_nesting_depth(std::string_view text, const std::string& path) {
  std::vector<std::size_t> indents;  // columns of the open block levels
  int flow = 0;
  int line = 0;
  auto check = [&](std::size_t depth) {
    if (depth > static_cast<std::size_t>(kMaxOpenCVNestingDepth))
      throw InputError(path, "",
                       fmt::format("line {}: nested more than {} levels deep (lists and mappings); glasspiv reads "
                                   "OpenCV FileStorage files nested at most {} levels",
                                   line, kMaxOpenCVNestingDepth, kMaxOpenCVNestingDepth));
  };
  for (std::size_t at = 0; at < text.size();) {
    ++line;
    const std::size_t end = std::min(text.find('\n', at), text.size());
    const std::string_view l = text.substr(at, end - at);
    at = end + 1;
    std::size_t column = l.find_first_not_of(" \t\r");
    if (column == std::string_view::npos) continue;
    // Block levels: the indentation, then the content after each "- ".
    while (!indents.empty() && indents.back() > column) indents.pop_back();
    for (;;) {
      if (indents.empty() || indents.back() < column) indents.push_back(column);
      if (l[column] != '-' || (column + 1 < l.size() && l[column + 1] != ' ' && l[column + 1] != '\t')) break;
      const std::size_t next = l.find_first_not_of(" \t\r", column + 1);
      if (next == std::string_view::npos) break;
      column = next;
    }
    check(indents.size() + static_cast<std::size_t>(flow));
    // Flow levels; from a quote or '#' on, the line may be text: count its
    // openings but none of its closings.
    bool maybe_text = false;
    for (std::size_t i = column; i < l.size(); ++i) {
      const char c = l[i];
      if (c == '[' || c == '{') {
        ++flow;
        check(indents.size() + static_cast<std::size_t>(flow));
      } else if ((c == ']' || c == '}') && !maybe_text) {
        flow = std::max(0, flow - 1);
      } else if (c == '"' || c == '\'' || c == '#') {
        maybe_text = true;
      }
    }
  }
}

// OpenCV's own FileStorage parser (4.6) can loop forever on malformed YAML
// (tests/fuzz/crashes/camera_opencv/ holds its hangs), so the file is read with
// yaml-cpp. The "%YAML:1.0" line FileStorage writes is its own spelling of the
// directive, not YAML's: it becomes a comment, so line numbers stay the file's.
// A second document is refused before yaml-cpp parses (its LoadAll runs away on
// some damaged multi-document texts), and FileStorage's JSON is YAML too.
YAML::Node load_one_mapping(std::string_view contents, const YamlFields& fields) {
  std::string yaml(contents);
  if (yaml.compare(0, 3, "\xEF\xBB\xBF") == 0) yaml.erase(0, 3);
  const std::size_t first = yaml.find_first_not_of(" \t\r\n");
  if (first != std::string::npos && yaml.compare(first, 6, "%YAML:") == 0) yaml[first] = '#';
  // "---" starts a document (text may follow it on its line), "..." ends one.
  bool content = false, ended = false;
  int line = 0;
  const auto text_from = [](std::string_view l, std::size_t from) {
    const std::size_t at = l.find_first_not_of(" \t\r", std::min(from, l.size()));
    return at != std::string_view::npos && l[at] != '#';
  };
  const auto is_marker = [](std::string_view l, const char* m) {
    return l.rfind(m, 0) == 0 && (l.size() == 3 || l[3] == ' ' || l[3] == '\t' || l[3] == '\r');
  };
  for (std::size_t pos = 0; pos < yaml.size(); ++line) {
    const std::size_t eol = std::min(yaml.find('\n', pos), yaml.size());
    const std::string_view l(yaml.data() + pos, eol - pos);
    pos = eol + 1;
    if (is_marker(l, "...")) {
      ended = ended || content;
      continue;
    }
    const bool start = is_marker(l, "---");
    const bool has_text = text_from(l, start ? 3 : 0);
    if ((start && (content || ended)) || (has_text && ended))
      throw InputError(fields.path(), "",
                       fmt::format("line {}: a second YAML document; a camera file holds one", line + 1));
    content = content || has_text;
  }
  return fields.load_mapping(yaml, "OpenCV FileStorage fields (camera_matrix, ...)");
}

// FileStorage keeps both entries of a key given twice (and reads the first), as
// yaml-cpp does: refuse them, in every mapping. FileStorage has no anchors or
// aliases; through them yaml-cpp's tree can be deeper than the text's nesting
// and repeat a subtree without end ("billion laughs"), so the walk is bounded in
// depth and in nodes: a tree without aliases has fewer nodes than its text has
// characters.
class UniqueKeys {
 public:
  UniqueKeys(const YamlFields& fields, std::size_t text_size) : fields_(fields), budget_(text_size + 16) {}

  void check(const YAML::Node& node) { check(node, nullptr, 0); }

 private:
  // A node's field name ("a.b[2]"), spelled out only for an error: building it
  // for every node costs the key's length each time (a megabyte key over a
  // long list is hours).
  struct Path {
    const Path* parent;
    const std::string* key;  // a mapping's key, or nullptr for a list's index
    std::size_t index;
    static std::string text(const Path* p) {
      if (p == nullptr) return "";
      std::string prefix = text(p->parent);
      if (p->key == nullptr) return fmt::format("{}[{}]", prefix, p->index);
      return prefix.empty() ? *p->key : prefix + "." + *p->key;
    }
  };

  void check(const YAML::Node& node, const Path* path, int depth) {
    if (depth > kMaxOpenCVNestingDepth)
      fields_.fail(Path::text(path), node,
                   fmt::format("nested more than {} levels deep through YAML aliases; glasspiv reads OpenCV "
                               "FileStorage files nested at most {} levels",
                               kMaxOpenCVNestingDepth, kMaxOpenCVNestingDepth));
    if (budget_-- == 0)
      fields_.fail(Path::text(path), node,
                   "holds more values than its text spells out (YAML aliases repeat them); OpenCV FileStorage "
                   "files have no aliases");
    if (node.IsMap()) {
      std::set<std::string> keys;
      for (auto it = node.begin(); it != node.end(); ++it) {
        if (!it->first.IsScalar()) fields_.fail(Path::text(path), it->first, "has a key that is not a text");
        const std::string& key = it->first.Scalar();
        const Path child{path, &key, 0};
        if (!keys.insert(key).second)
          fields_.fail(Path::text(&child), it->first, "appears twice (the key '" + key + "' is given more than once)");
        check(it->second, &child, depth + 1);
      }
    } else if (node.IsSequence()) {
      for (std::size_t i = 0; i < node.size(); ++i) {
        const Path child{path, nullptr, i};
        check(node[i], &child, depth + 1);
      }
    }
  }

  const YamlFields& fields_;
  std::size_t budget_;
};

// An OpenCV element type code ("d", "f", "u", ...): the range of values it
// holds exactly, or nullopt for codes glasspiv does not read.
struct ElementType {
  char code;
  double min, max;
  bool whole;
};
std::optional<ElementType> element_type(char code) {
  switch (code) {
    case 'u': return ElementType{code, 0, 255, true};
    case 'c': return ElementType{code, -128, 127, true};
    case 'w': return ElementType{code, 0, 65535, true};
    case 's': return ElementType{code, -32768, 32767, true};
    case 'i': return ElementType{code, -2147483648.0, 2147483647.0, true};
    case 'f': return ElementType{code, -std::numeric_limits<float>::max(), std::numeric_limits<float>::max(), false};
    case 'd': return ElementType{code, -std::numeric_limits<double>::max(), std::numeric_limits<double>::max(), false};
    default: return std::nullopt;
  }
}

// A matrix read from the file, row-major.
struct Matrix {
  int rows = 0, cols = 0;
  std::vector<double> values;
  double at(int r, int c) const { return values[static_cast<std::size_t>(r) * cols + c]; }
};

class Reader : public CameraYamlFields {
 public:
  using CameraYamlFields::CameraYamlFields;

  int required_image_side(const YAML::Node& node, const std::string& field) const {
    if (!node.IsDefined())
      throw InputError(path(), field, "missing (required: glasspiv needs the image size to build a camera model)");
    return image_side(node, field);
  }

  // An !!opencv-matrix, or a plain list of numbers (read as one row).
  Matrix matrix(const YAML::Node& node, const std::string& field) const {
    if (node.IsSequence()) {
      Matrix m{1, static_cast<int>(node.size()), reals(node, field)};
      if (m.cols == 0) m.rows = 0;
      return m;
    }
    if (!node.IsMap() || !node["rows"].IsDefined() || !node["cols"].IsDefined() || !node["data"].IsDefined())
      fail(field, node, "must be an !!opencv-matrix (rows, cols, dt, data) or a list of numbers");
    // dt is checked rather than trusted: OpenCV's `node >> m` converts every
    // value to it silently (dt: u turns 600 into 255).
    const int rows = whole(node["rows"], field + ".rows", 0), cols = whole(node["cols"], field + ".cols", 0);
    const YAML::Node dt_node = node["dt"];
    if (!dt_node.IsDefined()) fail(field + ".dt", node, "missing (the element type, e.g. d for double)");
    const std::string dt = text(dt_node, field + ".dt");
    std::size_t digits = 0;
    while (digits < dt.size() && std::isdigit(static_cast<unsigned char>(dt[digits]))) ++digits;
    if (digits > 0 && dt.substr(0, digits) != "1" && dt.size() == digits + 1 && element_type(dt.back()))
      fail(field, dt_node, fmt::format("must have one channel, dt '{}' has {}", dt, dt.substr(0, digits)));
    const std::optional<ElementType> type =
        dt.size() == digits + 1 ? element_type(dt.back()) : std::optional<ElementType>();
    if (!type)
      fail(field + ".dt", dt_node,
           fmt::format("element type '{}' is not one glasspiv reads (d, f, i, s, w, c or u, one channel)", dt));
    const YAML::Node data = node["data"];
    if (!data.IsSequence()) fail(field + ".data", data, "must be a list of numbers");
    const std::int64_t expected = static_cast<std::int64_t>(rows) * cols;
    if (static_cast<std::int64_t>(data.size()) != expected)
      fail(field, node,
           fmt::format("rows x cols = {} x {} = {} elements, but data has {}", rows, cols, expected, data.size()));
    Matrix m{expected == 0 ? 0 : rows, expected == 0 ? 0 : cols, {}};
    for (std::int64_t i = 0; i < expected; ++i) {
      const std::string f = fmt::format("{}.data[{}]", field, i);
      double v = real(data[static_cast<std::size_t>(i)], f);
      if (v < type->min || v > type->max || (type->whole && v != std::floor(v)))
        fail(f, data[static_cast<std::size_t>(i)],
             fmt::format("element ({}, {}) = {} does not fit dt '{}' ({} {} to {})", i / cols, i % cols,
                         format_number(v), type->code, type->whole ? "whole numbers" : "numbers",
                         format_number(type->min), format_number(type->max)));
      if (type->code == 'f') v = static_cast<float>(v);  // what a 32-bit matrix holds
      m.values.push_back(v);
    }
    return m;
  }

  // A 1xN or Nx1 matrix (or list) as a vector.
  std::vector<double> vector(const YAML::Node& node, const std::string& field) const {
    Matrix m = matrix(node, field);
    if (m.rows != 1 && m.cols != 1 && !m.values.empty())
      fail(field, node, fmt::format("must be a 1xN or Nx1 matrix, is {}x{}", m.rows, m.cols));
    return std::move(m.values);
  }
};

std::vector<Camera> parse(std::string_view contents, const std::string& path) {
  check_nesting_depth(contents, path);
  const Reader r(path);
  const YAML::Node root = load_one_mapping(contents, r);
  UniqueKeys(r, contents.size()).check(root);
  auto node = [&](const char* key) { return root[key]; };

  std::string name = camera_file_detail::default_camera_name(path);
  if (const YAML::Node n = node("camera_name"); n.IsDefined()) name = r.text(n, "camera_name");

  const int width = r.required_image_side(node("image_width"), "image_width");
  const int height = r.required_image_side(node("image_height"), "image_height");
  camera_file_detail::checked_image_size(width, height, path, "image_width");

  const YAML::Node k_node = node("camera_matrix");
  if (!k_node.IsDefined()) throw InputError(path, "camera_matrix", "missing (required)");
  const Matrix k = r.matrix(k_node, "camera_matrix");
  if (k.rows != 3 || k.cols != 3)
    r.fail("camera_matrix", k_node, fmt::format("must be a 3x3 matrix, is {}x{}", k.rows, k.cols));
  if (k.at(0, 1) != 0)
    r.fail("camera_matrix", k_node,
           fmt::format("has skew K(0,1) = {}; glasspiv's model (like OpenCV's calibrateCamera) has none",
                       format_real(k.at(0, 1))));
  if (k.at(1, 0) != 0) r.fail("camera_matrix", k_node, fmt::format("K(1,0) = {} must be 0", format_real(k.at(1, 0))));
  if (k.at(2, 0) != 0 || k.at(2, 1) != 0 || k.at(2, 2) != 1)
    r.fail("camera_matrix", k_node,
           fmt::format("last row must be (0, 0, 1), is ({}, {}, {})", format_real(k.at(2, 0)), format_real(k.at(2, 1)),
                       format_real(k.at(2, 2))));
  if (!(k.at(0, 0) > 0) || !(k.at(1, 1) > 0))
    r.fail("camera_matrix", k_node, "focal lengths K(0,0) and K(1,1) must be positive");

  const YAML::Node d_node = node("distortion_coefficients");
  if (!d_node.IsDefined())
    throw InputError(path, "distortion_coefficients",
                     "missing (required; write an empty matrix or [] for a camera without distortion)");
  const std::vector<double> distortion = r.vector(d_node, "distortion_coefficients");
  lens_model_for_count(distortion.size(), "distortion_coefficients");  // throws for other lengths

  std::optional<double> pitch_um;
  if (const YAML::Node n = node("pixel_pitch_um"); n.IsDefined()) {
    pitch_um = r.real(n, "pixel_pitch_um");
    if (const std::string problem = camera_file_detail::pixel_pitch_problem(*pitch_um); !problem.empty())
      r.fail("pixel_pitch_um", n, fmt::format("{}, got {}", problem, *pitch_um));
  }

  std::optional<RigidTransform> pose;
  const YAML::Node rvec_node = node("rvec"), tvec_node = node("tvec");
  if (rvec_node.IsDefined() || tvec_node.IsDefined()) {
    if (!rvec_node.IsDefined()) throw InputError(path, "rvec", "missing (tvec is given; the pose needs both)");
    if (!tvec_node.IsDefined()) throw InputError(path, "tvec", "missing (rvec is given; the pose needs both)");
    const std::vector<double> rv = r.vector(rvec_node, "rvec");
    const std::vector<double> tv = r.vector(tvec_node, "tvec");
    if (rv.size() != 3) r.fail("rvec", rvec_node, fmt::format("must have 3 elements, has {}", rv.size()));
    if (tv.size() != 3) r.fail("tvec", tvec_node, fmt::format("must have 3 elements, has {}", tv.size()));
    pose = RigidTransform::from_rvec_tvec({rv[0], rv[1], rv[2]}, {tv[0], tv[1], tv[2]});
  }

  return {Camera{name, CameraModel(width, height, k.at(0, 0), k.at(1, 1), k.at(0, 2), k.at(1, 2), distortion), pose,
                 pitch_um}};
}

}  // namespace

std::vector<Camera> parse_opencv_yaml(std::string_view contents, const std::string& path) {
  try {
    return parse(contents, path);
  } catch (const InputError&) {
    camera_file_detail::rethrow_naming_file(path);
  } catch (const YAML::Exception& e) {
    throw InputError(path, "", fmt::format("malformed YAML, line {}: {}", e.mark.line + 1, e.msg));
  }
}

std::string format_opencv_yaml(const std::vector<Camera>& cameras, const std::string& path) {
  if (cameras.size() != 1)
    throw InputError(path, "",
                     fmt::format("an OpenCV camera file holds one camera, {} were given (write one file each)",
                                 cameras.size()));
  const Camera& camera = cameras.front();
  camera_file_detail::check_writable(camera, path);
  const CameraModel& m = camera.model;
  try {
    cv::FileStorage fs(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
    fs.writeComment("glasspiv camera (docs/formats.md); rvec/tvec, if present, are camera_from_world, tvec in mm");
    // write(), not <<: FileStorage's << takes a text that starts with a
    // bracket or a brace for the start or end of a structure (a name "}" crashes it).
    if (!camera.name.empty()) fs.write("camera_name", camera.name);
    fs << "image_width" << m.width_px() << "image_height" << m.height_px();
    cv::Mat k(3, 3, CV_64F);
    const Eigen::Matrix3d km = m.camera_matrix();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) k.at<double>(r, c) = km(r, c);
    fs << "camera_matrix" << k;
    const std::vector<double> distortion = m.distortion();
    cv::Mat d(1, static_cast<int>(distortion.size()), CV_64F);
    for (std::size_t i = 0; i < distortion.size(); ++i) d.at<double>(0, static_cast<int>(i)) = distortion[i];
    fs << "distortion_coefficients" << d;
    if (camera.pixel_pitch_um) fs << "pixel_pitch_um" << *camera.pixel_pitch_um;
    if (camera.camera_from_world) {
      const Eigen::Vector3d rvec = camera.camera_from_world->rvec();
      const Eigen::Vector3d& t = camera.camera_from_world->translation_mm;
      fs << "rvec" << (cv::Mat_<double>(3, 1) << rvec.x(), rvec.y(), rvec.z());
      fs << "tvec" << (cv::Mat_<double>(3, 1) << t.x(), t.y(), t.z());
    }
    std::string text = fs.releaseAndGetString();
    // FileStorage leaves some texts unquoted ("[x]", "null") that then read
    // back as something else, in OpenCV or in glasspiv's reader: refuse those
    // names rather than write a file that fails.
    if (!camera.name.empty()) {
      cv::FileStorage check(text, cv::FileStorage::READ | cv::FileStorage::MEMORY);
      const cv::FileNode n = check["camera_name"];
      bool same = n.isString() && n.string() == camera.name;
      try {
        same = same && parse(text, path).front().name == camera.name;
      } catch (const InputError&) {
        same = false;
      }
      if (!same)
        throw InputError(path, "camera_name",
                         "OpenCV FileStorage cannot store the camera name '" + camera.name + "'; rename the camera");
    }
    return text;
  } catch (const cv::Exception& e) {
    throw InputError(path, "", "OpenCV FileStorage cannot write it: " + e.err);
  }
}

}  // namespace glasspiv
