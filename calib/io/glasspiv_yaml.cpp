#include "calib/io/glasspiv_yaml.h"

#include <cctype>
#include <cmath>
#include <map>
#include <optional>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "calib/io/camera_file.h"
#include "calib/io/camera_yaml_fields.h"
#include "util/input_error.h"
#include "util/text_number.h"

namespace glasspiv {
namespace {


constexpr int kVersion = 1;
const char* const kFields[] = {"glasspiv_camera",    "name",           "image_size_px",   "lens_model",
                               "focal_length_px",    "principal_point_px", "distortion_coefficients",
                               "pixel_pitch_um",     "focal_length_mm", "camera_from_world"};
const char* const kCoefficientNames[] = {"k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6",
                                         "s1", "s2", "s3", "s4", "tau_x", "tau_y"};

std::string known_fields() {
  std::string list;
  for (const char* f : kFields) list += (list.empty() ? "" : ", ") + std::string(f);
  return list;
}

using Reader = CameraYamlFields;

std::vector<Camera> parse(std::string_view contents, const std::string& path) {
  const Reader r(path);
  const YAML::Node root = r.load_mapping(contents, "glasspiv camera fields");

  std::map<std::string, YAML::Node> fields;
  for (auto it = root.begin(); it != root.end(); ++it) {
    const std::string key = it->first.IsScalar() ? it->first.Scalar() : std::string("?");
    bool known = false;
    for (const char* f : kFields) known = known || key == f;
    if (!known) r.fail(key, it->first, "unknown field (glasspiv_camera 1 has " + known_fields() + ")");
    if (fields.count(key)) r.fail(key, it->first, "appears twice");
    fields[key] = it->second;
  }
  auto field = [&](const char* key) -> std::optional<YAML::Node> {
    const auto it = fields.find(key);
    if (it == fields.end()) return std::nullopt;
    return it->second;
  };
  auto required = [&](const char* key) {
    std::optional<YAML::Node> node = field(key);
    if (!node) throw InputError(path, key, "missing (required)");
    return *node;
  };

  const YAML::Node version = required("glasspiv_camera");
  if (r.real(version, "glasspiv_camera") != kVersion)
    r.fail("glasspiv_camera", version,
           fmt::format("format version {} is not supported (this glasspiv reads version {})", version.Scalar(),
                       kVersion));

  const std::string name = field("name") ? r.text(*field("name"), "name") : camera_file_detail::default_camera_name(path);

  const YAML::Node size_node = required("image_size_px");
  if (!size_node.IsSequence() || size_node.size() != 2)
    r.fail("image_size_px", size_node, "must be [width, height] in pixels");
  const int width = r.image_side(size_node[0], "image_size_px[0]");
  const int height = r.image_side(size_node[1], "image_size_px[1]");
  camera_file_detail::checked_image_size(width, height, path, "image_size_px",
                                         fmt::format("line {}: ", size_node.Mark().line + 1));

  const YAML::Node model_node = required("lens_model");
  const std::string model_name = r.text(model_node, "lens_model");
  LensModel model = LensModel::Pinhole;
  try {
    model = lens_model_from_name(model_name);
  } catch (const InputError& e) {
    r.fail("lens_model", model_node, e.problem());
  }

  std::vector<double> distortion;
  if (field("distortion_coefficients")) {
    distortion = r.reals(*field("distortion_coefficients"), "distortion_coefficients", std::nullopt);
  } else if (model != LensModel::Pinhole) {
    throw InputError(path, "distortion_coefficients", "missing (required for lens_model " + model_name + ")");
  }
  if (distortion.size() != static_cast<std::size_t>(model))
    r.fail("lens_model", model_node,
           fmt::format("is {}, which takes {} distortion coefficients, but distortion_coefficients has {}",
                       model_name, static_cast<int>(model), distortion.size()));

  std::optional<double> pitch_um;
  if (field("pixel_pitch_um")) {
    pitch_um = r.real(*field("pixel_pitch_um"), "pixel_pitch_um");
    if (const std::string problem = camera_file_detail::pixel_pitch_problem(*pitch_um); !problem.empty())
      r.fail("pixel_pitch_um", *field("pixel_pitch_um"), fmt::format("{}, got {}", problem, format_real(*pitch_um)));
  }

  std::optional<std::vector<double>> focal_px, focal_mm;
  if (field("focal_length_px")) focal_px = r.reals(*field("focal_length_px"), "focal_length_px", 2);
  if (field("focal_length_mm")) {
    focal_mm = r.reals(*field("focal_length_mm"), "focal_length_mm", 2);
    if (!pitch_um)
      r.fail("focal_length_mm", *field("focal_length_mm"),
             "needs pixel_pitch_um (the sensor's pixel size) to relate it to pixels");
  }
  if (!focal_px && !focal_mm) throw InputError(path, "focal_length_px", "missing (required)");
  double fx = 0, fy = 0;
  if (focal_px) {
    fx = (*focal_px)[0];
    fy = (*focal_px)[1];
    if (focal_mm) {
      for (int i = 0; i < 2; ++i) {
        const double expected_mm = (*focal_px)[i] * (*pitch_um * 1e-3);
        if (!(std::abs((*focal_mm)[i] - expected_mm) <= 1e-12 * std::abs(expected_mm)))
          r.fail("focal_length_mm", *field("focal_length_mm"),
                 fmt::format("[{}] = {} mm disagrees with focal_length_px[{}] x pixel_pitch_um = {} mm; give one of "
                             "them or make them agree",
                             i, format_real((*focal_mm)[i]), i, format_real(expected_mm)));
      }
    }
  } else {
    DavisStyleIntrinsics davis;
    davis.focal_length_x_mm = (*focal_mm)[0];
    davis.focal_length_y_mm = (*focal_mm)[1];
    davis.pixel_pitch_um = *pitch_um;
    double cx_unused, cy_unused;
    from_davis_style(davis, &fx, &fy, &cx_unused, &cy_unused);
  }

  const std::vector<double> principal = r.reals(required("principal_point_px"), "principal_point_px", 2);

  std::optional<RigidTransform> pose;
  if (field("camera_from_world")) {
    const YAML::Node node = *field("camera_from_world");
    if (!node.IsMap()) r.fail("camera_from_world", node, "must be a mapping {rvec: [..], tvec_mm: [..]}");
    std::optional<YAML::Node> rvec, tvec;
    for (auto it = node.begin(); it != node.end(); ++it) {
      const std::string key = it->first.IsScalar() ? it->first.Scalar() : std::string("?");
      if (key == "rvec" && !rvec) {
        rvec = it->second;
      } else if (key == "tvec_mm" && !tvec) {
        tvec = it->second;
      } else {
        r.fail("camera_from_world." + key, it->first,
               key == "rvec" || key == "tvec_mm" ? "appears twice" : "unknown field (expected rvec and tvec_mm)");
      }
    }
    if (!rvec) r.fail("camera_from_world.rvec", node, "missing (required in camera_from_world)");
    if (!tvec) r.fail("camera_from_world.tvec_mm", node, "missing (required in camera_from_world)");
    const std::vector<double> rv = r.reals(*rvec, "camera_from_world.rvec", 3);
    const std::vector<double> tv = r.reals(*tvec, "camera_from_world.tvec_mm", 3);
    pose = RigidTransform::from_rvec_tvec({rv[0], rv[1], rv[2]}, {tv[0], tv[1], tv[2]});
  }

  return {Camera{name, CameraModel(width, height, fx, fy, principal[0], principal[1], distortion), pose, pitch_um}};
}

bool plain_yaml_safe(const std::string& text) {
  if (text.empty() || !(std::isalpha(static_cast<unsigned char>(text[0])) || text[0] == '_')) return false;
  for (char c : text)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.')) return false;
  std::string lower;
  for (char c : text) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  for (const char* word : {"null", "true", "false", "yes", "no", "on", "off", "y", "n"})
    if (lower == word) return false;
  return true;
}

std::string yaml_string(const std::string& text) {
  if (plain_yaml_safe(text)) return text;
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
      out += fmt::format("\\x{:02X}", static_cast<unsigned>(static_cast<unsigned char>(c)));
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string list(const std::vector<double>& values) {
  std::string out = "[";
  for (std::size_t i = 0; i < values.size(); ++i) out += (i ? ", " : "") + format_real(values[i]);
  return out + "]";
}

}  // namespace

std::vector<Camera> parse_glasspiv_yaml(std::string_view contents, const std::string& path) {
  try {
    return parse(contents, path);
  } catch (const InputError&) {
    camera_file_detail::rethrow_naming_file(path);
  } catch (const YAML::Exception& e) {
    throw InputError(path, "", fmt::format("line {}: {}", e.mark.line + 1, e.msg));
  }
}

std::string format_glasspiv_yaml(const std::vector<Camera>& cameras, const std::string& path) {
  if (cameras.size() != 1)
    throw InputError(path, "",
                     fmt::format("a glasspiv camera file holds one camera, {} were given (write one file each)",
                                 cameras.size()));
  const Camera& camera = cameras.front();
  camera_file_detail::check_writable(camera, path);
  const CameraModel& m = camera.model;
  const std::vector<double> distortion = m.distortion();
  std::string names;
  for (std::size_t i = 0; i < distortion.size(); ++i) names += (i ? ", " : "") + std::string(kCoefficientNames[i]);

  std::string out;
  out += "# glasspiv camera (docs/formats.md): pixels, millimetres, radians; OpenCV's pinhole + distortion model\n";
  out += fmt::format("glasspiv_camera: {}\n", kVersion);
  out += fmt::format("name: {}\n", yaml_string(camera.name));
  out += fmt::format("image_size_px: [{}, {}]\n", m.width_px(), m.height_px());
  out += fmt::format("lens_model: {}\n", lens_model_name(m.lens_model()));
  out += fmt::format("focal_length_px: {}\n", list({m.fx_px(), m.fy_px()}));
  out += fmt::format("principal_point_px: {}\n", list({m.cx_px(), m.cy_px()}));
  out += fmt::format("distortion_coefficients: {}{}\n", list(distortion), names.empty() ? "" : "  # " + names);
  if (camera.pixel_pitch_um) {
    // For reading only (the pixel values rule): the product in extended precision,
    // so 7692.307692307692 px at 6.5 um shows as 50.0 mm.
    const long double pitch_mm = static_cast<long double>(*camera.pixel_pitch_um) / 1000.0L;
    out += fmt::format("pixel_pitch_um: {}\n", format_real(*camera.pixel_pitch_um));
    out += fmt::format("focal_length_mm: {}\n",
                       list({static_cast<double>(m.fx_px() * pitch_mm), static_cast<double>(m.fy_px() * pitch_mm)}));
  }
  if (camera.camera_from_world) {
    const Eigen::Vector3d rvec = camera.camera_from_world->rvec();
    const Eigen::Vector3d& t = camera.camera_from_world->translation_mm;
    out += "camera_from_world:  # x_camera = R(rvec) * x_world + tvec_mm\n";
    out += fmt::format("  rvec: {}\n", list({rvec.x(), rvec.y(), rvec.z()}));
    out += fmt::format("  tvec_mm: {}\n", list({t.x(), t.y(), t.z()}));
  }
  return out;
}

}  // namespace glasspiv
