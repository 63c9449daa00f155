#include "synthetic_views.h"

#include <cmath>
#include <string>

#include <Eigen/Geometry>

namespace glasspiv::testing {

std::vector<RigidTransform> plan_views(const CameraModel& camera, const SyntheticBoard& board, const ViewPlan& plan,
                                       std::mt19937& rng) {
  constexpr double kDeg = M_PI / 180;
  std::uniform_real_distribution<double> tilt(-plan.max_tilt_deg, plan.max_tilt_deg),
      roll(-plan.max_roll_deg, plan.max_roll_deg), fill(plan.min_fill, plan.max_fill),
      spread(0.5 - plan.centre_spread / 2, 0.5 + plan.centre_spread / 2);
  const double board_width_mm = (board.cols - 1) * board.spacing_mm;
  std::vector<RigidTransform> poses;
  while (static_cast<int>(poses.size()) < plan.count) {
    const double a = tilt(rng) * kDeg, b = tilt(rng) * kDeg, c = roll(rng) * kDeg;
    const double distance_mm = camera.fx_px() * board_width_mm / (fill(rng) * camera.width_px());
    const Eigen::Vector2d target(spread(rng) * (camera.width_px() - 1), spread(rng) * (camera.height_px() - 1));
    const UnprojectResult ray = camera.unproject(target);
    if (!ray.ok()) continue;
    RigidTransform pose;
    pose.rotation = (Eigen::AngleAxisd(c, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(b, Eigen::Vector3d::UnitY()) *
                     Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX()))
                        .toRotationMatrix();
    const Eigen::Vector3d centre_camera = ray.ray_camera / ray.ray_camera.z() * distance_mm;
    pose.translation_mm = centre_camera - pose.rotation * board.centre();
    poses.push_back(pose);
  }
  return poses;
}

Observations observe(const CameraModel& camera, const SyntheticBoard& board,
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
      if (noise_px > 0) corner.pixel_px += Eigen::Vector2d(noise(rng), noise(rng));
      view.corners.push_back(corner);
    }
    out.views.push_back(view);
  }
  return out;
}

}  // namespace glasspiv::testing
