#include "calib/io/davis_xml.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <functional>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <pugixml.hpp>

#include "calib/io/camera_file.h"
#include "util/input_error.h"
#include "util/text_number.h"

namespace glasspiv {
namespace {

using camera_file_detail::line_of_offset;

constexpr const char* kMapperType = "PinholeOpenCV";

std::optional<long double> parse_long_double(std::string_view text) {
  const bool plus = !text.empty() && text.front() == '+';
  if (plus) text.remove_prefix(1);
  if (text.empty() || (plus && text.front() == '-')) return std::nullopt;
  long double value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size()) return std::nullopt;
  return value;
}

// DaVis gives the focal length in mm and the pixel size in mm. The reader turns
// them into pixels with extended precision, so the writer can always find a
// decimal text that reads back as exactly the double it started from.
double pixel_pitch_um_from_mm(long double pitch_mm) { return static_cast<double>(pitch_mm * 1000.0L); }
double focal_px_from_mm(long double focal_mm, long double pitch_mm) { return static_cast<double>(focal_mm / pitch_mm); }

// The text of a value that `read` turns back into `target`: the shortest double
// first, then the long double, then neighbours of the double.
std::string exact_text(double target, const std::function<double(long double)>& read, double guess,
                       long double precise_guess) {
  auto reads_back = [&](const std::string& text) {
    const std::optional<long double> v = parse_long_double(text);
    return v && read(*v) == target;
  };
  std::string text = format_real(guess);
  if (reads_back(text)) return text;
  const std::string precise = fmt::format("{}", precise_guess);
  if (reads_back(precise)) return precise;
  for (int step = 1; step <= 4; ++step) {
    double below = guess, above = guess;
    for (int i = 0; i < step; ++i) {
      below = std::nextafter(below, -INFINITY);
      above = std::nextafter(above, INFINITY);
    }
    if (reads_back(format_real(below))) return format_real(below);
    if (reads_back(format_real(above))) return format_real(above);
  }
  return text;  // within an ulp; not reached where long double is wider than double
}

class MapperReader {
 public:
  MapperReader(std::string_view contents, const std::string& path, std::string label)
      : contents_(contents), path_(path), label_(std::move(label)) {}

  [[noreturn]] void fail(const pugi::xml_node& at, const std::string& field, const std::string& problem) const {
    const std::ptrdiff_t offset = at ? at.offset_debug() : -1;
    const std::string where =
        offset >= 0 ? fmt::format("line {}: ", line_of_offset(contents_, static_cast<std::size_t>(offset))) : "";
    throw InputError(path_, label_ + (field.empty() ? "" : "/" + field), where + problem);
  }

  // The one element called `name` anywhere below `parent` (given twice, the
  // file would be ambiguous: refused).
  pugi::xml_node find(const pugi::xml_node& parent, const char* name, bool required = true) const {
    const pugi::xpath_node_set nodes = parent.select_nodes((std::string(".//") + name).c_str());
    if (nodes.empty()) {
      if (required) fail(parent, name, "missing (no <" + std::string(name) + "> element in the mapper)");
      return {};
    }
    if (nodes.size() > 1)
      fail(nodes[1].node(), name,
           fmt::format("<{}> appears twice in <{}> (it must be given once)", name, parent.name()));
    return nodes[0].node();
  }

  std::string text(const pugi::xml_node& node, const char* attribute) const {
    const pugi::xml_attribute a = node.attribute(attribute);
    if (!a) fail(node, field(node, attribute), "missing attribute");
    return a.value();
  }

  long double precise(const pugi::xml_node& node, const char* attribute) const {
    const std::string t = text(node, attribute);
    const std::optional<long double> v = parse_long_double(t);
    check(node, attribute, t, v.has_value(), v && std::isfinite(*v));
    return *v;
  }

  double real(const pugi::xml_node& node, const char* attribute) const {
    const std::string t = text(node, attribute);
    const std::optional<double> v = parse_number(t);
    check(node, attribute, t, v.has_value(), v && std::isfinite(*v));
    return *v;
  }

  int image_side(const pugi::xml_node& node, const char* attribute) const {
    const double v = real(node, attribute);
    try {
      return checked_image_side_px(v, field(node, attribute));
    } catch (const InputError& e) {
      fail(node, field(node, attribute), e.problem());
    }
  }

  // The line of `node`, for the shared checks' messages.
  std::string where(const pugi::xml_node& node) const {
    return fmt::format("line {}: ", line_of_offset(contents_, static_cast<std::size_t>(node.offset_debug())));
  }
  const std::string& label() const { return label_; }

  static std::string field(const pugi::xml_node& node, const char* attribute) {
    return std::string(node.name()) + "." + attribute;
  }

