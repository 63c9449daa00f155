#pragma once
// Tracer particles on the light sheet at known places, and the scores of a
// reconstruction against them: the ground truth of the correction's tests,
// benchmarks and demo. No I/O.
#include <cstdint>
#include <vector>

#include "correct/cell_mask.h"
#include "correct/sheet_grid.h"
#include "render/path_tracer.h"
#include "render/sheet_texture.h"

namespace glasspiv {

struct SheetParticle {
  double s_mm = 0, t_mm = 0;
};

// Gaussian particle images of peak 1 and 1/e^2 diameter diameter_mm, summed.
struct SheetParticles {
  std::vector<SheetParticle> particles;
  double diameter_mm = 1;

  // Point samples of the field at the cell centres of a grid.
  std::vector<float> on(const SheetGrid& grid) const;
  // The field as a texture of mm_per_texel over the sheet's extent (for the forward render).
  SheetTexture texture(const SheetPlane& sheet, double mm_per_texel) const;
};

// per_mm2 particles per mm^2, uniform over the sheet's extent; seeded (std::mt19937_64).
SheetParticles random_sheet_particles(const SheetPlane& sheet, double per_mm2, double diameter_mm, std::uint64_t seed);

// Where a score is taken: 1 = use the element.
std::vector<std::uint8_t> valid_cells(const std::vector<CellState>& states);

// Normalised cross-correlation and RMS difference of a and b over the used elements (0 if none).
double ncc_where(const std::vector<float>& a, const std::vector<float>& b, const std::vector<std::uint8_t>& use);
double rms_difference_where(const std::vector<float>& a, const std::vector<float>& b,
                            const std::vector<std::uint8_t>& use);

// Mean distance (grid cells) between the intensity centroid of l in a window
// of +-diameter around each isolated particle (no other within 3 diameters)
// whose window is all used, and the particle's true place; *counted gets the
// number of such particles (0: the result is NaN).
double mean_centroid_error_cells(const std::vector<float>& l, const SheetParticles& field, const SheetGrid& grid,
                                 const std::vector<std::uint8_t>& use, int* counted);

}  // namespace glasspiv
