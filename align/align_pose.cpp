#include "align/align_pose.h"

#include <algorithm>
#include <cmath>

namespace glasspiv {

AlignedPose align_pose(const TraceScene& scene, const SceneIndex& index, const std::vector<int>& rectangle_solids,
                       const std::vector<SceneFiducial>& fiducials, const CameraModel& camera,
                       const std::vector<FiducialCorner>& corners, const AlignPoseOptions& options) {
  std::vector<PointObservation> points;
  std::vector<Eigen::Vector3d> world;
  std::vector<int> solids;
  for (const FiducialCorner& c : corners) {
    const SceneFiducial& f = fiducials.at(static_cast<std::size_t>(c.fiducial));
    points.push_back({c.world_mm, c.pixel_px, c.fiducial, f.field + " corner " + std::to_string(c.corner_id)});
    world.push_back(c.world_mm);
    solids.push_back(rectangle_solids.at(static_cast<std::size_t>(f.rectangle)));
  }
  ExtrinsicFitOptions fit_options;
  fit_options.refine_focal = options.refine_focal;
  fit_options.outlier_k = options.outlier_k;
  fit_options.max_position_sigma_mm = options.max_position_sigma_mm;
  fit_options.max_rotation_sigma_deg = options.max_rotation_sigma_deg;
  fit_options.num_threads = options.threads;

  const ExtrinsicFit pinhole = fit_camera_pose(camera, points, fit_options);
  AlignedPose out{pinhole, pinhole, options.through_glass, {}, 0};
  if (options.through_glass) {
    ExtrinsicFitOptions traced = fit_options;
    traced.initial_camera_from_world = out.pinhole.camera_from_world;
    // The projector holds the camera model: a focal scale is fitted by the
    // pinhole fit only and then held (see AlignPoseOptions::refine_focal).
    traced.refine_focal = false;
    const PointProjector projector =
        traced_point_projector(scene, index, out.pinhole.camera, world, solids, options.traced);
    traced.projector = projector;
    out.fit = fit_camera_pose(out.pinhole.camera, points, traced);
    out.fit.focal_scale = out.pinhole.focal_scale;
    for (std::size_t i = 0; i < points.size(); ++i) {
      Eigen::Vector2d traced_px;
      const auto pinhole_px = out.fit.camera.project(out.fit.camera_from_world.apply(world[i]));
      if (pinhole_px && projector(out.fit.camera_from_world, static_cast<int>(i), &traced_px))
        out.glass_displacement_px = std::max(out.glass_displacement_px, (traced_px - *pinhole_px).norm());
    }
  }
  // Per fiducial: its inliers' RMS and worst residual.
  for (std::size_t f = 0; f < fiducials.size(); ++f) {
    FiducialFit ff;
    ff.fiducial = static_cast<int>(f);
    ff.field = fiducials[f].field;
    double sum2 = 0;
    for (const PointResidual& r : out.fit.residuals) {
      if (r.group != static_cast<int>(f)) continue;
      ++ff.corners;
      if (r.outlier) {
        ++ff.outliers;
        continue;
      }
      sum2 += r.residual_px.squaredNorm();
      ff.max_px = std::max(ff.max_px, r.residual_px.norm());
    }
    if (ff.corners == 0) continue;
    const int inliers = ff.corners - ff.outliers;
    ff.rms_px = inliers > 0 ? std::sqrt(sum2 / inliers) : 0;
    out.fiducials.push_back(ff);
  }
  return out;
}

}  // namespace glasspiv
