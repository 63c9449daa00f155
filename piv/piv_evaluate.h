#pragma once
// Multi-pass PIV evaluation of one frame pair with window deformation
// (Scarano 2002; the scheme of the published glasspiv evaluation: 64 px then
// 32 px windows, 50 % overlap). Pass 1 correlates the frames as they are; each
// later pass deforms both frames by the previous pass's validated field
// (frame_deformation.h: A by -d/2, B by +d/2), correlates the deformed windows
// and adds the residual displacement found to the predictor at the window
// centre. Every pass ends with the normalised median test
// (vector_validation.h); invalid vectors are filled from their neighbours
// (mean of the filled ones, repeated outwards) before they predict the next
// pass, and stay invalid in the result.
//
// Sign convention everywhere: (u_px, v_px) is the displacement of frame B
// relative to frame A in px, u along +x (columns, right), v along +y (rows,
// down); window centres (x_px, y_px) with (0, 0) the centre of the top-left
// pixel (docs/conventions.md). A particle at (x, y) in A and (x + 3, y) in B
// gives u_px = +3.
//
// Masks: a window whose centre pixel (the pixel at left + window/2, top +
// window/2) is not usable, or more than half of whose pixels are not, gives
// no vector (VectorFlag::invalid). Unusable pixels elsewhere count as the
// window mean in the correlation (cross_correlation.h). Non-finite pixels of
// either frame are unusable. No I/O; threaded over rows of windows, results
// independent of the thread count.
#include <cstddef>
#include <functional>
#include <vector>

#include <opencv2/core.hpp>

#include "piv/frame_deformation.h"
#include "piv/interrogation_grid.h"
#include "piv/vector_validation.h"

namespace glasspiv {

struct PivOptions {
  // One pass per entry, square window sides in px, each at least 8.
  std::vector<int> window_px{64, 32};
  double overlap = 0.5;  // fraction of a window shared with the next, [0, 0.9]
  // Quintic B-splines: bilinear and Keys' cubic bias 2.5 px particles by up to
  // 0.06 px, cubic B-splines by 0.02 px, quintic by 0.01 px (docs/piv.md).
  DeformInterpolation interpolation = DeformInterpolation::bspline5;
  MedianTestOptions validation;
  int threads = 0;  // <= 0: all cores
  int peak_exclusion_radius_px = 2;  // subpixel_peak.h, for the peak ratio

  // std::invalid_argument naming the field ("window_px", "overlap", ...).
  void check() const;
};

struct PivField {
  InterrogationGrid grid;  // of the final pass
  // Per vector, row-major over the grid (index = row * cols + col):
  // displacement of frame B relative to frame A, u along +x, v along +y, px;
  // NaN where the flag is invalid.
  std::vector<double> u_px, v_px;
  std::vector<VectorFlag> flags;
  std::vector<double> peak_ratio;  // of the final pass's correlation; 0 where there was none
  MedianTestCounts validation;     // of the final pass

  std::size_t size() const { return flags.size(); }
  double x_px(std::size_t i) const { return grid.x_px(static_cast<int>(i) % grid.cols); }
  double y_px(std::size_t i) const { return grid.y_px(static_cast<int>(i) / grid.cols); }
};

// frame_a, frame_b: CV_32F of one size; usable: empty (all usable) or CV_8U of
// the same size, nonzero = usable (glasspiv correct's mask.tif reads so).
// progress (optional) is called on the calling thread with (windows done,
// windows of all passes) now and then; it must not throw. Throws
// std::invalid_argument for bad options, sizes or types, or a window larger
// than the frames.
PivField evaluate_piv(const cv::Mat& frame_a, const cv::Mat& frame_b, const cv::Mat& usable, const PivOptions& options,
                      const std::function<void(std::size_t done, std::size_t total)>& progress = {});

// The final pass's grid evaluate_piv would use (for checks before the work).
InterrogationGrid final_piv_grid(int width_px, int height_px, const PivOptions& options);

}  // namespace glasspiv
