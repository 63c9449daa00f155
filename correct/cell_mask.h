#pragma once
// Which sheet cells can be reconstructed, and why not (docs/correction.md,
// "Masks"). From the operators of one or more cameras on the same grid and
// the scene's solids. No I/O.
//
// A cell is, in this order of precedence:
//   inside_solid  its centre lies inside a solid (the sheet there is in glass);
//   never_seen    no camera pixel's footprint reaches it;
//   few_pixels    fewer than min_pixels_per_cell camera pixels cover it (the
//                 rims, where a large region of the sheet is squeezed onto a
//                 few pixels: one pixel is smeared over many cells);
//   mostly_reflected  fewer than min_pixels_per_cell of them see it without
//                 a reflection: its view is ghost images (a few per cent of
//                 the light each), the edge of a direct view at best;
//   low_weight    the light its pixels receive from it, per pixel that sees it
//                 without a reflection, is below min_mean_weight (grazing
//                 refractions, long paths in absorbing glass: mostly noise);
//   valid         otherwise.
// With several cameras the pixels and weights of all of them add, so one
// camera can fill another's rims. A camera's weight (CameraOperator::weight)
// weighs its data in the reconstruction, never the mask: every camera of
// weight > 0 counts in full, one of weight 0 is left out.
#include <cstdint>
#include <vector>

#include "correct/correction_operator.h"
#include "render/path_tracer.h"

namespace glasspiv {

enum class CellState : std::uint8_t { valid = 0, inside_solid, never_seen, few_pixels, mostly_reflected, low_weight };
const char* cell_state_name(CellState state);  // "valid", "inside solid", ...

struct MaskOptions {
  // docs/correction.md gives the measurement behind the defaults.
  double min_pixels_per_cell = 0.25;  // one pixel over at most 4 cells
  double min_mean_weight = 0.1;       // a direct view through glass keeps ~0.8; one reflection ~0.04
};

struct CameraOperator {
  const CorrectionOperator* op = nullptr;
  double weight = 1;  // the camera's share in a multi-camera reconstruction (0: left out)
};

// Throws std::invalid_argument for no operators, operators on different grids,
// or options that are negative or not finite.
std::vector<CellState> classify_cells(const std::vector<CameraOperator>& cameras, const TraceScene& scene,
                                      const MaskOptions& options = {});

// Counts per state, and the fraction of the sheet's fluid region (cells not
// inside a solid) that is valid.
struct CellCounts {
  std::size_t valid = 0, inside_solid = 0, never_seen = 0, mostly_reflected = 0, few_pixels = 0, low_weight = 0;
  std::size_t fluid() const { return valid + never_seen + mostly_reflected + few_pixels + low_weight; }
  double valid_fraction_of_fluid() const { return fluid() ? double(valid) / double(fluid()) : 0.0; }
  // Of the fluid cells the cameras see (enough pixels, without a reflection), the fraction that is valid.
  double valid_fraction_of_seen() const {
    const std::size_t seen = valid + low_weight;
    return seen ? double(valid) / double(seen) : 0.0;
  }
};
CellCounts count_cells(const std::vector<CellState>& states);

}  // namespace glasspiv
