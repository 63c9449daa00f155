#pragma once
// A regular grid of sample pixels over an image, and a scalar/vector value per
// sample: the shape shared by distortion fields, projection differences and
// (later) residual and uncertainty maps.
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Core>

namespace glasspiv {

struct PixelGrid {
  int cols = 0, rows = 0;  // samples per row and per column
  // Sample (i, j) sits at pixel (i * step_x_px, j * step_y_px), spanning the whole
  // image from pixel centre (0, 0) to (width - 1, height - 1).
  double step_x_px = 0, step_y_px = 0;
  Eigen::Vector2d pixel(int i, int j) const { return {i * step_x_px, j * step_y_px}; }
  int size() const { return cols * rows; }

  // About `approx_step_px` apart, corners included; at least 2x2 samples.
  static PixelGrid over_image(int width_px, int height_px, double approx_step_px);
};

// Values on a PixelGrid, row-major; NaN marks a sample without a value.
struct GridValues {
  PixelGrid grid;
  std::vector<Eigen::Vector2d> vector_px;  // e.g. a displacement; NaN where invalid
  int valid_count = 0;
  double rms_px = std::numeric_limits<double>::quiet_NaN();  // of |vector| over valid samples
  double max_px = std::numeric_limits<double>::quiet_NaN();
  // Fills valid_count, rms_px and max_px from vector_px.
  void summarize();
};

}  // namespace glasspiv
