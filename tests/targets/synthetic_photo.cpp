#include "tests/targets/synthetic_photo.h"

#include <algorithm>
#include <cmath>
#include <random>

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include "targets/target_image.h"

namespace glasspiv::testing {

Eigen::Vector2d SyntheticPhoto::project(const Eigen::Vector3d& board_mm) const {
  const Eigen::Vector3d p = photo_from_board * Eigen::Vector3d(board_mm.x(), board_mm.y(), 1.0);
  return p.head<2>() / p.z();
}

PhotoSetup centred_setup(const TargetSpec& spec, double distance_mm, double tilt_x, double tilt_y, double roll,
                         Eigen::Vector2d offset_px) {
  PhotoSetup s;
  const Eigen::Vector2d size = board_size_mm(spec);
  const Eigen::Matrix3d r = (Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(tilt_y, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(tilt_x, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  const Eigen::AngleAxisd aa(r);
  s.rvec = aa.angle() * aa.axis();
  // Board centre on the optical axis at distance_mm, then shifted in the image.
  const Eigen::Vector3d centre(size.x() / 2, size.y() / 2, 0);
  s.tvec_mm = Eigen::Vector3d(0, 0, distance_mm) - r * centre;
  s.tvec_mm.x() += offset_px.x() * distance_mm / s.focal_px;
  s.tvec_mm.y() += offset_px.y() * distance_mm / s.focal_px;
  return s;
}

SyntheticPhoto synthesise_photo(const TargetSpec& spec, const PhotoSetup& s) {
  SyntheticPhoto photo;
  const double angle = s.rvec.norm();
  const Eigen::Matrix3d r = angle > 0 ? Eigen::AngleAxisd(angle, s.rvec / angle).toRotationMatrix()
                                      : Eigen::Matrix3d::Identity();
  Eigen::Matrix3d k;
  k << s.focal_px, 0, (s.width_px - 1) / 2.0, 0, s.focal_px, (s.height_px - 1) / 2.0, 0, 0, 1;
  Eigen::Matrix3d rt;
  rt.col(0) = r.col(0);
  rt.col(1) = r.col(1);
  rt.col(2) = s.tvec_mm;
  photo.photo_from_board = k * rt;

  // Render at about the supersampled photo's scale where the board is nearest.
  const Eigen::Vector2d size = board_size_mm(spec);
  double scale = 0;  // photo px per board mm, largest over the board's corners
  for (const double x : {0.0, size.x()})
    for (const double y : {0.0, size.y()}) {
      const Eigen::Vector3d p = rt * Eigen::Vector3d(x, y, 1);
      scale = std::max(scale, s.focal_px / p.z());
    }
  const int n = s.supersample;
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
  cv::Mat hi;
  cv::warpPerspective(render.image, hi, m, cv::Size(s.width_px * n, s.height_px * n), cv::INTER_LINEAR,
                      cv::BORDER_CONSTANT, cv::Scalar(s.background));
  cv::Mat low;
  cv::resize(hi, low, cv::Size(s.width_px, s.height_px), 0, 0, cv::INTER_AREA);
  cv::Mat f;
  low.convertTo(f, CV_32F);
  if (s.blur_sigma_px > 0) cv::GaussianBlur(f, f, cv::Size(0, 0), s.blur_sigma_px);
  // Paper is not perfectly white nor ink perfectly black: 255 -> 235, 0 -> 25.
  f = f * (210.0 / 255.0) + 25.0;
  std::mt19937_64 rng(s.seed);
  std::normal_distribution<float> noise(0.0f, static_cast<float>(s.noise_sigma));
  for (int y = 0; y < f.rows; ++y)
    for (float* p = f.ptr<float>(y); p != f.ptr<float>(y) + f.cols; ++p) *p += noise(rng);
  f.convertTo(photo.image, CV_8U);  // rounds and saturates
  return photo;
}

}  // namespace glasspiv::testing
