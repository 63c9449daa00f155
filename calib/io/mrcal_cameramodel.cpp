#include "calib/io/mrcal_cameramodel.h"

#include <cctype>
#include <cmath>
#include <cstring>
#include <limits>
#include <set>

#include <fmt/format.h>

#include "calib/io/camera_file.h"
#include "util/input_error.h"
#include "util/text_number.h"

namespace glasspiv {
namespace {

using camera_file_detail::line_of_offset;

// A value of the Python-literal subset mrcal writes.
struct PyValue {
  enum class Kind { Dict, List, String, Number, Constant };
  Kind kind = Kind::Constant;
  std::size_t offset = 0;  // where it starts, for error messages
  double number = 0;
  std::string text;  // a string's contents; a number's or constant's spelling
  std::vector<PyValue> items;
  std::vector<std::pair<std::string, PyValue>> entries;
};

const char* kind_name(PyValue::Kind kind) {
  switch (kind) {
    case PyValue::Kind::Dict: return "a dict";
    case PyValue::Kind::List: return "a list";
    case PyValue::Kind::String: return "a string";
    case PyValue::Kind::Number: return "a number";
    case PyValue::Kind::Constant: return "a constant";
  }
  return "a value";
}

class Parser {
 public:
  Parser(std::string_view text, const std::string& path) : s_(text), path_(path) {}

  PyValue parse_document() {
    skip();
    if (pos_ >= s_.size()) fail(pos_, "the file is empty; expected an mrcal .cameramodel dict { ... }");
    PyValue top = value();
    skip();
    if (pos_ < s_.size()) fail(pos_, "unexpected text after the end of the dict");
    return top;
  }

 private:
  static constexpr int kMaxDepth = 64;

  [[noreturn]] void fail(std::size_t offset, const std::string& problem) const {
    throw InputError(path_, "", fmt::format("line {}: {}", line_of_offset(s_, offset), problem));
  }

  bool at_end() const { return pos_ >= s_.size(); }
  char peek(std::size_t ahead = 0) const { return pos_ + ahead < s_.size() ? s_[pos_ + ahead] : '\0'; }

  // Blanks, newlines and '#' comments.
  void skip() {
    while (!at_end()) {
      const char c = s_[pos_];
      if (c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v') {
        ++pos_;
      } else if (c == '\\' && peek(1) == '\n') {
        pos_ += 2;
      } else if (c == '#') {
        while (!at_end() && s_[pos_] != '\n') ++pos_;
      } else {
        break;
      }
    }
  }

  PyValue value() {
    if (++depth_ > kMaxDepth) fail(pos_, "values nested too deeply");
    skip();
    if (at_end()) fail(pos_, "the file ends where a value was expected");
    PyValue v;
    const char c = peek();
    if (c == '{') {
      v = dict();
    } else if (c == '[' || c == '(') {
      v = list();
    } else if (c == '\'' || c == '"' || string_prefix_length() > 0) {
      v = string();
    } else if (std::isdigit(static_cast<unsigned char>(c)) || c == '-' || c == '+' || c == '.') {
      v = number();
    } else if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') {
      v = constant();
    } else {
      fail(pos_, fmt::format("unexpected character '{}'", c));
    }
    --depth_;
    return v;
  }

  PyValue dict() {
    PyValue v;
    v.kind = PyValue::Kind::Dict;
    v.offset = pos_++;
    std::set<std::string> keys;
    for (;;) {
      skip();
      if (peek() == '}') break;
      const PyValue key = value();
      if (key.kind != PyValue::Kind::String && key.kind != PyValue::Kind::Number)
        fail(key.offset, std::string("a dict key must be a string, not ") + kind_name(key.kind));
      // Python keeps the last of a key given twice; mrcal never writes one.
      if (!keys.insert(key.text).second)
        throw InputError(path_, key.text,
                         fmt::format("line {}: the key '{}' appears twice in the dict", line_of_offset(s_, key.offset),
                                     key.text));
      skip();
      if (peek() != ':') fail(pos_, "expected ':' after the key '" + key.text + "'");
      ++pos_;
      v.entries.emplace_back(key.text, value());
      skip();
      if (peek() == ',') {
        ++pos_;
      } else if (peek() != '}') {
        fail(pos_, at_end() ? "the dict is never closed with '}'" : "expected ',' or '}' in the dict");
      }
    }
    ++pos_;
    return v;
  }

