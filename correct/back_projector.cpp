#include "correct/back_projector.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "correct/camera_resampler.h"
#include "render/parallel_rows.h"

namespace glasspiv {

std::size_t BackProjector::memory_bytes() const {
  return (cells.size() + offsets.size() + pixel.size()) * sizeof(std::uint32_t) + value.size() * sizeof(float) +
         camera_pixel_offset.size() * sizeof(std::size_t);
}

BackProjector make_back_projector(const std::vector<CameraOperator>& cameras, const std::vector<CellState>& states,
                                  const std::vector<std::uint8_t>* needed) {
  if (cameras.empty() || !cameras.front().op) throw std::invalid_argument("back projector: no cameras");
  BackProjector b;
  b.grid = cameras.front().op->grid;
  const std::size_t cells = b.grid.cell_count();
  if (states.size() != cells || (needed && needed->size() != cells))
    throw std::invalid_argument("back projector: states or needed cells of another grid");
  for (const CameraOperator& c : cameras) {
    if (!c.op || !(c.op->grid == b.grid)) throw std::invalid_argument("back projector: operators on different grids");
    if (!(c.weight >= 0) || !std::isfinite(c.weight)) throw std::invalid_argument("back projector: bad camera weight");
    b.camera_pixel_offset.push_back(b.frame_pixels);
    b.frame_pixels += c.op->pixel_count();
  }
  if (b.frame_pixels > std::numeric_limits<std::uint32_t>::max())
    throw std::invalid_argument("back projector: more than 2^32 - 1 pixels over all cameras");
  b.offsets.push_back(0);
  for (std::size_t c = 0; c < cells; ++c) {
    if (states[c] != CellState::valid || (needed && !(*needed)[c])) continue;
    double weight = 0;
    for (const CameraOperator& cam : cameras) weight += cam.weight * cam.op->cell_weight[c];
    if (!(weight > 0)) continue;
    for (std::size_t k = 0; k < cameras.size(); ++k) {
      const CorrectionOperator& op = *cameras[k].op;
      const double scale = cameras[k].weight / weight;
      if (scale == 0) continue;
      for (std::uint32_t i = op.cell_offsets[c]; i < op.cell_offsets[c + 1]; ++i) {
        b.pixel.push_back(static_cast<std::uint32_t>(b.camera_pixel_offset[k] + op.entry_pixel[i]));
        b.value.push_back(static_cast<float>(scale * op.value_by_cell[i]));
      }
    }
    if (b.pixel.size() > std::numeric_limits<std::uint32_t>::max())
      throw std::invalid_argument("back projector: more than 2^32 - 1 entries");
    b.cells.push_back(static_cast<std::uint32_t>(c));
    b.offsets.push_back(static_cast<std::uint32_t>(b.pixel.size()));
  }
  return b;
}

void apply_back_projector(const BackProjector& b, const float* frame, float* l) {
  constexpr std::size_t kCellsPerTask = 8192;
  const std::size_t n = b.cells.size();
  const int tasks = static_cast<int>((n + kCellsPerTask - 1) / kCellsPerTask);
  parallel_rows(std::max(tasks, 1), 0, [&](int t) {
    const std::size_t begin = static_cast<std::size_t>(t) * kCellsPerTask, end = std::min(n, begin + kCellsPerTask);
    for (std::size_t k = begin; k < end; ++k) {
      double sum = 0;
      for (std::uint32_t i = b.offsets[k]; i < b.offsets[k + 1]; ++i) sum += double(b.value[i]) * frame[b.pixel[i]];
      l[b.cells[k]] = static_cast<float>(sum);
    }
  });
}

std::vector<std::uint8_t> cells_read_by(const CameraResampler& r, std::size_t cell_count) {
  std::vector<std::uint8_t> used(cell_count, 0);
  for (std::uint32_t c : r.cell) {
    if (c >= cell_count) throw std::invalid_argument("cells_read_by: resampler of another grid");
    used[c] = 1;
  }
  return used;
}

}  // namespace glasspiv
