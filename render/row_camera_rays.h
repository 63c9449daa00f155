#pragma once
// The camera rays of one image row, samples_per_axis^2 per pixel in the order
// the tracers take them (column, then sample row, then sample column), made a
// few columns at a time so their unprojections interleave (pixel_camera_rays):
// the same rays as pixel_camera_ray, pixel by pixel, at ~1.5x the rate.
#include <cstddef>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "calib/camera_model.h"
#include "calib/rigid_transform.h"
#include "render/path_tracer.h"

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
  std::size_t next_ray_ = 0;
};

}  // namespace glasspiv
