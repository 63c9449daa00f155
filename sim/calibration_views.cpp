#include "sim/calibration_views.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace glasspiv {
namespace {

constexpr double kDeg = M_PI / 180;

}  // namespace

RigidTransform board_pose_facing(const Eigen::Vector3d& board_centre_camera_mm, const Eigen::Vector2d& board_size_mm,
                                 double tilt_x_rad, double tilt_y_rad, double roll_rad) {
  RigidTransform pose;
  pose.rotation = rotation_from_euler_zyx(tilt_x_rad, tilt_y_rad, roll_rad);
  const Eigen::Vector3d centre_board(board_size_mm.x() / 2, board_size_mm.y() / 2, 0);
  pose.translation_mm = board_centre_camera_mm - pose.rotation * centre_board;
  return pose;
}

std::vector<RigidTransform> plan_views(const CameraModel& camera, const SyntheticBoard& board, const ViewPlan& plan,
                                       std::mt19937& rng) {
  std::uniform_real_distribution<double> tilt(-plan.max_tilt_deg, plan.max_tilt_deg),
      roll(-plan.max_roll_deg, plan.max_roll_deg), fill(plan.min_fill, plan.max_fill),
      spread(0.5 - plan.centre_spread / 2, 0.5 + plan.centre_spread / 2);
  const Eigen::Vector2d board_size_mm = board.size_mm();
  std::vector<RigidTransform> poses;
  while (static_cast<int>(poses.size()) < plan.count) {
    const double a = tilt(rng) * kDeg, b = tilt(rng) * kDeg, c = roll(rng) * kDeg;
    // Head-on, the board's width w at depth z covers fx w / z pixels.
    const double depth_mm = camera.fx_px() * board_size_mm.x() / (fill(rng) * camera.width_px());
    // One draw per statement: a call's arguments are evaluated in an
    // unspecified order (GCC right to left, clang left to right), and the
    // views must follow from the seed alone. Row first: GCC's order, so the
    // views are those of earlier releases.
    const double row_fraction = spread(rng);
    const double col_fraction = spread(rng);
    const Eigen::Vector2d target(col_fraction * (camera.width_px() - 1), row_fraction * (camera.height_px() - 1));
    const UnprojectResult ray = camera.unproject(target);
    if (!ray.ok()) continue;
    poses.push_back(board_pose_facing(ray.ray_camera / ray.ray_camera.z() * depth_mm, board_size_mm, a, b, c));
  }
  return poses;
}

std::vector<RigidTransform> calibration_view_poses(const CameraModel& camera, const Eigen::Vector2d& board_size_mm,
                                                   int views, double near_mm, double far_mm, double max_tilt_deg,
                                                   std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto uniform = [&](double a, double b) { return a + (b - a) * unit(rng); };
  std::vector<RigidTransform> poses;
  for (int v = 0; v < views; ++v) {
    // The 3x3 regions of the image in turn, the centre first.
    static const int order[9] = {4, 0, 8, 2, 6, 1, 7, 3, 5};
    const int region = order[v % 9];
    const double distance_mm = uniform(near_mm, far_mm);
    // The board centre at least a quarter board from the image edges.
    const double half_w = std::min(0.45 * camera.width_px(), 0.25 * camera.fx_px() * board_size_mm.x() / distance_mm);
    const double half_h = std::min(0.45 * camera.height_px(), 0.25 * camera.fy_px() * board_size_mm.y() / distance_mm);
    const double u = half_w + (region % 3 + uniform(0.3, 0.7)) / 3.0 * (camera.width_px() - 1 - 2 * half_w);
    const double w = half_h + (region / 3 + uniform(0.3, 0.7)) / 3.0 * (camera.height_px() - 1 - 2 * half_h);
    const UnprojectResult ray = camera.unproject({u, w});
    const Eigen::Vector3d direction = ray.ok() ? ray.ray_camera : Eigen::Vector3d::UnitZ();
    // Tilts alternate in sign so that the set is never close to fronto-parallel.
    const double tilt_x = (v % 2 ? 1 : -1) * uniform(0.4, 1.0) * max_tilt_deg * kDeg;
    const double tilt_y = (v % 4 < 2 ? 1 : -1) * uniform(0.4, 1.0) * max_tilt_deg * kDeg;
    const double roll = uniform(-20, 20) * kDeg;
    poses.push_back(board_pose_facing(direction * distance_mm, board_size_mm, tilt_x, tilt_y, roll));
  }
  return poses;
}

Observations observe_board(const CameraModel& camera, const SyntheticBoard& board,
                           const std::vector<RigidTransform>& camera_from_board, double noise_px, std::mt19937& rng) {
  std::normal_distribution<double> noise(0.0, noise_px);
  Observations out;
  out.image_width_px = camera.width_px();
  out.image_height_px = camera.height_px();
  out.target_name = "synthetic " + std::to_string(board.cols) + "x" + std::to_string(board.rows);
  for (std::size_t v = 0; v < camera_from_board.size(); ++v) {
    ViewObservations view;
    view.source = "synthetic view " + std::to_string(v);
    for (int id = 0; id < board.size(); ++id) {
      const Eigen::Vector3d p = camera_from_board[v].apply(board.point(id));
      const std::optional<Eigen::Vector2d> pixel = camera.project(p);
      // Corners beyond the distortion's fold would be images no real lens makes.
      if (!pixel || std::hypot(p.x() / p.z(), p.y() / p.z()) >= camera.fold_radius()) continue;
      if (pixel->x() < -0.5 || pixel->y() < -0.5 || pixel->x() > camera.width_px() - 0.5 ||
          pixel->y() > camera.height_px() - 0.5)
        continue;
      CornerObservation corner;
      corner.id = id;
      corner.board_point_mm = board.point(id);
      corner.pixel_px = *pixel;
      if (noise_px > 0) {
        const double dy = noise(rng);  // y first, as above
        const double dx = noise(rng);
        corner.pixel_px += Eigen::Vector2d(dx, dy);
      }
      view.corners.push_back(corner);
    }
    out.views.push_back(view);
  }
  return out;
}

}  // namespace glasspiv
