#pragma once
// Window deformation (Scarano 2002, Meas. Sci. Technol. 13:R1; Raffel et al.,
// 3rd ed., sec. 5.5): a displacement field known on an interrogation grid is
// interpolated to every pixel, and both frames are resampled half-way towards
// each other (central difference), frame A at x - d(x)/2 and frame B at
// x + d(x)/2, so a particle that moved by d(x) between the frames appears at
// the same place in both deformed frames and the second-order error of a
// forward difference cancels. d is the displacement of frame B relative to
// frame A: u along +x (columns), v along +y (rows), px. No I/O.
#include <vector>

#include <opencv2/core.hpp>

#include "piv/interrogation_grid.h"

namespace glasspiv {

enum class DeformInterpolation {
  bilinear,  // 2 x 2 taps
  bicubic,   // 4 x 4 taps, Keys' cubic convolution with a = -0.5 (Catmull-Rom), interpolating
  // 4 x 4 taps on cubic B-spline coefficients (Unser 1999, IEEE Signal Process.
  // Mag. 16(6):22; the frame prefiltered once, mirror boundaries): interpolating,
  // and far less biased on 2-3 px particle images than bilinear or Keys, which
  // shift a particle by up to 0.03 px with the fractional sample position
  // (Astarita & Cardone 2005, Exp. Fluids 38:233).
  bspline3,
  bspline5,  // 6 x 6 taps on quintic B-spline coefficients, likewise
};

// "bilinear", "bicubic", "bspline3", "bspline5" (the command line's names).
const char* deform_interpolation_name(DeformInterpolation interpolation);

// Bilinear interpolation of a grid field (row-major over grid, finite) at a
// point in px; beyond the outermost window centres the outermost cells are
// extended linearly (the border windows of a gradient need it; it reaches at
// most half a window).
double grid_field_at(const InterrogationGrid& grid, const std::vector<double>& field, double x_px, double y_px);

// The grid field at every pixel centre of a width_px x height_px image (CV_32F).
cv::Mat dense_field(const InterrogationGrid& grid, const std::vector<double>& field, int width_px, int height_px);

struct DeformedFrame {
  cv::Mat values;  // CV_32F, the frame's size
  cv::Mat usable;  // CV_8U, 1 where every tap of the interpolation lay inside the frame on usable pixels
};

// Resamples frame (CV_32F) at x + fraction * (u_px(x), v_px(x)) for every pixel
// x (fraction -0.5 for frame A, +0.5 for frame B). Taps beyond the border are
// mirrored about it, but a sample point outside [0, width - 1] x [0, height - 1]
// is unusable; usable (CV_8U, nonzero = usable; empty: all) marks pixels a tap
// with nonzero weight may not fall on otherwise. threads as in row_threads.h.
DeformedFrame deform_frame(const cv::Mat& frame, const cv::Mat& usable, const cv::Mat& u_px, const cv::Mat& v_px,
                           double fraction, DeformInterpolation interpolation, int threads = 0);

}  // namespace glasspiv
