#pragma once
// The back-projection of a series, prepared once: the operators' entries
// regrouped by sheet cell, kept only for the cells an output reads (valid
// cells; on the camera grid only those the resampler uses), each value already
// divided by the cell's accumulated weight. A frame is then one gather per
// cell: l_c = sum_k sum_p R_k[c, p] I_k[p], the same l as back_projection
// (correct/reconstruct.h) on those cells, with the entries of masked cells
// (ghost footprints, rims, spill into solids) not read at all. No I/O.
#include <cstdint>
#include <vector>

#include "correct/cell_mask.h"
#include "correct/reconstruct.h"

namespace glasspiv {

struct BackProjector {
  SheetGrid grid;
  std::vector<std::size_t> camera_pixel_offset;  // camera k's pixels start here in the concatenated frame
  std::size_t frame_pixels = 0;                  // all cameras' pixels
  std::vector<std::uint32_t> cells;              // the cells computed, ascending
  std::vector<std::uint32_t> offsets;            // cells.size() + 1
  std::vector<std::uint32_t> pixel;              // per entry: index into the concatenated frame
  std::vector<float> value;                      // per entry: w_k A_k[p, c] / sum_k w_k W_k[c]
  std::size_t memory_bytes() const;
};

// cameras: operators on one grid with their weights (background radiance 0).
// needed (optional, grid.cell_count()): cells to compute; default all valid
// cells. Cells not valid are never computed. Throws std::invalid_argument for
// operators on different grids, bad weights or sizes, or more than 2^32 - 1
// entries or pixels.
BackProjector make_back_projector(const std::vector<CameraOperator>& cameras, const std::vector<CellState>& states,
                                  const std::vector<std::uint8_t>* needed = nullptr);

// l (grid.cell_count() values): the computed cells set, the others left as they
// are (zero them once). frame: the cameras' images one after the other
// (frame_pixels values).
void apply_back_projector(const BackProjector& b, const float* frame, float* l);

// The cells a camera resampler reads (correct/camera_resampler.h).
struct CameraResampler;
std::vector<std::uint8_t> cells_read_by(const CameraResampler& r, std::size_t cell_count);

}  // namespace glasspiv
