#include "sim/target_photo.h"

#include <algorithm>
#include <cmath>
#include <random>

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

std::vector<RigidTransform> calibration_view_poses(const CameraModel& camera, const Eigen::Vector2d& board_size_mm,
                                                   int views, double near_mm, double far_mm, double max_tilt_deg,
                                                   std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto uniform = [&](double a, double b) { return a + (b - a) * unit(rng); };
  const double deg = M_PI / 180.0;
  std::vector<RigidTransform> poses;
  for (int v = 0; v < views; ++v) {
    // Visit the 3x3 regions of the image in turn, the centre first; the board
    // centre stays far enough from the edges that at least about three quarters
    // of the board is seen, so the corners of the sensor get corners too.
    static const int order[9] = {4, 0, 8, 2, 6, 1, 7, 3, 5};
    const int region = order[v % 9];
    const double distance = uniform(near_mm, far_mm);
    const double half_w = std::min(0.45 * camera.width_px(), 0.25 * camera.fx_px() * board_size_mm.x() / distance);
    const double half_h = std::min(0.45 * camera.height_px(), 0.25 * camera.fy_px() * board_size_mm.y() / distance);
    const double u = half_w + (region % 3 + uniform(0.3, 0.7)) / 3.0 * (camera.width_px() - 1 - 2 * half_w);
    const double w = half_h + (region / 3 + uniform(0.3, 0.7)) / 3.0 * (camera.height_px() - 1 - 2 * half_h);
    const UnprojectResult ray = camera.unproject({u, w});
    const Eigen::Vector3d direction = ray.ok() ? ray.ray_camera : Eigen::Vector3d::UnitZ();
    // Tilt alternates in sign so the set is never close to fronto-parallel.
    const double tilt_x = (v % 2 ? 1 : -1) * uniform(0.4, 1.0) * max_tilt_deg * deg;
    const double tilt_y = (v % 4 < 2 ? 1 : -1) * uniform(0.4, 1.0) * max_tilt_deg * deg;
    const double roll = uniform(-20, 20) * deg;
    RigidTransform pose;
    pose.rotation = (Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(tilt_y, Eigen::Vector3d::UnitY()) *
                     Eigen::AngleAxisd(tilt_x, Eigen::Vector3d::UnitX()))
                        .toRotationMatrix();
    const Eigen::Vector3d centre_board(board_size_mm.x() / 2, board_size_mm.y() / 2, 0);
    pose.translation_mm = direction * distance - pose.rotation * centre_board;
    poses.push_back(pose);
  }
  return poses;
}

}  // namespace glasspiv
