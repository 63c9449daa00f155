#pragma once
// Synthetic photographs of a calibration target through a known camera: the
// ground truth for testing detection and calibration. Each photo pixel averages
// the board's reflectance over its footprint (sub-samples placed through the
// exact lens model), then a sensor adds its offset, gain, shot and read noise.
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "calib/camera_model.h"
#include "calib/rigid_transform.h"
#include "targets/target_image.h"

namespace glasspiv {

struct SensorOptions {
  double black_level = 20;      // digital value of unlit pixels
  double white_level = 220;     // digital value of white paper (8-bit scale)
  double read_noise = 1.0;      // Gaussian read noise, 8-bit digital values (1 sigma)
  double photons_at_white = 0;  // > 0: Poisson shot noise with this many photo-electrons at white
  int subsamples = 4;           // per pixel and axis (4: 16 samples per pixel)
  std::uint32_t seed = 1;       // noise seed: the same seed gives the same photo
};

// The photo (CV_8UC1, the camera's size) of `board` seen by `camera` with the
// board at `camera_from_board`; where the board is not seen the paper's
// surroundings are dark (black level).
cv::Mat render_target_photo(const CameraModel& camera, const RigidTransform& camera_from_board,
                            const TargetRender& board, const SensorOptions& sensor = {});

// A spread of board poses for a calibration session, reproducible from `seed`:
// the board centre placed over the image (3x3 regions visited in turn, so the
// corners of the sensor are covered, with most of the board kept in view), at
// distances in [near_mm, far_mm], tilted
// up to max_tilt_deg about both board axes and rolled up to 20 degrees.
std::vector<RigidTransform> calibration_view_poses(const CameraModel& camera, const Eigen::Vector2d& board_size_mm,
                                                   int views, double near_mm, double far_mm, double max_tilt_deg,
                                                   std::uint32_t seed);

}  // namespace glasspiv
