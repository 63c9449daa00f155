#pragma once
// Pictures a user would rather look at than read: heat maps and vector fields of
// values over the image, written as PNG (atomically).
#include <string>

#include <opencv2/core.hpp>

#include "calib/pixel_grid.h"

namespace glasspiv {

struct PlotLabels {
  std::string title;         // top line
  std::string value_name;    // e.g. "|difference| px"
  std::string unit = "px";   // of the summary line's RMS and max
  bool cells = false;        // draw each sample as a flat cell (counts) instead of interpolating
};

// A heat map drawn but not written, for pictures that draw over it.
struct HeatMapPicture {
  cv::Mat image;      // BGR, the plot with its colour bar and captions
  cv::Rect plot;      // where the image's area lies in it
  double scale = 1;   // plot pixels per image pixel
  cv::Point at(double x_px, double y_px) const;  // an image pixel's place in `image`
};

// Colour map of |vector| over the image with a colour bar; grey where invalid.
// top: the colour bar's full scale (maps drawn with one top compare by colour);
// <= 0: the largest magnitude.
HeatMapPicture draw_magnitude_map(const GridValues& values, int image_width_px, int image_height_px,
                                  const PlotLabels& labels, double top = 0);
// The same, written to a PNG.
void write_magnitude_png(const GridValues& values, int image_width_px, int image_height_px, const PlotLabels& labels,
                         const std::string& path);
// The same heat map with an arrow per sample, scaled so the longest is legible;
// the scale is printed on the picture.
void write_vector_field_png(const GridValues& values, int image_width_px, int image_height_px,
                            const PlotLabels& labels, const std::string& path);

}  // namespace glasspiv
