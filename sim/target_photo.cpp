#include "sim/target_photo.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

namespace glasspiv {
namespace {

// Board point (mm, z = 0 plane) seen through pixel `pixel`, or NaN if none.
Eigen::Vector2d board_point_through(const CameraModel& camera, const RigidTransform& board_from_camera,
                                    const Eigen::Vector2d& pixel) {
  const UnprojectResult ray = camera.unproject(pixel);
  const Eigen::Vector2d none = Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
  if (!ray.ok()) return none;
  const Eigen::Vector3d origin = board_from_camera.translation_mm;
  const Eigen::Vector3d direction = board_from_camera.rotation * ray.ray_camera;
  if (std::abs(direction.z()) < 1e-12) return none;
  const double t = -origin.z() / direction.z();
  if (!(t > 0)) return none;
  const Eigen::Vector3d p = origin + t * direction;
  return p.head<2>();
}

}  // namespace

cv::Mat render_target_photo(const CameraModel& camera, const RigidTransform& camera_from_board,
                            const TargetRender& board, const SensorOptions& sensor) {
  const int w = camera.width_px(), h = camera.height_px();
  const RigidTransform board_from_camera = camera_from_board.inverse();
  // Exact board points at the pixel corners (one unprojection per corner); the
  // sub-samples inside a pixel interpolate them bilinearly, which is exact to
  // second order in the footprint (under a millionth of a pixel for real lenses).
  cv::Mat corner_x(h + 1, w + 1, CV_64F), corner_y(h + 1, w + 1, CV_64F);
  for (int j = 0; j <= h; ++j)
    for (int i = 0; i <= w; ++i) {
      const Eigen::Vector2d b_mm = board_point_through(camera, board_from_camera, {i - 0.5, j - 0.5});
      const Eigen::Vector2d p = b_mm.allFinite() ? board.pixel_from_board(b_mm) : b_mm;
      corner_x.at<double>(j, i) = p.x();
      corner_y.at<double>(j, i) = p.y();
    }

  const int n = std::max(1, sensor.subsamples);
  cv::Mat map_x(h * n, w * n, CV_32F), map_y(h * n, w * n, CV_32F);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const double x00 = corner_x.at<double>(j, i), x10 = corner_x.at<double>(j, i + 1);
      const double x01 = corner_x.at<double>(j + 1, i), x11 = corner_x.at<double>(j + 1, i + 1);
      const double y00 = corner_y.at<double>(j, i), y10 = corner_y.at<double>(j, i + 1);
      const double y01 = corner_y.at<double>(j + 1, i), y11 = corner_y.at<double>(j + 1, i + 1);
      for (int b = 0; b < n; ++b)
        for (int a = 0; a < n; ++a) {
          const double s = (a + 0.5) / n, t = (b + 0.5) / n;
          const double x = (1 - t) * ((1 - s) * x00 + s * x10) + t * ((1 - s) * x01 + s * x11);
          const double y = (1 - t) * ((1 - s) * y00 + s * y10) + t * ((1 - s) * y01 + s * y11);
          const bool ok = std::isfinite(x) && std::isfinite(y);
          map_x.at<float>(j * n + b, i * n + a) = ok ? static_cast<float>(x) : -1e6f;
          map_y.at<float>(j * n + b, i * n + a) = ok ? static_cast<float>(y) : -1e6f;
        }
    }
  cv::Mat reflectance_fine, reflectance;
  cv::Mat board_float;
  board.image.convertTo(board_float, CV_32F, 1.0 / 255.0);
  // Outside the rendered board (its margin included) the scene is dark.
  cv::remap(board_float, reflectance_fine, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0));
  cv::resize(reflectance_fine, reflectance, cv::Size(w, h), 0, 0, cv::INTER_AREA);  // box average of the samples

  std::mt19937 rng(sensor.seed);
  std::normal_distribution<double> read(0.0, sensor.read_noise);
  cv::Mat photo(h, w, CV_8UC1);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const double r = reflectance.at<float>(j, i);
      double signal = (sensor.white_level - sensor.black_level) * r;
      if (sensor.photons_at_white > 0) {
        const double electrons = sensor.photons_at_white * r;
        std::poisson_distribution<int> shot(std::max(electrons, 1e-9));
        signal = (sensor.white_level - sensor.black_level) * shot(rng) / sensor.photons_at_white;
      }
      const double value = sensor.black_level + signal + (sensor.read_noise > 0 ? read(rng) : 0.0);
      photo.at<std::uint8_t>(j, i) = static_cast<std::uint8_t>(std::clamp(std::lround(value), 0L, 255L));
    }
  return photo;
}

