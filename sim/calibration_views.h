#pragma once
// Synthetic calibration sessions with known truth, the one synthesiser the
// calibration tests, the benchmarks and `glasspiv demo` share: where the board
// stands in each view (camera_from_board), and the exact corners a camera sees
// of it, with seeded Gaussian pixel noise. The photos themselves are
// sim/target_photo.h's.
//
// Reproducibility: the same arguments and seed give the same poses and
// observations to the bit (std::mt19937 and libstdc++'s distributions).
#include <cstdint>
#include <random>
#include <vector>

#include <Eigen/Core>

#include "calib/camera_model.h"
#include "calib/observations.h"
#include "calib/rigid_transform.h"

namespace glasspiv {

// A planar board of cols x rows corners spacing_mm apart on z = 0; corner
// id = row * cols + col, at (col * spacing_mm, row * spacing_mm, 0).
struct SyntheticBoard {
  int cols = 12, rows = 9;
  double spacing_mm = 20;
  int size() const { return cols * rows; }
  Eigen::Vector3d point(int id) const { return {(id % cols) * spacing_mm, (id / cols) * spacing_mm, 0.0}; }
  // The corners' extent (first to last corner) and its centre.
  Eigen::Vector2d size_mm() const { return {(cols - 1) * spacing_mm, (rows - 1) * spacing_mm}; }
  Eigen::Vector3d centre() const { return {(cols - 1) * spacing_mm / 2, (rows - 1) * spacing_mm / 2, 0.0}; }
};

// camera_from_board for a board of extent `board_size_mm` whose centre
// (board_size_mm / 2, z = 0) lies at `board_centre_camera_mm`, turned by
// R = Rz(roll) Ry(tilt_y) Rx(tilt_x) (radians: tilts about the board's x then
// y axis, roll about the optical axis; rotation_from_euler_zyx).
RigidTransform board_pose_facing(const Eigen::Vector3d& board_centre_camera_mm, const Eigen::Vector2d& board_size_mm,
                                 double tilt_x_rad, double tilt_y_rad, double roll_rad);

// Independent random views, the fit tests' and fit_bench's: each draw uniform.
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

// Board poses (camera_from_board) following `plan`, drawn from `rng` (which
// observe_board may then go on drawing from). A drawn centre pixel the camera
// cannot unproject is drawn again.
std::vector<RigidTransform> plan_views(const CameraModel& camera, const SyntheticBoard& board, const ViewPlan& plan,
                                       std::mt19937& rng);

// A session as a careful person photographs it, the demo's: the board centre
// visits the 3x3 regions of the image in turn (centre first; kept far enough
// from the edges that about three quarters of the board stays in view, so the
// sensor's corners get corners too), at a distance along the centre's ray
// uniform in [near_mm, far_mm], tilted 0.4 to 1 times max_tilt_deg about both
// board axes with alternating signs (never near fronto-parallel), rolled up to
// +-20 degrees. Reproducible from `seed`.
std::vector<RigidTransform> calibration_view_poses(const CameraModel& camera, const Eigen::Vector2d& board_size_mm,
                                                   int views, double near_mm, double far_mm, double max_tilt_deg,
                                                   std::uint32_t seed);

// The corners of `board` that `camera` sees from each pose, with N(0, noise_px)
// drawn from `rng` added to x and y (noise_px = 0 draws nothing); corners behind
// the camera, beyond the distortion's fold or outside the image are left out.
// One view per pose, named "synthetic view <index>".
Observations observe_board(const CameraModel& camera, const SyntheticBoard& board,
                           const std::vector<RigidTransform>& camera_from_board, double noise_px, std::mt19937& rng);

}  // namespace glasspiv
