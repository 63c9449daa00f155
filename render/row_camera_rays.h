#pragma once
// The camera rays of one image row, samples_per_axis^2 per pixel in the order
// the tracers take them (column, then sample row, then sample column), made a
// few columns at a time so their unprojections interleave, each batch's
// started from the one before (pixel_camera_rays with a CameraRayWarmStart):
// pixel_camera_ray's rays to the unprojection's tolerance (1e-10 px), at about
// twice the rate of pixel_camera_ray one by one.
#include <cstddef>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "calib/camera_model.h"
#include "calib/rigid_transform.h"
#include "render/path_tracer.h"
#include "render/trace_scene_builder.h"

namespace glasspiv {

class RowCameraRays {
 public:
  RowCameraRays(const CameraModel& camera, const RigidTransform& camera_from_world, int row, int samples_per_axis);

  // The next sample's ray; nullopt where the model cannot unproject it.
  const std::optional<CameraRay>& next();

 private:
  static constexpr int kColumnsPerBatch = 8;
  const CameraModel& camera_;
  const RigidTransform& camera_from_world_;
  int row_, k_, next_column_ = 0;
  std::vector<Eigen::Vector2d> pixels_;
  std::vector<std::optional<CameraRay>> rays_;
  CameraRayWarmStart warm_;
  std::size_t next_ray_ = 0;
};

}  // namespace glasspiv