Eigen::Vector2d PinholeTargetPhoto::project(const Eigen::Vector3d& board_mm) const {
  const Eigen::Vector3d p = photo_from_board * Eigen::Vector3d(board_mm.x(), board_mm.y(), 1.0);
  return p.head<2>() / p.z();
}

PinholeTargetPhoto render_pinhole_target_photo(const CameraModel& pinhole, const RigidTransform& camera_from_board,
                                               const TargetSpec& spec, const PinholePhotoOptions& options) {
  if (pinhole.lens_model() != LensModel::Pinhole)
    throw std::invalid_argument("render_pinhole_target_photo: the camera has a distortion model");
  PinholeTargetPhoto photo;
  // photo_from_board = K [r1 r2 t]: the plane z = 0 seen by a pinhole.
  Eigen::Matrix3d k;
  k << pinhole.fx_px(), 0, pinhole.cx_px(), 0, pinhole.fy_px(), pinhole.cy_px(), 0, 0, 1;
  Eigen::Matrix3d rt;
  rt.col(0) = camera_from_board.rotation.col(0);
  rt.col(1) = camera_from_board.rotation.col(1);
  rt.col(2) = camera_from_board.translation_mm;
  photo.photo_from_board = k * rt;

  // Render at about the supersampled photo's scale where the board is nearest.
  const Eigen::Vector2d size = board_size_mm(spec);
  const double focal_px = std::max(pinhole.fx_px(), pinhole.fy_px());
  double scale = 0;  // photo px per board mm, largest over the board's corners
  for (const double x : {0.0, size.x()})
    for (const double y : {0.0, size.y()}) {
      const Eigen::Vector3d p = rt * Eigen::Vector3d(x, y, 1);
      scale = std::max(scale, focal_px / p.z());
    }
  const int n = options.supersample;
  const double margin = default_margin_mm(spec);
  const TargetRender render = render_target(spec, scale * n * 1.25, margin);

  // hi-res pixel X = n x + (n - 1) / 2 for photo pixel x (INTER_AREA's n x n box).
  Eigen::Matrix3d hi_from_photo;
  hi_from_photo << n, 0, (n - 1) / 2.0, 0, n, (n - 1) / 2.0, 0, 0, 1;
  Eigen::Matrix3d board_from_render;  // board = (px + 0.5) / ppmm - margin
  board_from_render << 1 / render.px_per_mm, 0, 0.5 / render.px_per_mm - margin, 0, 1 / render.px_per_mm,
      0.5 / render.px_per_mm - margin, 0, 0, 1;
  const Eigen::Matrix3d hi_from_render = hi_from_photo * photo.photo_from_board * board_from_render;
  cv::Mat m(3, 3, CV_64F);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m.at<double>(i, j) = hi_from_render(i, j);
  const int w = pinhole.width_px(), h = pinhole.height_px();
  cv::Mat hi;
  cv::warpPerspective(render.image, hi, m, cv::Size(w * n, h * n), cv::INTER_LINEAR, cv::BORDER_CONSTANT,
                      cv::Scalar(options.background));
  cv::Mat low;
  cv::resize(hi, low, cv::Size(w, h), 0, 0, cv::INTER_AREA);
  cv::Mat f;
  low.convertTo(f, CV_32F);
  if (options.blur_sigma_px > 0) cv::GaussianBlur(f, f, cv::Size(0, 0), options.blur_sigma_px);
  // Paper is not perfectly white nor ink perfectly black: 255 -> 235, 0 -> 25.
  f = f * (210.0 / 255.0) + 25.0;
  std::mt19937_64 rng(options.seed);
  std::normal_distribution<float> noise(0.0f, static_cast<float>(options.noise_sigma));
  for (int y = 0; y < f.rows; ++y)
    for (float* p = f.ptr<float>(y); p != f.ptr<float>(y) + f.cols; ++p) *p += noise(rng);
  f.convertTo(photo.image, CV_8U);  // rounds and saturates
  return photo;
}

}  // namespace glasspiv
