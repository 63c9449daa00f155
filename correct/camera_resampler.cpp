#include "correct/camera_resampler.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "render/parallel_rows.h"

namespace glasspiv {

TransportMap glass_removed_map(const TraceScene& scene, const CameraModel& camera,
                               const RigidTransform& camera_from_world, int samples_per_axis, int threads) {
  TraceScene empty;
  empty.fluid_index = scene.fluid_index;
  empty.sheet = scene.sheet;
  return build_transport_map(empty, camera, camera_from_world, TraceOptions{}, samples_per_axis, threads);
}

double median_footprint_mm(const TransportMap& map) {
  std::vector<double> side;
  side.reserve(map.crossing_count());
  for (std::size_t i = 0; i < map.crossing_count(); ++i) {
    const double det = std::abs(double(map.ds_dcol[i]) * map.dt_drow[i] - double(map.ds_drow[i]) * map.dt_dcol[i]);
    if (std::isfinite(det) && det > 0) side.push_back(std::sqrt(det));
  }
  if (side.empty()) return 0;
  std::nth_element(side.begin(), side.begin() + side.size() / 2, side.end());
  return side[side.size() / 2];
}

CameraResampler make_camera_resampler(const CorrectionOperator& glass_removed, const std::vector<CellState>& states,
                                      double min_valid_fraction) {
  if (states.size() != glass_removed.grid.cell_count())
    throw std::invalid_argument("camera resampler: cell states of another grid");
  if (!(min_valid_fraction > 0 && min_valid_fraction <= 1))
    throw std::invalid_argument("camera resampler: min_valid_fraction must be in (0, 1]");
  const CorrectionOperator& b = glass_removed;
  CameraResampler r;
  r.width = b.width;
  r.height = b.height;
  r.pixel_valid.assign(b.pixel_count(), 0);
  r.pixel_offsets.reserve(b.pixel_count() + 1);
  r.pixel_offsets.push_back(0);
  for (std::size_t p = 0; p < b.pixel_count(); ++p) {
    double all = 0, valid = 0;
    for (std::uint32_t i = b.pixel_offsets[p]; i < b.pixel_offsets[p + 1]; ++i) {
      all += b.value[i];
      if (states[b.cell[i]] == CellState::valid) valid += b.value[i];
    }
    if (all > 0 && valid >= min_valid_fraction * all) {
      r.pixel_valid[p] = 255;
      for (std::uint32_t i = b.pixel_offsets[p]; i < b.pixel_offsets[p + 1]; ++i)
        if (states[b.cell[i]] == CellState::valid) {
          r.cell.push_back(b.cell[i]);
          r.value.push_back(static_cast<float>(b.value[i] / valid));
        }
    }
    r.pixel_offsets.push_back(static_cast<std::uint32_t>(r.cell.size()));
  }
  return r;
}

void resample_to_camera(const CameraResampler& r, const float* sheet, float* image) {
  parallel_rows(r.height, 0, [&](int row) {
    const std::size_t begin = static_cast<std::size_t>(row) * r.width, end = begin + r.width;
    for (std::size_t p = begin; p < end; ++p) {
      double sum = 0;
      for (std::uint32_t i = r.pixel_offsets[p]; i < r.pixel_offsets[p + 1]; ++i)
        sum += double(r.value[i]) * sheet[r.cell[i]];
      image[p] = static_cast<float>(sum);
    }
  });
}

}  // namespace glasspiv
