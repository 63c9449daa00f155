#include "calib/io/camera_file.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>

#include <fmt/format.h>

#include "calib/io/davis_xml.h"
#include "calib/io/glasspiv_yaml.h"
#include "calib/io/mrcal_cameramodel.h"
#include "calib/io/opencv_yaml.h"
#include "util/atomic_file.h"
#include "util/input_error.h"

namespace glasspiv {

namespace camera_file_detail {


void rethrow_naming_file(const std::string& path) {
  try {
    throw;
  } catch (const InputError& e) {
    if (e.file().empty()) throw InputError(path, e.field(), e.problem());
    throw;
  }
}

std::string default_camera_name(const std::string& path) {
  if (path.empty()) return "camera";
  const std::string stem = std::filesystem::path(path).stem().string();
  return stem.empty() ? "camera" : stem;
}

int line_of_offset(std::string_view text, std::size_t offset) {
  offset = std::min(offset, text.size());
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(offset), '\n'));
}

std::string pixel_pitch_problem(double pitch_um) {
  if (!std::isfinite(pitch_um)) return "must be finite";
  if (!(pitch_um > 0)) return "must be positive (micrometres)";
  if (pitch_um > kMaxPixelPitchUm) return fmt::format("must be at most {} um (1 mm)", kMaxPixelPitchUm);
  return "";
}

std::pair<int, int> checked_image_size(double width_px, double height_px, const std::string& path,
                                       const std::string& field, const std::string& where) {
  try {
    check_image_size(width_px, height_px, field);
  } catch (const InputError& e) {
    throw InputError(path, e.field(), where + e.problem());
  }
  return {static_cast<int>(width_px), static_cast<int>(height_px)};
}

void check_writable(const Camera& camera, const std::string& path) {
  if (camera.pixel_pitch_um && !pixel_pitch_problem(*camera.pixel_pitch_um).empty())
    throw InputError(path, "pixel_pitch_um",
                     fmt::format("camera '{}' has pixel pitch {}; it {}", camera.name, *camera.pixel_pitch_um,
                                 pixel_pitch_problem(*camera.pixel_pitch_um)));
  if (camera.camera_from_world &&
      !(camera.camera_from_world->rotation.allFinite() && camera.camera_from_world->translation_mm.allFinite()))
    throw InputError(path, "camera_from_world", fmt::format("camera '{}' has a pose that is not finite", camera.name));
}

}  // namespace camera_file_detail

std::string format_name(CameraFileFormat format) {
  switch (format) {
    case CameraFileFormat::Glasspiv: return "glasspiv";
    case CameraFileFormat::OpenCV: return "opencv";
    case CameraFileFormat::Mrcal: return "mrcal";
    case CameraFileFormat::Davis: return "davis";
  }
  return "unknown";
}

CameraFileFormat format_from_name(const std::string& name) {
  for (CameraFileFormat f :
       {CameraFileFormat::Glasspiv, CameraFileFormat::OpenCV, CameraFileFormat::Mrcal, CameraFileFormat::Davis})
    if (format_name(f) == name) return f;
  throw InputError("", "format", "unknown camera file format '" + name + "' (expected glasspiv, opencv, mrcal or davis)");
}

CameraFileFormat format_for_output_path(const std::string& path) {
  std::string extension = std::filesystem::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (extension == ".cameramodel") return CameraFileFormat::Mrcal;
  if (extension == ".xml") return CameraFileFormat::Davis;
  if (extension == ".yaml" || extension == ".yml") return CameraFileFormat::Glasspiv;
  throw InputError(path, "",
                   "cannot tell the camera file format from the extension '" + extension +
                       "' (use .yaml for glasspiv, .cameramodel for mrcal, .xml for DaVis, or name the format)");
}

namespace {

bool starts_with(std::string_view text, std::string_view prefix) { return text.substr(0, prefix.size()) == prefix; }

// True if some line starts (column 0) with `key` followed by optional blanks and ':'.
bool has_top_level_key(std::string_view text, std::string_view key) {
  for (std::size_t at = 0; at < text.size();) {
    const std::size_t end = std::min(text.find('\n', at), text.size());
    std::string_view line = text.substr(at, end - at);
    if (starts_with(line, key)) {
      line.remove_prefix(key.size());
      const std::size_t colon = line.find_first_not_of(" \t");
      if (colon != std::string_view::npos && line[colon] == ':') return true;
    }
    at = end + 1;
  }
  return false;
}

// The text after a UTF-8 byte order mark, blanks and (when `skip_comments`) '#' comment lines.
std::string_view skip_preamble(std::string_view text, bool skip_comments) {
  if (starts_with(text, "\xEF\xBB\xBF")) text.remove_prefix(3);
  for (;;) {
    const std::size_t first = text.find_first_not_of(" \t\r\n");
    if (first == std::string_view::npos) return {};
    text.remove_prefix(first);
    if (!skip_comments || text.front() != '#') return text;
    const std::size_t eol = text.find('\n');
    if (eol == std::string_view::npos) return {};
    text.remove_prefix(eol + 1);
  }
}

}  // namespace

