#pragma once
// Forward render (DESIGN.md section 3): an image from the light-transport map
// and a sheet radiance. pixel = sum over its crossings of weight * texture(s, t)
// + background_weight * background_radiance (opaque surfaces contribute 0: no
// shading yet). No I/O.
//
// KNOWN LIMIT: no footprint filtering. Each crossing samples the texture at one
// point (s, t); minified regions alias and magnified ones are not smoothed.
// Until the map carries ray differentials, supersampling with
// build_transport_map(..., samples_per_axis > 1) is the anti-aliasing.
//
// The core works on plain float buffers so that glasspiv_render needs no
// OpenCV; the cv::Mat entry points below are inline and appear wherever OpenCV
// is on the include path (tests, bench, apps).
#include <algorithm>
#include <functional>
#include <vector>

#include "render/transport_map.h"

#if __has_include(<opencv2/core.hpp>)
#include <opencv2/core.hpp>
#define GLASSPIV_FORWARD_RENDER_HAS_OPENCV 1
#endif

namespace glasspiv {

// Sheet radiance at sheet coordinates (mm).
using SheetSampler = std::function<float(double s_mm, double t_mm)>;

// Row-major width * height image; sums in double per pixel.
std::vector<float> forward_render_values(const TransportMap& map, const SheetSampler& texture,
                                         double background_radiance = 0);

// A texture image laid on the sheet, centred on the sheet origin, mm_per_pixel
// per texture pixel; column grows with s, row grows with -t (t is "up").
// Bilinear; 0 outside. values: row-major, rows x cols; kept by reference.
SheetSampler texture_sampler(const float* values, int rows, int cols, double mm_per_pixel);

#ifdef GLASSPIV_FORWARD_RENDER_HAS_OPENCV
// CV_32F image of map.height x map.width.
inline cv::Mat forward_render(const TransportMap& map, const SheetSampler& texture, double background_radiance = 0) {
  const std::vector<float> v = forward_render_values(map, texture, background_radiance);
  cv::Mat image(map.height, map.width, CV_32F);
  std::copy(v.begin(), v.end(), image.ptr<float>(0));
  return image;
}

// The texture as a CV_32F (or convertible single-channel) cv::Mat; see texture_sampler.
inline cv::Mat forward_render(const TransportMap& map, const cv::Mat& texture, double mm_per_pixel,
                              double background_radiance = 0) {
  cv::Mat t32;
  texture.convertTo(t32, CV_32F);
  if (!t32.isContinuous()) t32 = t32.clone();
  return forward_render(map, texture_sampler(t32.ptr<float>(0), t32.rows, t32.cols, mm_per_pixel),
                        background_radiance);
}
#endif

}  // namespace glasspiv
