#pragma once
// Reconstruction of the sheet's light field l (one value per cell of a
// SheetGrid) from the images of one or more cameras (docs/correction.md).
// Assumptions, as the method's: each camera is a pinhole with lens distortion
// (one ray per pixel), and the light field on the sheet is isotropic (a sheet
// point is equally bright from every direction), so every camera's image is
// I_c = A_c l + background. No I/O.
//
// - back_projection: each pixel's value spread over its crossings' footprints
//   (A_c^T I_c), normalised by the accumulated weight (sum_p A_c[p, cell]),
//   summed over cameras: the published method's result. A pixel lit through
//   several paths (a reflection, a double image) paints its value at every
//   one of them: ghosts.
// - least_squares: min_l sum_c w_c |A_c l - I_c|^2 + lambda |grad l|^2 over the
//   valid cells (others held at 0), by CGLS warm-started from the
//   back-projection; the ghosts a pixel's second path paints are explained
//   away by the first.
//
// Pixels that are not finite (NaN, infinite: dead pixels, masked regions of a
// float frame) are left out: they have no row in A_c, so neither a sum nor a
// normalising weight sees them. A valid cell that only left-out pixels see has
// no data in that frame and comes out kNoData (NaN), with either method.
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "correct/cell_mask.h"
#include "correct/correction_operator.h"

namespace glasspiv {

// One camera's image at one instant (width * height values, row-major).
struct CameraImage {
  const CorrectionOperator* op = nullptr;
  const float* image = nullptr;
  double weight = 1;               // w_c
  double background_radiance = 0;  // what lies beyond the scene (subtracted through background_weight)
};

// A valid cell without data in this frame (seen by left-out pixels only).
inline constexpr float kNoData = std::numeric_limits<float>::quiet_NaN();

// Pixels among values[0, count) that are not finite: those left out.
std::size_t count_non_finite(const float* values, std::size_t count);

// l over grid.cell_count() cells; 0 where the state is not valid. Throws
// std::invalid_argument for no images, operators on different grids or a
// states vector of the wrong size.
std::vector<float> back_projection(const std::vector<CameraImage>& images, const std::vector<CellState>& states);

struct LeastSquaresOptions {
  // lambda = smoothness * mean over valid cells of the columns' squared norms
  // (sum_c w_c sum_p A_c[p, cell]^2), so the value is dimensionless.
  double smoothness = 0.01;
  int max_iterations = 100;
  double tolerance = 1e-3;  // stop when |K^T r| falls below this fraction of its start
};

struct LeastSquaresReport {
  int iterations = 0;
  bool converged = false;
  double residual_start = 0, residual_end = 0;  // RMS of A l - I over all pixels of all cameras
  double gradient_ratio = 0;                    // |K^T r| at the end / at the start
  std::size_t masked_pixels = 0;                // pixels left out (not finite), all cameras
};

// start: the warm start (e.g. back_projection), grid.cell_count() values; its
// non-finite values start at 0. Throws std::invalid_argument when no pixel of
// any camera is finite, or when the data overflow single precision: least
// squares never silently returns its start.
std::vector<float> least_squares(const std::vector<CameraImage>& images, const std::vector<CellState>& states,
                                 const std::vector<float>& start, const LeastSquaresOptions& options = {},
                                 LeastSquaresReport* report = nullptr);

}  // namespace glasspiv
