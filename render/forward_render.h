#pragma once
// Forward render (DESIGN.md section 3): an image from the light-transport map
// and a sheet radiance. pixel = sum over its crossings of weight * radiance +
// background_weight * background_radiance (opaque surfaces contribute 0: the
// sheet's light is all a PIV camera records). No I/O.
//
// With a SheetTexture the radiance of a crossing is the texture's mean over the
// crossing's footprint (its Jacobian from the map, divided by the samples per
// axis since a sub-sample covers 1/k of the pixel): minified regions do not
// alias. With a SheetSampler (any function of s, t) it is a point sample.
//
// The core works on plain float buffers so that glasspiv_render needs no
// OpenCV; the cv::Mat entry points below are inline and appear wherever OpenCV
// is on the include path (tests, bench, apps).
#include <algorithm>
#include <functional>
#include <vector>

#include "render/sheet_texture.h"
#include "render/transport_map.h"

#if __has_include(<opencv2/core.hpp>)
#include <opencv2/core.hpp>
#define GLASSPIV_FORWARD_RENDER_HAS_OPENCV 1
#endif

namespace glasspiv {

// Sheet radiance at sheet coordinates (mm).
using SheetSampler = std::function<float(double s_mm, double t_mm)>;

// Row-major width * height image; sums in double per pixel. The filtered
// render runs on all cores (rows in parallel; the result does not depend on it).
std::vector<float> forward_render_values(const TransportMap& map, const SheetSampler& texture,
                                         double background_radiance = 0);

// Footprint-filtered (see above).
std::vector<float> forward_render_values(const TransportMap& map, const SheetTexture& texture,
                                         double background_radiance = 0);

#ifdef GLASSPIV_FORWARD_RENDER_HAS_OPENCV
// CV_32F image of map.height x map.width.
inline cv::Mat forward_render(const TransportMap& map, const SheetSampler& texture, double background_radiance = 0) {
  const std::vector<float> v = forward_render_values(map, texture, background_radiance);
  cv::Mat image(map.height, map.width, CV_32F);
  std::copy(v.begin(), v.end(), image.ptr<float>(0));
  return image;
}

// The texture as a single-channel cv::Mat (any depth) laid on the sheet as
// SheetTexture says, footprint-filtered.
inline cv::Mat forward_render(const TransportMap& map, const cv::Mat& texture, double mm_per_pixel,
                              double background_radiance = 0) {
  cv::Mat t32;
  texture.convertTo(t32, CV_32F);
  if (!t32.isContinuous()) t32 = t32.clone();
  const std::vector<float> v =
      forward_render_values(map, SheetTexture(t32.ptr<float>(0), t32.rows, t32.cols, mm_per_pixel), background_radiance);
  cv::Mat image(map.height, map.width, CV_32F);
  std::copy(v.begin(), v.end(), image.ptr<float>(0));
  return image;
}
#endif

}  // namespace glasspiv
