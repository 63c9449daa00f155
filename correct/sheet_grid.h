#pragma once
// The rectified sheet grid: square cells of mm_per_px in the sheet's own
// coordinates (s, t in mm, render/path_tracer.h SheetPlane), the common output
// grid of all cameras, so vectors come out in physical units. No I/O.
//
// Cell (col, row) has its centre at s = s0_mm + col * mm_per_px,
// t = t0_mm - row * mm_per_px: the column grows with s and the row with -t, so
// an image of the grid looks upright when t is "up" (the placement of
// render/sheet_texture.h: a SheetTexture of the same size and mm_per_texel made
// by sheet_grid_covering lies exactly on the grid's cells).
#include <cstddef>
#include <cstdint>
#include <string>

#include <Eigen/Core>

#include "render/path_tracer.h"

namespace glasspiv {

struct SheetGrid {
  int cols = 0, rows = 0;
  double mm_per_px = 1;
  double s0_mm = 0, t0_mm = 0;  // centre of cell (0, 0), the top-left one

  std::size_t cell_count() const { return static_cast<std::size_t>(cols) * static_cast<std::size_t>(rows); }
  double s_mm(double col) const { return s0_mm + col * mm_per_px; }
  double t_mm(double row) const { return t0_mm - row * mm_per_px; }
  // Fractional cell coordinates (cell centres at integers).
  double col(double s_mm) const { return (s_mm - s0_mm) / mm_per_px; }
  double row(double t_mm) const { return (t0_mm - t_mm) / mm_per_px; }
  bool operator==(const SheetGrid& o) const {
    return cols == o.cols && rows == o.rows && mm_per_px == o.mm_per_px && s0_mm == o.s0_mm && t0_mm == o.t0_mm;
  }
};

// Most cells a grid may have (the operator's 32-bit cell indices and memory).
inline constexpr std::size_t kMaxSheetGridCells = std::size_t(1) << 28;

// The grid centred on the sheet origin that covers the sheet's extent:
// cols = ceil(extent_s / mm_per_px), rows likewise. Throws
// std::invalid_argument for mm_per_px not finite and positive or for more than
// kMaxSheetGridCells cells (the message says the limit).
SheetGrid sheet_grid_covering(const SheetPlane& sheet, double mm_per_px);

// Where a grid lies in the world (what is written beside a rectified image):
// the centre of cell (0, 0) and the world step of one column and one row.
struct SheetGridPlacement {
  Eigen::Vector3d cell00_centre_mm, col_step_mm, row_step_mm;
};
SheetGridPlacement sheet_grid_placement(const SheetGrid& grid, const SheetPlane& sheet);

// The text of sheet_grid.yaml (docs/correction.md, "Output grids"): a comment
// on how to read it, then glasspiv_sheet_grid: 1, scene (scene_path), cols,
// rows, mm_per_px, s0_mm, t0_mm, cell00_centre_mm, col_step_mm, row_step_mm,
// numbers to 17 digits. Written by yaml-cpp's emitter, so any path (a '#', a
// ': ', quotes, a newline) reads back as itself.
std::string sheet_grid_yaml(const SheetGrid& grid, const SheetPlane& sheet, const std::string& scene_path);

}  // namespace glasspiv
