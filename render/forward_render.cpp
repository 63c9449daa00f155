#include "render/forward_render.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "render/parallel_rows.h"

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

std::vector<float> forward_render_values(const TransportMap& map, const SheetTexture& texture,
                                         double background_radiance) {
  if (map.pixel_offsets.size() != map.pixel_count() + 1)
    throw std::invalid_argument("forward_render: transport map offsets do not match its size");
  if (map.ds_dcol.size() != map.crossing_count())
    throw std::invalid_argument("forward_render: transport map has no footprint Jacobians");
  const double inv_k = 1.0 / map.samples_per_axis;
  std::vector<float> out(map.pixel_count());
  parallel_rows(map.height, 0, [&](int row) {
    const std::size_t begin = static_cast<std::size_t>(row) * map.width, end = begin + map.width;
    for (std::size_t p = begin; p < end; ++p) {
      double sum = static_cast<double>(map.background_weight[p]) * background_radiance;
      for (std::uint32_t i = map.pixel_offsets[p]; i < map.pixel_offsets[p + 1]; ++i) {
        Eigen::Matrix2d j;
        j << map.ds_dcol[i], map.ds_drow[i], map.dt_dcol[i], map.dt_drow[i];
        sum += static_cast<double>(map.weight[i]) * texture.average(map.s_mm[i], map.t_mm[i], inv_k * j);
      }
      out[p] = static_cast<float>(sum);
    }
  });
  return out;
}

}  // namespace glasspiv
