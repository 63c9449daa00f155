#include "correct/cell_mask.h"

#include <cmath>
#include <stdexcept>

#include "render/parallel_rows.h"
#include "render/shapes.h"

namespace glasspiv {

const char* cell_state_name(CellState state) {
  switch (state) {
    case CellState::valid: return "valid";
    case CellState::inside_solid: return "inside solid";
    case CellState::never_seen: return "never seen";
    case CellState::mostly_reflected: return "seen mostly through reflections";
    case CellState::few_pixels: return "too few pixels";
    case CellState::low_weight: return "too little weight";
  }
  return "?";
}

std::vector<CellState> classify_cells(const std::vector<CameraOperator>& cameras, const TraceScene& scene,
                                      const MaskOptions& options) {
  if (cameras.empty() || !cameras.front().op) throw std::invalid_argument("classify_cells: no camera operators");
  const SheetGrid& grid = cameras.front().op->grid;
  for (const CameraOperator& c : cameras) {
    if (!c.op || !(c.op->grid == grid)) throw std::invalid_argument("classify_cells: operators on different grids");
    if (!(c.weight >= 0) || !std::isfinite(c.weight)) throw std::invalid_argument("classify_cells: bad camera weight");
  }
  if (!(options.min_pixels_per_cell >= 0) || !std::isfinite(options.min_pixels_per_cell) ||
      !(options.min_mean_weight >= 0) || !std::isfinite(options.min_mean_weight))
    throw std::invalid_argument("classify_cells: thresholds must be finite and >= 0");

  // Only solids whose bounds reach the sheet plane can contain a cell centre.
  const SheetPlane& sheet = scene.sheet;
  const Eigen::Vector3d normal = sheet.normal();
  std::vector<const Shape*> cutting;
  for (const TraceSolid& s : scene.solids) {
    const Eigen::AlignedBox3d b = bounds_mm(s.shape);
    double lo = 0, hi = 0;
    for (int k = 0; k < 8; ++k) {
      const double d = (b.corner(static_cast<Eigen::AlignedBox3d::CornerType>(k)) - sheet.origin_mm).dot(normal);
      lo = k ? std::min(lo, d) : d;
      hi = k ? std::max(hi, d) : d;
    }
    if (lo <= 0 && hi >= 0) cutting.push_back(&s.shape);
  }

  std::vector<CellState> states(grid.cell_count());
  parallel_rows(grid.rows, 0, [&](int row) {
    for (int col = 0; col < grid.cols; ++col) {
      const std::size_t c = static_cast<std::size_t>(row) * grid.cols + col;
      const Eigen::Vector3d p = sheet.origin_mm + grid.s_mm(col) * sheet.s_axis + grid.t_mm(row) * sheet.t_axis;
      bool inside = false;
      for (const Shape* s : cutting)
        if ((inside = contains(*s, p))) break;
      // A camera's weight weighs its data in the reconstruction, never the
      // mask: a camera that takes part (weight > 0) counts its pixels in full.
      double pixels = 0, direct = 0, weight = 0;
      for (const CameraOperator& cam : cameras) {
        if (!(cam.weight > 0)) continue;
        pixels += cam.op->cell_pixels[c];
        direct += cam.op->cell_direct_pixels[c];
        weight += cam.op->cell_weight[c];
      }
      CellState& st = states[c];
      if (inside) st = CellState::inside_solid;
      else if (pixels <= 0) st = CellState::never_seen;
      else if (pixels < options.min_pixels_per_cell) st = CellState::few_pixels;
      else if (direct < options.min_pixels_per_cell) st = CellState::mostly_reflected;
      else if (weight < options.min_mean_weight * direct) st = CellState::low_weight;
      else st = CellState::valid;
    }
  });
  return states;
}

CellCounts count_cells(const std::vector<CellState>& states) {
  CellCounts n;
  for (CellState s : states) {
    switch (s) {
      case CellState::valid: ++n.valid; break;
      case CellState::inside_solid: ++n.inside_solid; break;
      case CellState::never_seen: ++n.never_seen; break;
      case CellState::mostly_reflected: ++n.mostly_reflected; break;
      case CellState::few_pixels: ++n.few_pixels; break;
      case CellState::low_weight: ++n.low_weight; break;
    }
  }
  return n;
}

}  // namespace glasspiv
