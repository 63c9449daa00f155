#include "calib/io/opencv_yaml.h"

#include <charconv>
#include <cmath>

#include <fmt/format.h>
#include <opencv2/core.hpp>

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
    }
  }

  double real(const cv::FileNode& node, const std::string& field) const {
    if (!(node.isInt() || node.isReal())) fail(field, "must be a number");
    const double value = guarded(field, [&] { return static_cast<double>(node); });
    if (!std::isfinite(value)) fail(field, fmt::format("must be finite, got {}", value));
    return value;
  }

  int positive_int(const cv::FileNode& node, const std::string& field) const {
    if (node.isNone()) fail(field, "missing (required: glasspiv needs the image size to build a camera model)");
    if (node.isInt()) {
      const int value = guarded(field, [&] { return static_cast<int>(node); });
      if (value <= 0) fail(field, fmt::format("must be a positive number of pixels, got {}", value));
      return value;
    }
    const double value = real(node, field);
    if (!(value == std::floor(value) && value > 0 && value <= 1e9))
      fail(field, fmt::format("must be a positive whole number of pixels, got {}", format_real(value)));
    return static_cast<int>(value);
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
    guarded(field, [&] {
      node >> m;
      return 0;
    });
    if (m.empty()) return cv::Mat(0, 0, CV_64F);
    if (m.channels() != 1) fail(field, fmt::format("must have one channel, has {}", m.channels()));
    cv::Mat d;
    m.convertTo(d, CV_64F);
    for (int r = 0; r < d.rows; ++r)
      for (int c = 0; c < d.cols; ++c)
        if (!std::isfinite(d.at<double>(r, c)))
          fail(field, fmt::format("element ({}, {}) must be finite, got {}", r, c, d.at<double>(r, c)));
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

std::vector<Camera> parse(std::string_view contents, const std::string& path) {
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
  }
  const Reader r(path, added_lines);
  const cv::FileNode root = r.guarded("", [&] { return fs.root(); });
  if (!root.isMap()) r.fail("", "expected a mapping of OpenCV FileStorage fields (camera_matrix, ...)");
  auto node = [&](const char* key) { return r.guarded(key, [&] { return root[key]; }); };

  std::string name = camera_file_detail::default_camera_name(path);
  if (const cv::FileNode n = node("camera_name"); !n.isNone()) {
    if (!n.isString()) r.fail("camera_name", "must be a text");
    name = n.string();
  }

  const int width = r.positive_int(node("image_width"), "image_width");
  const int height = r.positive_int(node("image_height"), "image_height");

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
    if (!(*pitch_um > 0)) r.fail("pixel_pitch_um", fmt::format("must be positive (micrometres), got {}", *pitch_um));
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
