#pragma once
// Pictures a user would rather look at than read: heat maps and vector fields of
// values over the image, written as PNG (atomically).
#include <string>

#include "calib/pixel_grid.h"

namespace glasspiv {

struct PlotLabels {
  std::string title;         // top line
  std::string value_name;    // e.g. "|difference| px"
  std::string unit = "px";   // of the summary line's RMS and max
  bool cells = false;        // draw each sample as a flat cell (counts) instead of interpolating
};

// Colour map of |vector| over the image with a colour bar; grey where invalid.
void write_magnitude_png(const GridValues& values, int image_width_px, int image_height_px, const PlotLabels& labels,
                         const std::string& path);
// The same heat map with an arrow per sample, scaled so the longest is legible;
// the scale is printed on the picture.
void write_vector_field_png(const GridValues& values, int image_width_px, int image_height_px,
                            const PlotLabels& labels, const std::string& path);

}  // namespace glasspiv
