#pragma once
// The correction operator of one camera (DESIGN.md section 3, docs/correction.md):
// the transport map turned into a sparse matrix A between camera pixels and the
// cells of a SheetGrid, so that the forward model of an image is one sparse
// pass,
//     I_p = sum_c A[p, c] l_c + background_weight_p * background_radiance,
// and the back-projection of a distorted image is its transpose. Every sheet
// crossing of pixel p (weight w, centre (s, t), footprint Jacobian J) is spread
// over its footprint {(s, t) + J (u, v) / k : |u|, |v| <= 1/2} (k = the map's
// samples per axis) with the weight w: the footprint filter is evaluated here,
// once, never per frame. A[p, c] is w times the fraction of the footprint that
// falls on cell c (bilinear splats of a stratified grid of taps, the same taps
// render/sheet_texture.h reads, so A l equals the footprint-filtered render of
// a texture on the grid). No I/O.
//
// Layout: struct of arrays, float32 values, 32-bit indices; CSR by pixel (the
// forward direction) and the same entries CSR by cell (the back-projection),
// both kept so that each direction is a gather, threaded without atomics.
#include <cstdint>
#include <functional>
#include <vector>

#include "correct/sheet_grid.h"
#include "render/transport_map.h"

namespace glasspiv {

struct OperatorOptions {
  // false: each crossing goes to its centre only (one bilinear splat), the
  // footprint ignored: faster to build, aliases where the sheet is squeezed.
  bool footprint_filter = true;
  // Taps per footprint axis: ceil(axis length in cells), at most this. A
  // footprint longer than 2x this many cells is sampled with gaps between taps
  // (only the rims, which the masks reject, are that squeezed).
  int max_taps_per_axis = 16;
  // Taps follow the light: a crossing of weight w gets at most
  // ceil(max_taps_per_axis * sqrt(w)) taps per axis. Reflected ghosts (w of a
  // few per cent) are minified and spread over hundreds of cells: at full tap
  // count they hold 90 % of the entries for 4 % of the light. Their footprint
  // mean is then sampled more coarsely (bench/RESULTS.md has the error); false
  // spends the full tap count on every crossing.
  bool taps_by_weight = true;
};

struct CorrectionOperator {
  int width = 0, height = 0;  // camera pixels
  SheetGrid grid;
  // By pixel (row-major, p = row * width + col): entries [pixel_offsets[p], pixel_offsets[p + 1]).
  std::vector<std::uint32_t> pixel_offsets;  // width * height + 1
  std::vector<std::uint32_t> cell;           // per entry: cell index row * grid.cols + col
  std::vector<float> value;                  // per entry: A[p, cell]
  std::vector<float> background_weight;      // per pixel (from the map)
  // Per cell: camera pixels that see the cell, sum of footprint fractions
  // regardless of weight (< 1: one pixel is spread over more than a cell).
  std::vector<float> cell_pixels;
  // The same counting only crossings reached without a reflection (direct or
  // refracted views; 0 where a cell is seen through reflections only).
  std::vector<float> cell_direct_pixels;
  // Derived (finish_correction_operator): per cell, sum_p A[p, c] (the weight
  // the back-projection divides by), and the entries by cell.
  std::vector<float> cell_weight;
  std::vector<std::uint32_t> cell_offsets;   // grid.cell_count() + 1
  std::vector<std::uint32_t> entry_pixel;    // per entry, by cell: the pixel
  std::vector<float> value_by_cell;          // per entry, by cell: A[pixel, c]

  std::size_t pixel_count() const { return static_cast<std::size_t>(width) * static_cast<std::size_t>(height); }
  std::size_t entry_count() const { return value.size(); }
  std::size_t memory_bytes() const;
};

// Builds A from a map. Rows of pixels in parallel (threads <= 0: all cores),
// each into its own buffer, concatenated in order: the result is the same for
// any thread count. progress as for build_transport_map. Throws
// std::invalid_argument for a map without footprint Jacobians or with
// inconsistent arrays, or options out of range, and std::overflow_error beyond
// 2^32 - 1 entries.
CorrectionOperator build_correction_operator(const TransportMap& map, const SheetGrid& grid,
                                             const OperatorOptions& options = {}, int threads = 0,
                                             const std::function<void(int, int)>& progress = {});

// Fills cell_weight, cell_offsets, entry_pixel and value_by_cell from the
// pixel-major arrays (a counting sort; entries of a cell in pixel order).
// Throws std::invalid_argument when the pixel-major arrays are inconsistent.
void finish_correction_operator(CorrectionOperator& op);

// image = A sheet + background_weight * background_radiance (width * height
// values); sheet has grid.cell_count() values. Sums in double per pixel.
void apply_forward(const CorrectionOperator& op, const float* sheet, double background_radiance, float* image);
// per_cell = A^T image (grid.cell_count() values). Sums in double per cell.
void apply_transpose(const CorrectionOperator& op, const float* image, float* per_cell);

}  // namespace glasspiv
