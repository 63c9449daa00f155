#pragma once
// Synthetic calibration data for the fit tests and fit_bench: a planar board of
// corners, board poses spread over the image, and the Observations a camera
// would make of them (seeded Gaussian pixel noise).
#include <random>
#include <vector>

#include <Eigen/Core>

#include "calib/camera_model.h"
#include "calib/observations.h"
#include "calib/rigid_transform.h"

namespace glasspiv::testing {

// cols x rows corners spacing_mm apart on z = 0; corner id = row * cols + col,
// at (col * spacing_mm, row * spacing_mm, 0).
struct SyntheticBoard {
  int cols = 12, rows = 9;
  double spacing_mm = 20;
  int size() const { return cols * rows; }
  Eigen::Vector3d point(int id) const { return {(id % cols) * spacing_mm, (id / cols) * spacing_mm, 0.0}; }
  Eigen::Vector3d centre() const { return {(cols - 1) * spacing_mm / 2, (rows - 1) * spacing_mm / 2, 0.0}; }
};

struct ViewPlan {
  int count = 20;
  double max_tilt_deg = 35;  // tilt about the board's x and y axes, each uniform in +-max_tilt_deg
  double max_roll_deg = 30;  // in-plane rotation, uniform in +-max_roll_deg
  // The board's width seen head-on covers this fraction of the image width
  // (sets the distance), uniform in [min_fill, max_fill].
  double min_fill = 0.6, max_fill = 1.0;
  // Where the board's centre appears: uniform over this central fraction of the
  // image in each direction (boards near the edges lose their outer corners).
  double centre_spread = 0.8;
};

// Board poses (camera_from_board) following `plan`, seeded by `rng`.
std::vector<RigidTransform> plan_views(const CameraModel& camera, const SyntheticBoard& board, const ViewPlan& plan,
                                       std::mt19937& rng);

// The corners of `board` seen by `camera` from each pose, with N(0, noise_px)
// added to x and y; corners outside the image or behind the camera are left out.
Observations observe(const CameraModel& camera, const SyntheticBoard& board,
                     const std::vector<RigidTransform>& camera_from_board, double noise_px, std::mt19937& rng);

// The reference cameras of the fit tests and fit_bench: 2048 x 1536, fx ~ 2400,
// a mild OpenCV5 lens; and a strong rational (OpenCV8) lens at 2560 x 1600.
inline CameraModel truth_opencv5() {
  return CameraModel(2048, 1536, 2400, 2401.5, 1030.25, 760.75, {-0.2, 0.1, 1e-4, -1.2e-4, -0.02});
}
inline CameraModel truth_opencv8() {
  return CameraModel(2560, 1600, 1500, 1501, 1275.5, 805.25, {-0.25, 0.08, 3e-4, -2e-4, -0.01, 0.15, -0.02, 0.005});
}

}  // namespace glasspiv::testing