 private:
  void check(const pugi::xml_node& node, const char* attribute, const std::string& t, bool parsed, bool finite) const {
    if (!parsed)
      fail(node, field(node, attribute),
           "'" + t + "' is not a number" +
               (t.find(',') != std::string::npos ? " (a decimal comma? DaVis files use a decimal point)" : ""));
    if (!finite) fail(node, field(node, attribute), "must be finite, is " + t);
  }

  std::string_view contents_;
  const std::string& path_;
  std::string label_;
};

// The distortion attributes glasspiv takes; any other must be zero.
void read_distortion(const MapperReader& r, const pugi::xml_node& node, const char* first, const char* second,
                     double* a, double* b) {
  *a = r.real(node, first);
  *b = r.real(node, second);
  for (const pugi::xml_attribute& attribute : node.attributes()) {
    const std::string name = attribute.name();
    if (name == first || name == second) continue;
    const std::optional<double> v = parse_number(attribute.value());
    if (!v || *v != 0)
      r.fail(node, MapperReader::field(node, attribute.name()),
             std::string("= ") + attribute.value() +
                 ", but DaVis's PinholeOpenCV model as glasspiv reads it holds k1, k2, p1, p2 only");
  }
}

Camera read_mapper(std::string_view contents, const std::string& path, const pugi::xml_node& mapper,
                   const std::string& id) {
  const MapperReader r(contents, path, "CoordinateMapper[CameraIdentifier=" + id + "]");
  const pugi::xml_attribute type = mapper.attribute("Type");
  if (!type) r.fail(mapper, "Type", "missing (expected Type=\"PinholeOpenCV\")");
  if (std::string(type.value()) != kMapperType)
    r.fail(mapper, "Type",
           fmt::format("mapper Type '{}' is not supported: glasspiv reads DaVis's PinholeOpenCV mapper only "
                       "(recalibrate with the pinhole model in DaVis)",
                       type.value()));
  const pugi::xml_attribute name_attribute = mapper.attribute("Name");
  const std::string name = name_attribute ? name_attribute.value() : "camera" + id;

  const pugi::xml_node size = r.find(mapper, "OriginalImageSize");
  const int width = r.image_side(size, "Width");
  const int height = r.image_side(size, "Height");
  camera_file_detail::checked_image_size(width, height, path, r.label() + "/OriginalImageSize", r.where(size));

  const pugi::xml_node internal = r.find(mapper, "InternalCameraParameters");
  const pugi::xml_node pixel = r.find(internal, "SensorPixelSizeMm");
  const long double pitch_mm = r.precise(pixel, "Value");
  if (!(pitch_mm > 0)) r.fail(pixel, "SensorPixelSizeMm.Value", "must be a positive pixel size in mm");
  const double pitch_um = pixel_pitch_um_from_mm(pitch_mm);
  if (const std::string problem = camera_file_detail::pixel_pitch_problem(pitch_um); !problem.empty())
    r.fail(pixel, "SensorPixelSizeMm.Value",
           fmt::format("is {} mm, a pixel pitch of {} um; it {}", r.text(pixel, "Value"), pitch_um, problem));

  const pugi::xml_node focal = r.find(internal, "FocalLengthPixel");
  const long double focal_x_mm = r.precise(focal, "x");
  const long double focal_y_mm = focal.attribute("y") ? r.precise(focal, "y") : focal_x_mm;
  if (!(focal_x_mm > 0)) r.fail(focal, "FocalLengthPixel.x", "must be a positive focal length (in mm)");
  if (!(focal_y_mm > 0)) r.fail(focal, "FocalLengthPixel.y", "must be a positive focal length (in mm)");
  const double fx = focal_px_from_mm(focal_x_mm, pitch_mm), fy = focal_px_from_mm(focal_y_mm, pitch_mm);

  const pugi::xml_node principal = r.find(internal, "PrincipalPoint");
  const double cx = r.real(principal, "x"), cy = r.real(principal, "y");

  std::vector<double> distortion(4);
  read_distortion(r, r.find(internal, "RadialDistortion"), "radialDistortionCoefficient1",
                  "radialDistortionCoefficient2", &distortion[0], &distortion[1]);
  read_distortion(r, r.find(internal, "TangentialDistortion"), "tangentialDistortionCoefficient1",
                  "tangentialDistortionCoefficient2", &distortion[2], &distortion[3]);

  std::optional<RigidTransform> pose;
  if (const pugi::xml_node external = r.find(mapper, "ExternalCameraParameters", false)) {
    const pugi::xml_node t = r.find(external, "TranslationMm");
    const pugi::xml_node a = r.find(external, "RotationAngles");
    RigidTransform camera_from_world;
    camera_from_world.rotation = rotation_from_euler_zyx(r.real(a, "Rx"), r.real(a, "Ry"), r.real(a, "Rz"));
    camera_from_world.translation_mm = {r.real(t, "Tx"), r.real(t, "Ty"), r.real(t, "Tz")};
    pose = camera_from_world;
  }

  try {
    return Camera{name, CameraModel(width, height, fx, fy, cx, cy, distortion), pose, pitch_um};
  } catch (const InputError& e) {
    if (!e.file().empty()) throw;
    throw InputError(path, "CoordinateMapper[CameraIdentifier=" + id + "]/" + e.field(), e.problem());
  }
}

void set(pugi::xml_node node, const char* attribute, const std::string& value) {
  node.append_attribute(attribute).set_value(value.c_str());
}

// pugixml keeps every copy of an attribute given twice (and reads the first):
// refuse them, on every element. Iterative, so deep files cannot overflow the stack.
void check_unique_attributes(const pugi::xml_document& doc, std::string_view contents, const std::string& path) {
  struct Walker : pugi::xml_tree_walker {
    std::string_view contents;
    const std::string* path = nullptr;
    bool for_each(pugi::xml_node& node) override {
      if (node.type() != pugi::node_element) return true;
      std::set<std::string> names;
      for (const pugi::xml_attribute& a : node.attributes())
        if (!names.insert(a.name()).second)
          throw InputError(*path, std::string(node.name()) + "." + a.name(),
                           fmt::format("line {}: attribute '{}' appears twice in <{}>",
                                       line_of_offset(contents, static_cast<std::size_t>(node.offset_debug())),
                                       a.name(), node.name()));
      return true;
    }
  } walker;
  walker.contents = contents;
  walker.path = &path;
  const_cast<pugi::xml_document&>(doc).traverse(walker);
}

// Calls `each(mapper, identifier)` for every CoordinateMapper of a DaVis file.
void for_each_mapper(std::string_view contents, const std::string& path,
                     const std::function<void(const pugi::xml_node&, const std::string&)>& each) {
  pugi::xml_document doc;
  const pugi::xml_parse_result result = doc.load_buffer(contents.data(), contents.size());
  if (!result)
    throw InputError(path, "",
                     fmt::format("malformed XML, line {}: {}",
                                 line_of_offset(contents, static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, result.offset))),
                                 result.description()));
  check_unique_attributes(doc, contents, path);
  const pugi::xml_node root = doc.document_element();
  if (std::string(root.name()) != "Calibration")
    throw InputError(path, "",
                     fmt::format("not a DaVis Calibration.xml: the root element is <{}>, expected <Calibration>",
                                 root.name()));
  const pugi::xpath_node_set mappers = root.select_nodes(".//CoordinateMapper");
  if (mappers.empty()) throw InputError(path, "CoordinateMapper", "missing (the file has no camera)");
  std::set<std::string> ids;
  for (std::size_t i = 0; i < mappers.size(); ++i) {
    const pugi::xml_node mapper = mappers[i].node();
    const pugi::xml_attribute id_attribute = mapper.attribute("CameraIdentifier");
    const std::string id = id_attribute ? id_attribute.value() : std::to_string(i + 1);
    if (!ids.insert(id).second)
      throw InputError(path, "CoordinateMapper.CameraIdentifier",
                       fmt::format("line {}: camera identifier {} appears twice",
                                   line_of_offset(contents, static_cast<std::size_t>(mapper.offset_debug())), id));
    each(mapper, id);
  }
}

}  // namespace