  PyValue list() {
    PyValue v;
    v.kind = PyValue::Kind::List;
    v.offset = pos_;
    const char close = s_[pos_++] == '[' ? ']' : ')';
    for (;;) {
      skip();
      if (peek() == close) break;
      v.items.push_back(value());
      skip();
      if (peek() == ',') {
        ++pos_;
      } else if (peek() != close) {
        fail(pos_, at_end() ? fmt::format("the list is never closed with '{}'", close)
                            : fmt::format("expected ',' or '{}' in the list", close));
      }
    }
    ++pos_;
    return v;
  }

  // Length of a string prefix (b, r, u, br, rb in any case) directly followed by a quote; 0 if none.
  std::size_t string_prefix_length() const {
    std::size_t n = 0;
    while (n < 2 && std::strchr("bBrRuU", peek(n)) != nullptr && peek(n) != '\0') ++n;
    return n > 0 && (peek(n) == '\'' || peek(n) == '"') ? n : 0;
  }

  PyValue string() {
    PyValue v;
    v.kind = PyValue::Kind::String;
    v.offset = pos_;
    // Adjacent literals concatenate, as in Python.
    do {
      const std::size_t start = pos_;
      const std::size_t prefix = string_prefix_length();
      bool raw = false;
      for (std::size_t i = 0; i < prefix; ++i) raw = raw || s_[pos_ + i] == 'r' || s_[pos_ + i] == 'R';
      pos_ += prefix;
      const char quote = s_[pos_];
      const bool triple = peek(1) == quote && peek(2) == quote;
      pos_ += triple ? 3 : 1;
      for (;;) {
        if (at_end()) fail(start, "the string is never closed");
        const char c = s_[pos_];
        if (c == quote && (!triple || (peek(1) == quote && peek(2) == quote))) {
          pos_ += triple ? 3 : 1;
          break;
        }
        if (c == '\n' && !triple) fail(start, "the string runs past the end of its line");
        if (c == '\\' && pos_ + 1 < s_.size()) {
          const char e = s_[pos_ + 1];
          pos_ += 2;
          if (raw) {
            v.text += c;
            v.text += e;
          } else if (e == 'n') {
            v.text += '\n';
          } else if (e == 't') {
            v.text += '\t';
          } else if (e == 'r') {
            v.text += '\r';
          } else if (e == '\\' || e == '\'' || e == '"') {
            v.text += e;
          } else if (e != '\n') {
            v.text += c;
            v.text += e;
          }
          continue;
        }
        v.text += c;
        ++pos_;
      }
      skip();
    } while (!at_end() && (peek() == '\'' || peek() == '"' || string_prefix_length() > 0));
    return v;
  }

  PyValue number() {
    PyValue v;
    v.kind = PyValue::Kind::Number;
    v.offset = pos_;
    std::size_t end = pos_;
    if (s_[end] == '-' || s_[end] == '+') ++end;
    while (end < s_.size()) {
      const char c = s_[end];
      if (std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' ||
          ((c == '-' || c == '+') && (s_[end - 1] == 'e' || s_[end - 1] == 'E'))) {
        ++end;
      } else {
        break;
      }
    }
    v.text = std::string(s_.substr(pos_, end - pos_));
    std::string digits;
    for (char c : v.text)
      if (c != '_') digits += c;
    std::string_view word = digits;
    const bool negative = !word.empty() && word.front() == '-';
    if (negative || (!word.empty() && word.front() == '+')) word.remove_prefix(1);
    const std::optional<double> parsed = parse_number(word);
    // from_chars also takes "nan" and "inf", which Python spells as names, not numbers;
    // they arrive here only with a sign ("-inf") and are kept to be rejected as non-finite.
    if (!parsed || (!word.empty() && (word.front() == '+' || word.front() == '-')))
      fail(pos_, "'" + v.text + "' is not a number");
    v.number = negative ? -*parsed : *parsed;
    pos_ = end;
    return v;
  }

  PyValue constant() {
    PyValue v;
    v.offset = pos_;
    std::size_t end = pos_;
    while (end < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[end])) || s_[end] == '_')) ++end;
    v.text = std::string(s_.substr(pos_, end - pos_));
    if (v.text == "True" || v.text == "False" || v.text == "None") {
      v.kind = PyValue::Kind::Constant;
    } else if (v.text == "nan" || v.text == "inf") {  // numpy's spelling; rejected later as non-finite
      v.kind = PyValue::Kind::Number;
      v.number = v.text == "nan" ? std::numeric_limits<double>::quiet_NaN() : std::numeric_limits<double>::infinity();
    } else {
      fail(pos_, "unexpected name '" + v.text + "' (a Python literal was expected)");
    }
    pos_ = end;
    return v;
  }

  std::string_view s_;
  const std::string& path_;
  std::size_t pos_ = 0;
  int depth_ = 0;
};

