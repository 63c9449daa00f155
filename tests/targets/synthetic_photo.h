#pragma once
// Synthetic photos of a target for the detector tests: the board rendered by
// render_target(), seen by a pinhole camera at a known pose, sampled the way a
// sensor integrates light (each photo pixel the area average over its square),
// blurred a little like a lens and with seeded noise. The true pixel of every
// board point is known exactly: photo_from_board.
#include <cstdint>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "targets/target_spec.h"

namespace glasspiv::testing {

struct PhotoSetup {
  int width_px = 1280, height_px = 960;
  double focal_px = 1400;
  // Board pose: rotation (axis-angle, rad) and translation (mm) camera_from_board.
  Eigen::Vector3d rvec = Eigen::Vector3d::Zero();
  Eigen::Vector3d tvec_mm = Eigen::Vector3d(0, 0, 400);
  double blur_sigma_px = 0.7;   // Gaussian, in photo pixels
  double noise_sigma = 2.0;     // grey levels
  std::uint64_t seed = 1;
  int supersample = 4;          // photo rendered at 4x, then area-averaged
  unsigned char background = 90;
};

struct SyntheticPhoto {
  cv::Mat image;                      // CV_8UC1
  Eigen::Matrix3d photo_from_board;   // board mm (x, y, 1) -> glasspiv pixel
  Eigen::Vector2d project(const Eigen::Vector3d& board_mm) const;
};

// A pose that puts the board's centre at the image centre plus `offset_px`,
// at `distance_mm`, turned by `tilt` (rad, about the board's x then y axes) and
// `roll` (rad, about the optical axis).
PhotoSetup centred_setup(const TargetSpec& spec, double distance_mm, double tilt_x, double tilt_y, double roll,
                         Eigen::Vector2d offset_px = Eigen::Vector2d::Zero());

SyntheticPhoto synthesise_photo(const TargetSpec& spec, const PhotoSetup& setup);

}  // namespace glasspiv::testing