CameraFileFormat detect_format(std::string_view contents, const std::string& path) {
  const std::string_view start = skip_preamble(contents, false);
  if (starts_with(start, "<?xml") || starts_with(start, "<Calibration")) return CameraFileFormat::Davis;
  if (starts_with(start, "%YAML:1.0") || starts_with(start, "%YAML 1.0")) return CameraFileFormat::OpenCV;
  std::string_view body = contents;
  if (starts_with(body, "\xEF\xBB\xBF")) body.remove_prefix(3);
  if (has_top_level_key(body, "glasspiv_camera")) return CameraFileFormat::Glasspiv;
  if (has_top_level_key(body, "camera_matrix")) return CameraFileFormat::OpenCV;
  const std::string_view code = skip_preamble(contents, true);
  if (starts_with(code, "{")) {
    // OpenCV's FileStorage also writes JSON; mrcal's files have a 'lensmodel'.
    if (code.find("\"camera_matrix\"") != std::string_view::npos &&
        code.find("lensmodel") == std::string_view::npos)
      return CameraFileFormat::OpenCV;
    return CameraFileFormat::Mrcal;
  }
  throw InputError(path, "",
                   "not a camera file glasspiv knows (expected glasspiv YAML with 'glasspiv_camera: 1', OpenCV "
                   "FileStorage YAML with 'camera_matrix', an mrcal .cameramodel '{...}', or a DaVis "
                   "Calibration.xml)");
}

std::vector<Camera> parse_cameras(std::string_view contents, CameraFileFormat format, const std::string& path) {
  try {
    switch (format) {
      case CameraFileFormat::Glasspiv: return parse_glasspiv_yaml(contents, path);
      case CameraFileFormat::OpenCV: return parse_opencv_yaml(contents, path);
      case CameraFileFormat::Mrcal: return parse_mrcal_cameramodel(contents, path);
      case CameraFileFormat::Davis: return parse_davis_xml(contents, path);
    }
  } catch (const InputError&) {
    camera_file_detail::rethrow_naming_file(path);
  }
  throw InputError(path, "format", "unknown camera file format");
}

std::string format_cameras(const std::vector<Camera>& cameras, CameraFileFormat format, const std::string& path) {
  if (cameras.empty()) throw InputError(path, "", "no camera to write");
  try {
    switch (format) {
      case CameraFileFormat::Glasspiv: return format_glasspiv_yaml(cameras, path);
      case CameraFileFormat::OpenCV: return format_opencv_yaml(cameras, path);
      case CameraFileFormat::Mrcal: return format_mrcal_cameramodel(cameras, path);
      case CameraFileFormat::Davis: return format_davis_xml(cameras, path);
    }
  } catch (const InputError&) {
    camera_file_detail::rethrow_naming_file(path);
  }
  throw InputError(path, "format", "unknown camera file format");
}

std::vector<Camera> read_cameras(const std::string& path) {
  const std::string contents = read_file(path);
  return parse_cameras(contents, detect_format(contents, path), path);
}

Camera read_camera(const std::string& path, const std::string& name) {
  const std::string contents = read_file(path);
  const CameraFileFormat format = detect_format(contents, path);
  std::vector<Camera> cameras = parse_cameras(contents, format, path);
  std::vector<std::string> ids;
  if (format == CameraFileFormat::Davis) ids = davis_camera_identifiers(contents, path);
  std::string names;
  for (std::size_t i = 0; i < cameras.size(); ++i)
    names += fmt::format("{}'{}'{}", names.empty() ? "" : ", ", cameras[i].name,
                         i < ids.size() ? " (CameraIdentifier " + ids[i] + ")" : "");
  if (name.empty()) {
    if (cameras.size() == 1) return std::move(cameras.front());
    throw InputError(path, "",
                     fmt::format("holds {} cameras ({}); say which one to use", cameras.size(), names));
  }
  for (Camera& c : cameras)
    if (c.name == name) return std::move(c);
  for (std::size_t i = 0; i < ids.size() && i < cameras.size(); ++i)
    if (ids[i] == name) return std::move(cameras[i]);
  throw InputError(path, "name", fmt::format("no camera named '{}' (the file holds {})", name, names));
}

void write_cameras(const std::string& path, const std::vector<Camera>& cameras,
                   std::optional<CameraFileFormat> format) {
  const CameraFileFormat chosen = format ? *format : format_for_output_path(path);
  write_file_atomically(path, format_cameras(cameras, chosen, path));
}

}  // namespace glasspiv
