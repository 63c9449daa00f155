#pragma once
// Synthetic photographs of a calibration target through a known camera: the
// ground truth for testing detection and calibration. render_target_photo: each
// photo pixel averages the board's reflectance over its footprint (sub-samples
// placed through the exact lens model), then a sensor adds its offset, gain,
// shot and read noise. render_pinhole_target_photo: a pinhole camera, so the
// truth is one homography. Where the board stands: sim/calibration_views.h.
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "calib/camera_model.h"
#include "calib/rigid_transform.h"
#include "targets/target_image.h"
#include "targets/target_spec.h"

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

// A pinhole photo of a target whose truth is one exact homography, the
// detector tests': the board rendered by render_target() at 1.25 times the
// supersampled photo's scale where the board is nearest, warped by the
// homography onto a `supersample` times finer grid (bilinear), area-averaged to
// photo pixels (INTER_AREA's box), blurred by a symmetric Gaussian like a lens,
// ink and paper mapped to 25 and 235 grey levels, and seeded Gaussian noise
// added before rounding. Nothing in it is biased, so a detector in glasspiv's
// pixel convention has no systematic error against photo_from_board.
struct PinholePhotoOptions {
  double blur_sigma_px = 0.7;     // Gaussian, photo pixels (0: none)
  double noise_sigma = 2.0;       // grey levels (1 sigma)
  std::uint64_t seed = 1;         // noise seed (std::mt19937_64)
  int supersample = 4;            // per axis
  unsigned char background = 90;  // grey level where the board is not
};

struct PinholeTargetPhoto {
  cv::Mat image;                     // CV_8UC1, the camera's size
  Eigen::Matrix3d photo_from_board;  // board mm (x, y, 1) -> glasspiv pixel
  // The true pixel of a board point (z = 0).
  Eigen::Vector2d project(const Eigen::Vector3d& board_mm) const;
};

// The photo of `spec` seen by `pinhole` (a CameraModel without distortion:
// throws std::invalid_argument otherwise) with the board at `camera_from_board`.
PinholeTargetPhoto render_pinhole_target_photo(const CameraModel& pinhole, const RigidTransform& camera_from_board,
                                               const TargetSpec& spec, const PinholePhotoOptions& options = {});

}  // namespace glasspiv