struct MrcalLensModel {
  const char* name;
  LensModel model;
};
constexpr MrcalLensModel kLensModels[] = {{"LENSMODEL_PINHOLE", LensModel::Pinhole},
                                          {"LENSMODEL_OPENCV4", LensModel::OpenCV4},
                                          {"LENSMODEL_OPENCV5", LensModel::OpenCV5},
                                          {"LENSMODEL_OPENCV8", LensModel::OpenCV8},
                                          {"LENSMODEL_OPENCV12", LensModel::OpenCV12}};

class Interpreter {
 public:
  Interpreter(std::string_view text, const std::string& path) : text_(text), path_(path) {}

  [[noreturn]] void fail(const std::string& field, const PyValue& at, const std::string& problem) const {
    throw InputError(path_, field, fmt::format("line {}: {}", line_of_offset(text_, at.offset), problem));
  }

  double number(const PyValue& v, const std::string& field) const {
    if (v.kind != PyValue::Kind::Number) fail(field, v, std::string("must be a number, is ") + kind_name(v.kind));
    if (!std::isfinite(v.number)) fail(field, v, "must be finite, is " + v.text);
    return v.number;
  }

  std::vector<double> numbers(const PyValue& v, const std::string& field, std::size_t size,
                              const std::string& what) const {
    if (v.kind != PyValue::Kind::List) fail(field, v, "must be a list of " + what);
    if (v.items.size() != size) fail(field, v, fmt::format("has {} values; it must hold {}", v.items.size(), what));
    std::vector<double> out;
    for (std::size_t i = 0; i < v.items.size(); ++i) out.push_back(number(v.items[i], fmt::format("{}[{}]", field, i)));
    return out;
  }

  Camera camera(const PyValue& top) const {
    if (top.kind != PyValue::Kind::Dict)
      fail("", top, std::string("an mrcal .cameramodel is a dict { ... }, this is ") + kind_name(top.kind));
    const PyValue *lensmodel = nullptr, *intrinsics = nullptr, *imagersize = nullptr, *extrinsics = nullptr;
    for (const auto& [key, value] : top.entries) {
      const PyValue** slot = key == "lensmodel"    ? &lensmodel
                             : key == "intrinsics" ? &intrinsics
                             : key == "imagersize" ? &imagersize
                             : key == "extrinsics" ? &extrinsics
                                                   : nullptr;
      if (!slot) continue;  // valid_intrinsics_region, optimization_inputs, icam_intrinsics, ...
      if (*slot) fail(key, value, "appears twice");
      *slot = &value;
    }
    if (!lensmodel) throw InputError(path_, "lensmodel", "missing (required)");
    if (!intrinsics) throw InputError(path_, "intrinsics", "missing (required)");
    if (!imagersize) throw InputError(path_, "imagersize", "missing (required)");

    if (lensmodel->kind != PyValue::Kind::String) fail("lensmodel", *lensmodel, "must be a string such as 'LENSMODEL_OPENCV8'");
    const MrcalLensModel* model = nullptr;
    for (const MrcalLensModel& m : kLensModels)
      if (lensmodel->text == m.name) model = &m;
    if (!model)
      fail("lensmodel", *lensmodel,
           "lens model " + lensmodel->text +
               " cannot be represented by glasspiv's pinhole+OpenCV model (it takes LENSMODEL_PINHOLE and "
               "LENSMODEL_OPENCV4, 5, 8 or 12)");

    const int count = static_cast<int>(model->model);
    const std::vector<double> k = numbers(
        *intrinsics, "intrinsics", 4 + count,
        fmt::format("{} numbers for {} (fx, fy, cx, cy and {} distortion coefficients)", 4 + count, model->name, count));

    if (imagersize->kind != PyValue::Kind::List || imagersize->items.size() != 2)
      fail("imagersize", *imagersize, "must be [width, height] in pixels");
    int size[2];
    for (int i = 0; i < 2; ++i) {
      const std::string field = fmt::format("imagersize[{}]", i);
      const double v = number(imagersize->items[i], field);
      try {
        size[i] = checked_image_side_px(v, field);
      } catch (const InputError& e) {
        fail(field, imagersize->items[i], e.problem());
      }
    }
    camera_file_detail::checked_image_size(size[0], size[1], path_, "imagersize",
                                           fmt::format("line {}: ", line_of_offset(text_, imagersize->offset)));

    std::optional<RigidTransform> pose;
    if (extrinsics) {
      const std::vector<double> rt = numbers(*extrinsics, "extrinsics", 6, "6 numbers: rt_cam_ref = rvec, tvec");
      bool identity = true;
      for (double v : rt) identity = identity && v == 0;
      // All zeros is mrcal's "this camera is the reference": no pose in the world.
      if (!identity) pose = RigidTransform::from_rvec_tvec({rt[0], rt[1], rt[2]}, {rt[3], rt[4], rt[5]});
    }
    return Camera{camera_file_detail::default_camera_name(path_),
                  CameraModel(size[0], size[1], k[0], k[1], k[2], k[3], std::vector<double>(k.begin() + 4, k.end())),
                  pose, std::nullopt};
  }

