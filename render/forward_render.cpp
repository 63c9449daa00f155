#include "render/forward_render.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace glasspiv {

std::vector<float> forward_render_values(const TransportMap& map, const SheetSampler& texture,
                                         double background_radiance) {
  if (map.pixel_offsets.size() != map.pixel_count() + 1)
    throw std::invalid_argument("forward_render: transport map offsets do not match its size");
  std::vector<float> out(map.pixel_count());
  for (std::size_t p = 0; p < out.size(); ++p) {
    double sum = static_cast<double>(map.background_weight[p]) * background_radiance;
    for (std::uint32_t i = map.pixel_offsets[p]; i < map.pixel_offsets[p + 1]; ++i)
      sum += static_cast<double>(map.weight[i]) * texture(map.s_mm[i], map.t_mm[i]);
    out[p] = static_cast<float>(sum);
  }
  return out;
}

SheetSampler texture_sampler(const float* values, int rows, int cols, double mm_per_pixel) {
  if (!(mm_per_pixel > 0) || rows < 1 || cols < 1) throw std::invalid_argument("texture_sampler: bad texture");
  return [=](double s_mm, double t_mm) -> float {
    const double x = s_mm / mm_per_pixel + 0.5 * (cols - 1);
    const double y = -t_mm / mm_per_pixel + 0.5 * (rows - 1);
    if (!(x >= 0 && y >= 0 && x <= cols - 1 && y <= rows - 1)) return 0.0f;
    const int x0 = std::min(static_cast<int>(x), std::max(cols - 2, 0));
    const int y0 = std::min(static_cast<int>(y), std::max(rows - 2, 0));
    const int x1 = std::min(x0 + 1, cols - 1), y1 = std::min(y0 + 1, rows - 1);
    const double fx = x - x0, fy = y - y0;
    auto at = [&](int r, int c) { return static_cast<double>(values[static_cast<std::size_t>(r) * cols + c]); };
    return static_cast<float>((1 - fy) * ((1 - fx) * at(y0, x0) + fx * at(y0, x1)) +
                              fy * ((1 - fx) * at(y1, x0) + fx * at(y1, x1)));
  };
}

}  // namespace glasspiv
