#include "render/row_camera_rays.h"

#include <algorithm>
#include <stdexcept>

namespace glasspiv {

RowCameraRays::RowCameraRays(const CameraModel& camera, const RigidTransform& camera_from_world, int row,
                             int samples_per_axis)
    : camera_(camera), camera_from_world_(camera_from_world), row_(row), k_(samples_per_axis) {
  if (k_ < 1) throw std::invalid_argument("RowCameraRays: samples_per_axis must be >= 1");
}

const std::optional<CameraRay>& RowCameraRays::next() {
  if (next_ray_ == rays_.size()) {
    if (next_column_ >= camera_.width_px()) throw std::logic_error("RowCameraRays: past the end of the row");
    pixels_.clear();
    const int end = std::min(camera_.width_px(), next_column_ + kColumnsPerBatch);
    for (int col = next_column_; col < end; ++col)
      for (int sy = 0; sy < k_; ++sy)
        for (int sx = 0; sx < k_; ++sx)
          pixels_.emplace_back(col + (sx + 0.5) / k_ - 0.5, row_ + (sy + 0.5) / k_ - 0.5);
    next_column_ = end;
    pixel_camera_rays(camera_, camera_from_world_, pixels_, &rays_, &warm_);
    next_ray_ = 0;
  }
  return rays_[next_ray_++];
}

}  // namespace glasspiv
