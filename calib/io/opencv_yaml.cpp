#include "calib/io/opencv_yaml.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <set>
#include <stdexcept>

#include <fmt/format.h>
#include <opencv2/core.hpp>
#include <yaml-cpp/yaml.h>

#include "calib/io/camera_file.h"
#include "util/input_error.h"
#include "util/text_number.h"

namespace glasspiv {
namespace {


// OpenCV's parser reports "(LINE): message" in cv::Exception::func; other
// failures carry their text in cv::Exception::err.
std::string describe(const cv::Exception& e, int added_lines) {
  const std::string& func = e.func;
  const std::size_t close = func.find("): ");
  if (!func.empty() && func[0] == '(' && close != std::string::npos) {
    int line = 0;
    const auto [end, ec] = std::from_chars(func.data() + 1, func.data() + close, line);
    if (ec == std::errc() && end == func.data() + close)
      return fmt::format("malformed OpenCV FileStorage YAML, line {}: {}", line - added_lines, func.substr(close + 3));
  }
  return "OpenCV FileStorage cannot read it: " + e.err;
}

// OpenCV 4.6's parser also fails with standard exceptions on some malformed
// texts (std::length_error from a string it sizes from the input): the file's
// fault, not an internal error.
std::string describe(const std::exception& e) {
  return std::string("OpenCV FileStorage's parser failed on it (") + e.what() + ")";
}

// OpenCV's FileStorage parser recurses once per level of nesting, so a file
// nested deep enough overflows the stack (SIGSEGV): measure the depth on the text
// first. The measure never undercounts: every indentation step, "- " entry and
// '[' / '{' adds a level (also in comments and strings, which only overcounts),
// and a ']' / '}' ends one only outside comments and quotes.
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

// FileStorage keeps both entries of a key given twice (and reads the first):
// refuse them, in every mapping.
void check_unique_keys(const cv::FileNode& node, const std::string& path, const std::string& field) {
  if (!node.isMap() && !node.isSeq()) return;
  std::set<std::string> keys;
  int index = 0;
  for (cv::FileNodeIterator it = node.begin(); it != node.end(); ++it, ++index) {
    const cv::FileNode child = *it;
    std::string name;
    if (node.isMap()) {
      name = child.name();
      if (!keys.insert(name).second)
        throw InputError(path, field.empty() ? name : field + "." + name,
                         "appears twice (the key '" + name + "' is given more than once)");
      name = field.empty() ? name : field + "." + name;
    } else {
      name = fmt::format("{}[{}]", field, index);
    }
    check_unique_keys(child, path, name);
  }
}

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

class Reader {
 public:
  Reader(const std::string& path, int added_lines) : path_(path), added_lines_(added_lines) {}

  [[noreturn]] void fail(const std::string& field, const std::string& problem) const {
    throw InputError(path_, field, problem);
  }

  // Runs `read`, turning OpenCV's exceptions into an InputError naming `field`.
  template <typename F>
  auto guarded(const std::string& field, F&& read) const -> decltype(read()) {
    try {
      return read();
    } catch (const cv::Exception& e) {
      fail(field, describe(e, added_lines_));
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& e) {
      fail(field, describe(e));
    }
  }

  double real(const cv::FileNode& node, const std::string& field) const {
    if (!(node.isInt() || node.isReal())) fail(field, "must be a number");
    const double value = guarded(field, [&] { return static_cast<double>(node); });
    if (!std::isfinite(value)) fail(field, fmt::format("must be finite, got {}", value));
    return value;
  }

  int image_side(const cv::FileNode& node, const std::string& field) const {
    if (node.isNone()) fail(field, "missing (required: glasspiv needs the image size to build a camera model)");
    const double value =
        node.isInt() ? static_cast<double>(guarded(field, [&] { return static_cast<int>(node); })) : real(node, field);
    try {
      return checked_image_side_px(value, field);
    } catch (const InputError& e) {
      fail(field, e.problem());
    }
  }