 private:
  std::string_view text_;
  const std::string& path_;
};

std::string list(const std::vector<double>& values) {
  std::string out = "[ ";
  for (double v : values) out += format_real(v) + ", ";
  return out + "]";
}

// A camera name fit for a one-line comment.
std::string printable(const std::string& text) {
  std::string out;
  for (char c : text) out += static_cast<unsigned char>(c) < 0x20 || c == 0x7f ? '?' : c;
  return out;
}

}  // namespace

std::vector<Camera> parse_mrcal_cameramodel(std::string_view contents, const std::string& path) {
  try {
    Parser parser(contents, path);
    const PyValue top = parser.parse_document();
    return {Interpreter(contents, path).camera(top)};
  } catch (const InputError&) {
    camera_file_detail::rethrow_naming_file(path);
  }
}

std::string format_mrcal_cameramodel(const std::vector<Camera>& cameras, const std::string& path) {
  if (cameras.size() != 1)
    throw InputError(path, "",
                     fmt::format("an mrcal .cameramodel holds one camera, {} were given (write one file each)",
                                 cameras.size()));
  const Camera& camera = cameras.front();
  camera_file_detail::check_writable(camera, path);
  const CameraModel& m = camera.model;
  const char* lensmodel = nullptr;
  for (const MrcalLensModel& candidate : kLensModels)
    if (candidate.model == m.lens_model()) lensmodel = candidate.name;
  if (!lensmodel)
    throw InputError(path, "lens_model",
                     fmt::format("camera '{}' uses {}, but mrcal has no 14-coefficient (tilted-sensor) OpenCV model; "
                                 "it takes pinhole, opencv4, opencv5, opencv8 and opencv12",
                                 camera.name, lens_model_name(m.lens_model())));
  std::vector<double> intrinsics = {m.fx_px(), m.fy_px(), m.cx_px(), m.cy_px()};
  for (double d : m.distortion()) intrinsics.push_back(d);
  std::vector<double> extrinsics(6, 0.0);
  if (camera.camera_from_world) {
    const Eigen::Vector3d r = camera.camera_from_world->rvec();
    const Eigen::Vector3d& t = camera.camera_from_world->translation_mm;
    extrinsics = {r.x(), r.y(), r.z(), t.x(), t.y(), t.z()};
  }

  std::string out;
  out += fmt::format("# glasspiv camera '{}' (docs/formats.md)", printable(camera.name));
  if (camera.pixel_pitch_um)
    out += fmt::format("; pixel pitch {} um (not part of mrcal's format)", format_real(*camera.pixel_pitch_um));
  out += "\n{\n";
  out += fmt::format("    'lensmodel':  '{}',\n\n", lensmodel);
  out += "    # intrinsics are fx,fy,cx,cy,distortion0,distortion1,....\n";
  out += fmt::format("    'intrinsics': {},\n\n", list(intrinsics));
  out += "    # extrinsics are rt_fromref (glasspiv's camera_from_world: rvec, tvec in mm)\n";
  out += fmt::format("    'extrinsics': {},\n\n", list(extrinsics));
  out += fmt::format("    'imagersize': [ {}, {}, ],\n", m.width_px(), m.height_px());
  out += "}\n";
  return out;
}

}  // namespace glasspiv