std::vector<Camera> parse_davis_xml(std::string_view contents, const std::string& path) {
  try {
    std::vector<Camera> cameras;
    for_each_mapper(contents, path, [&](const pugi::xml_node& mapper, const std::string& id) {
      cameras.push_back(read_mapper(contents, path, mapper, id));
    });
    return cameras;
  } catch (const InputError&) {
    camera_file_detail::rethrow_naming_file(path);
  }
}

std::vector<std::string> davis_camera_identifiers(std::string_view contents, const std::string& path) {
  std::vector<std::string> ids;
  for_each_mapper(contents, path, [&](const pugi::xml_node&, const std::string& id) { ids.push_back(id); });
  return ids;
}

std::string format_davis_xml(const std::vector<Camera>& cameras, const std::string& path) {
  static const char* const kNames[] = {"k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6",
                                       "s1", "s2", "s3", "s4", "tau_x", "tau_y"};
  if (cameras.empty()) throw InputError(path, "", "no camera to write");
  pugi::xml_document doc;
  pugi::xml_node declaration = doc.append_child(pugi::node_declaration);
  declaration.append_attribute("version") = "1.0";
  declaration.append_attribute("encoding") = "UTF-8";
  pugi::xml_node calibration = doc.append_child("Calibration");
  for (std::size_t i = 0; i < cameras.size(); ++i) {
    const Camera& camera = cameras[i];
    camera_file_detail::check_writable(camera, path);
    const CameraModel& m = camera.model;
    if (!camera.pixel_pitch_um)
      throw InputError(path, "pixel_pitch_um",
                       fmt::format("camera '{}' has no pixel pitch; DaVis gives focal lengths in mm and needs the "
                                   "sensor's pixel size: give pixel_pitch_um (e.g. 6.5 for a 6.5 um sCMOS sensor)",
                                   camera.name));
    std::vector<double> distortion = m.distortion();
    distortion.resize(std::max<std::size_t>(distortion.size(), 4), 0.0);
    for (std::size_t k = 4; k < distortion.size(); ++k)
      if (distortion[k] != 0)
        throw InputError(path, "distortion_coefficients",
                         fmt::format("DaVis's PinholeOpenCV holds k1, k2, p1, p2 only; camera '{}' ({}) has {} = {}",
                                     camera.name, lens_model_name(m.lens_model()), kNames[k], format_real(distortion[k])));

    const std::string id = std::to_string(i + 1);
    pugi::xml_node mapper = calibration.append_child("CoordinateMapper");
    set(mapper, "CameraIdentifier", id);
    set(mapper, "Type", kMapperType);
    if (camera.name != "camera" + id) set(mapper, "Name", camera.name);

    pugi::xml_node common = mapper.append_child("CommonParameters");
    for (const char* element : {"OriginalImageSize", "CorrectedImageSize"}) {
      pugi::xml_node size = common.append_child(element);
      set(size, "Width", std::to_string(m.width_px()));
      set(size, "Height", std::to_string(m.height_px()));
    }

    pugi::xml_node parameters = mapper.append_child("PinholeOpenCVParameters");
    pugi::xml_node internal = parameters.append_child("InternalCameraParameters");
    const double pitch_um = *camera.pixel_pitch_um;
    const std::string pitch_text = exact_text(
        pitch_um, [](long double v) { return pixel_pitch_um_from_mm(v); }, pitch_um / 1000.0,
        static_cast<long double>(pitch_um) / 1000.0L);
    const long double pitch_mm = *parse_long_double(pitch_text);
    set(internal.append_child("SensorPixelSizeMm"), "Value", pitch_text);
    pugi::xml_node focal = internal.append_child("FocalLengthPixel");
    for (const auto& [attribute, f_px] : {std::pair<const char*, double>{"x", m.fx_px()}, {"y", m.fy_px()}}) {
      const long double f_mm = static_cast<long double>(f_px) * pitch_mm;
      set(focal, attribute,
          exact_text(
              f_px, [&](long double v) { return focal_px_from_mm(v, pitch_mm); }, static_cast<double>(f_mm), f_mm));
    }
    pugi::xml_node principal = internal.append_child("PrincipalPoint");
    set(principal, "x", format_real(m.cx_px()));
    set(principal, "y", format_real(m.cy_px()));
    pugi::xml_node radial = internal.append_child("RadialDistortion");
    set(radial, "radialDistortionCoefficient1", format_real(distortion[0]));
    set(radial, "radialDistortionCoefficient2", format_real(distortion[1]));
    pugi::xml_node tangential = internal.append_child("TangentialDistortion");
    set(tangential, "tangentialDistortionCoefficient1", format_real(distortion[2]));
    set(tangential, "tangentialDistortionCoefficient2", format_real(distortion[3]));

    if (camera.camera_from_world) {
      pugi::xml_node external = parameters.append_child("ExternalCameraParameters");
      const Eigen::Vector3d& t = camera.camera_from_world->translation_mm;
      const Eigen::Vector3d angles = euler_zyx_from_rotation(camera.camera_from_world->rotation);
      pugi::xml_node translation = external.append_child("TranslationMm");
      set(translation, "Tx", format_real(t.x()));
      set(translation, "Ty", format_real(t.y()));
      set(translation, "Tz", format_real(t.z()));
      pugi::xml_node rotation = external.append_child("RotationAngles");
      set(rotation, "Rx", format_real(angles.x()));
      set(rotation, "Ry", format_real(angles.y()));
      set(rotation, "Rz", format_real(angles.z()));
    }
  }
  std::ostringstream out;
  doc.save(out, "  ", pugi::format_default, pugi::encoding_utf8);
  return out.str();
}

}  // namespace glasspiv