  // An !!opencv-matrix, or a plain list of numbers (read as one row).
  cv::Mat matrix(const cv::FileNode& node, const std::string& field) const {
    cv::Mat m;
    if (node.isSeq()) {
      m = cv::Mat(1, static_cast<int>(node.size()), CV_64F);
      for (int i = 0; i < m.cols; ++i) m.at<double>(0, i) = real(node[i], fmt::format("{}[{}]", field, i));
      return m;
    }
    if (!node.isMap() || node["rows"].isNone() || node["cols"].isNone() || node["data"].isNone())
      fail(field, "must be an !!opencv-matrix (rows, cols, dt, data) or a list of numbers");
    // Read by hand rather than by OpenCV's `node >> m`, which converts every
    // value to `dt` silently (dt: u turns 600 into 255).
    auto count = [&](const char* key) {
      const cv::FileNode n = node[key];
      const std::string f = field + "." + key;
      if (!n.isInt()) fail(f, "must be a whole number");
      const int value = guarded(f, [&] { return static_cast<int>(n); });
      if (value < 0) fail(f, fmt::format("must not be negative, is {}", value));
      return value;
    };
    const int rows = count("rows"), cols = count("cols");
    const cv::FileNode dt_node = node["dt"];
    if (dt_node.isNone()) fail(field + ".dt", "missing (the element type, e.g. d for double)");
    if (!dt_node.isString()) fail(field + ".dt", "must be an OpenCV element type such as d or f");
    const std::string dt = dt_node.string();
    std::size_t digits = 0;
    while (digits < dt.size() && std::isdigit(static_cast<unsigned char>(dt[digits]))) ++digits;
    if (digits > 0 && dt.substr(0, digits) != "1" && dt.size() == digits + 1 && element_type(dt.back()))
      fail(field, fmt::format("must have one channel, dt '{}' has {}", dt, dt.substr(0, digits)));
    const std::optional<ElementType> type =
        dt.size() == digits + 1 ? element_type(dt.back()) : std::optional<ElementType>();
    if (!type)
      fail(field + ".dt",
           fmt::format("element type '{}' is not one glasspiv reads (d, f, i, s, w, c or u, one channel)", dt));
    const cv::FileNode data = node["data"];
    if (!data.isSeq()) fail(field + ".data", "must be a list of numbers");
    const std::int64_t expected = static_cast<std::int64_t>(rows) * cols;
    if (static_cast<std::int64_t>(data.size()) != expected)
      fail(field, fmt::format("rows x cols = {} x {} = {} elements, but data has {}", rows, cols, expected,
                              data.size()));
    if (expected == 0) return cv::Mat(0, 0, CV_64F);
    cv::Mat d(rows, cols, CV_64F);
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c) {
        const std::string f = fmt::format("{}.data[{}]", field, r * cols + c);
        double v = real(data[r * cols + c], f);
        if (v < type->min || v > type->max || (type->whole && v != std::floor(v)))
          fail(f, fmt::format("element ({}, {}) = {} does not fit dt '{}' ({} {} to {})", r, c, format_number(v),
                              type->code, type->whole ? "whole numbers" : "numbers", format_number(type->min),
                              format_number(type->max)));
        if (type->code == 'f') v = static_cast<float>(v);  // what a 32-bit matrix holds
        d.at<double>(r, c) = v;
      }
    return d;
  }

  // A 1xN or Nx1 matrix (or list) as a vector.
  std::vector<double> vector(const cv::FileNode& node, const std::string& field) const {
    const cv::Mat m = matrix(node, field);
    if (m.empty()) return {};
    if (m.rows != 1 && m.cols != 1)
      fail(field, fmt::format("must be a 1xN or Nx1 matrix, is {}x{}", m.rows, m.cols));
    return std::vector<double>(m.begin<double>(), m.end<double>());
  }

