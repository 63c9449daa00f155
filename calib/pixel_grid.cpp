#include "calib/pixel_grid.h"

#include <algorithm>

namespace glasspiv {

PixelGrid PixelGrid::over_image(int width_px, int height_px, double approx_step_px) {
  PixelGrid g;
  g.cols = std::max(2, static_cast<int>(std::lround((width_px - 1) / approx_step_px)) + 1);
  g.rows = std::max(2, static_cast<int>(std::lround((height_px - 1) / approx_step_px)) + 1);
  g.step_x_px = (width_px - 1.0) / (g.cols - 1);
  g.step_y_px = (height_px - 1.0) / (g.rows - 1);
  return g;
}

void GridValues::summarize() {
  valid_count = 0;
  double sum_sq = 0, max_norm = 0;
  for (const Eigen::Vector2d& v : vector_px) {
    if (!v.allFinite()) continue;
    ++valid_count;
    sum_sq += v.squaredNorm();
    max_norm = std::max(max_norm, v.norm());
  }
  if (valid_count > 0) {
    rms_px = std::sqrt(sum_sq / valid_count);
    max_px = max_norm;
  }
}

}  // namespace glasspiv
