#include "correct/sheet_grid.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "util/text_number.h"

namespace glasspiv {

SheetGrid sheet_grid_covering(const SheetPlane& sheet, double mm_per_px) {
  if (!(mm_per_px > 0) || !std::isfinite(mm_per_px))
    throw std::invalid_argument("sheet grid: mm per pixel must be finite and positive");
  // The same count as render/sheet_pattern.h pictures of the sheet, so one at this pitch lies on the grid.
  const double cols = std::ceil(sheet.extent_s_mm / mm_per_px), rows = std::ceil(sheet.extent_t_mm / mm_per_px);
  if (!(cols * rows <= static_cast<double>(kMaxSheetGridCells)))
    throw std::invalid_argument("sheet grid: " + format_number(cols) + " x " + format_number(rows) +
                                " cells exceed the limit of " + std::to_string(kMaxSheetGridCells) +
                                " (choose a larger mm per pixel)");
  SheetGrid g;
  g.cols = std::max(1, static_cast<int>(cols));
  g.rows = std::max(1, static_cast<int>(rows));
  g.mm_per_px = mm_per_px;
  g.s0_mm = -0.5 * (g.cols - 1) * mm_per_px;
  g.t0_mm = 0.5 * (g.rows - 1) * mm_per_px;
  return g;
}

SheetGridPlacement sheet_grid_placement(const SheetGrid& grid, const SheetPlane& sheet) {
  return {sheet.origin_mm + grid.s0_mm * sheet.s_axis + grid.t0_mm * sheet.t_axis, grid.mm_per_px * sheet.s_axis,
          -grid.mm_per_px * sheet.t_axis};
}

}  // namespace glasspiv