 private:
  const std::string& path_;
  int added_lines_;
};

// OpenCV 4.6's FileStorage parser can loop forever on malformed YAML (the
// reproducers in tests/fuzz/crashes/camera_opencv/): it only ever sees one
// document that yaml-cpp has parsed as a well-formed mapping first. OpenCV's
// "%YAML:1.0" line is its own spelling of the directive, not YAML's, so it is
// left out; a second document is refused before either parser sees it
// (yaml-cpp's LoadAll itself runs away on some damaged multi-document texts).
// The parser also loops on some texts yaml-cpp reads as a mapping whose keys
// are indented (every reproducer so far), so the top level must start in the
// first column, as FileStorage writes it.
void check_one_mapping(std::string_view contents, const std::string& path) {
  std::string yaml(contents);
  int skipped_lines = 0;
  const std::size_t first = yaml.find_first_not_of(" \t\r\n");
  if (first != std::string::npos && yaml.compare(first, 6, "%YAML:") == 0) {
    const std::size_t eol = yaml.find('\n', first);
    yaml = eol == std::string::npos ? std::string() : yaml.substr(eol + 1);
    skipped_lines = 1;
  }
  bool content = false;
  int line = skipped_lines;
  for (std::size_t pos = 0; pos < yaml.size(); ++line) {
    const std::size_t eol = std::min(yaml.find('\n', pos), yaml.size());
    const std::string_view l(yaml.data() + pos, eol - pos);
    const bool marker = l.rfind("---", 0) == 0 || l.rfind("...", 0) == 0;
    if (marker && content)
      throw InputError(path, "", fmt::format("line {}: a second YAML document; a camera file holds one", line + 1));
    const std::size_t indent = l.find_first_not_of(" \t\r");
    if (!marker && indent != std::string_view::npos && l[indent] != '#') {
      if (!content && indent > 0)
        throw InputError(path, "",
                         fmt::format("line {}: the top-level keys must start in the first column, as OpenCV "
                                     "FileStorage writes them",
                                     line + 1));
      content = true;
    }
    pos = eol + 1;
  }
  try {
    if (!YAML::Load(yaml).IsMap())
      throw InputError(path, "", "expected a mapping of OpenCV FileStorage fields (camera_matrix, ...)");
  } catch (const YAML::Exception& e) {
    throw InputError(path, "", fmt::format("malformed YAML, line {}: {}", e.mark.line + 1 + skipped_lines, e.msg));
  }
}

std::vector<Camera> parse(std::string_view contents, const std::string& path) {
  check_nesting_depth(contents, path);
  check_one_mapping(contents, path);
  std::string text(contents);
  if (text.compare(0, 3, "\xEF\xBB\xBF") == 0) text.erase(0, 3);
  // In memory, FileStorage recognises YAML by its %YAML directive only.
  const std::size_t first = text.find_first_not_of(" \t\r\n");
  int added_lines = 0;
  if (first == std::string::npos || (text.compare(first, 5, "%YAML") != 0 && text[first] != '{')) {
    text = "%YAML:1.0\n" + text;
    added_lines = 1;
  }
  cv::FileStorage fs;
  try {
    if (!fs.open(text, cv::FileStorage::READ | cv::FileStorage::MEMORY))
      throw InputError(path, "", "OpenCV FileStorage cannot open it");
  } catch (const cv::Exception& e) {
    throw InputError(path, "", describe(e, added_lines));
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(path, "", describe(e));
  }
  const Reader r(path, added_lines);
  const cv::FileNode root = r.guarded("", [&] { return fs.root(); });
  if (!root.isMap()) r.fail("", "expected a mapping of OpenCV FileStorage fields (camera_matrix, ...)");
  r.guarded("", [&] {
    check_unique_keys(root, path, "");
    return 0;
  });
  auto node = [&](const char* key) { return r.guarded(key, [&] { return root[key]; }); };

  std::string name = camera_file_detail::default_camera_name(path);
  if (const cv::FileNode n = node("camera_name"); !n.isNone()) {
    if (!n.isString()) r.fail("camera_name", "must be a text");
    name = n.string();
  }

  const int width = r.image_side(node("image_width"), "image_width");
  const int height = r.image_side(node("image_height"), "image_height");
  camera_file_detail::checked_image_size(width, height, path, "image_width");

  const cv::FileNode k_node = node("camera_matrix");
  if (k_node.isNone()) r.fail("camera_matrix", "missing (required)");
  const cv::Mat k = r.matrix(k_node, "camera_matrix");
  if (k.rows != 3 || k.cols != 3) r.fail("camera_matrix", fmt::format("must be a 3x3 matrix, is {}x{}", k.rows, k.cols));
  if (k.at<double>(0, 1) != 0)
    r.fail("camera_matrix",
           fmt::format("has skew K(0,1) = {}; glasspiv's model (like OpenCV's calibrateCamera) has none",
                       format_real(k.at<double>(0, 1))));
  if (k.at<double>(1, 0) != 0)
    r.fail("camera_matrix", fmt::format("K(1,0) = {} must be 0", format_real(k.at<double>(1, 0))));
  if (k.at<double>(2, 0) != 0 || k.at<double>(2, 1) != 0 || k.at<double>(2, 2) != 1)
    r.fail("camera_matrix", fmt::format("last row must be (0, 0, 1), is ({}, {}, {})", format_real(k.at<double>(2, 0)),
                                        format_real(k.at<double>(2, 1)), format_real(k.at<double>(2, 2))));
  if (!(k.at<double>(0, 0) > 0) || !(k.at<double>(1, 1) > 0))
    r.fail("camera_matrix", "focal lengths K(0,0) and K(1,1) must be positive");

  const cv::FileNode d_node = node("distortion_coefficients");
  if (d_node.isNone())
    r.fail("distortion_coefficients",
           "missing (required; write an empty matrix or [] for a camera without distortion)");
  const std::vector<double> distortion = r.vector(d_node, "distortion_coefficients");
  lens_model_for_count(distortion.size(), "distortion_coefficients");  // throws for other lengths

  std::optional<double> pitch_um;
  if (const cv::FileNode n = node("pixel_pitch_um"); !n.isNone()) {
    pitch_um = r.real(n, "pixel_pitch_um");
    if (const std::string problem = camera_file_detail::pixel_pitch_problem(*pitch_um); !problem.empty())
      r.fail("pixel_pitch_um", fmt::format("{}, got {}", problem, *pitch_um));
  }

  std::optional<RigidTransform> pose;
  const cv::FileNode rvec_node = node("rvec"), tvec_node = node("tvec");
  if (!rvec_node.isNone() || !tvec_node.isNone()) {
    if (rvec_node.isNone()) r.fail("rvec", "missing (tvec is given; the pose needs both)");
    if (tvec_node.isNone()) r.fail("tvec", "missing (rvec is given; the pose needs both)");
    const std::vector<double> rv = r.vector(rvec_node, "rvec");
    const std::vector<double> tv = r.vector(tvec_node, "tvec");
    if (rv.size() != 3) r.fail("rvec", fmt::format("must have 3 elements, has {}", rv.size()));
    if (tv.size() != 3) r.fail("tvec", fmt::format("must have 3 elements, has {}", tv.size()));
    pose = RigidTransform::from_rvec_tvec({rv[0], rv[1], rv[2]}, {tv[0], tv[1], tv[2]});
  }

  return {Camera{name,
                 CameraModel(width, height, k.at<double>(0, 0), k.at<double>(1, 1), k.at<double>(0, 2),
                             k.at<double>(1, 2), distortion),
                 pose, pitch_um}};
}

}  // namespace

std::vector<Camera> parse_opencv_yaml(std::string_view contents, const std::string& path) {
  try {
    return parse(contents, path);
  } catch (const InputError&) {
    camera_file_detail::rethrow_naming_file(path);
  } catch (const cv::Exception& e) {
    throw InputError(path, "", describe(e, 0));
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
    if (!camera.name.empty()) fs << "camera_name" << camera.name;
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
    // FileStorage leaves some texts unquoted ("[x]") that then read back as
    // something else: refuse those names rather than write a file that fails.
    if (!camera.name.empty()) {
      cv::FileStorage check(text, cv::FileStorage::READ | cv::FileStorage::MEMORY);
      const cv::FileNode n = check["camera_name"];
      if (!n.isString() || n.string() != camera.name)
        throw InputError(path, "camera_name",
                         "OpenCV FileStorage cannot store the camera name '" + camera.name + "'; rename the camera");
    }
    return text;
  } catch (const cv::Exception& e) {
    throw InputError(path, "", "OpenCV FileStorage cannot write it: " + e.err);
  }
}

}  // namespace glasspiv
