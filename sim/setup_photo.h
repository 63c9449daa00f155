#pragma once
// A render of the setup made to look like a photograph of it: lens blur, a
// vignette, the sensor's black level, gain and noise, quantised. The ground truth
// of alignment tests and of the demo: the pose and the model are known exactly.
// No I/O.
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

namespace glasspiv {

struct PhotoLook {
  double blur_sigma_px = 0.7;   // Gaussian lens and sensor blur
  double vignette = 0.25;       // relative loss of light in the image corners (0: none)
  double black_level = 12;      // digital value of zero radiance (8-bit scale)
  double white_level = 235;     // digital value of radiance 1
  double noise_sigma = 0.5;     // Gaussian read noise, 8-bit digital values (1 sigma)
  std::uint32_t seed = 1;       // the same seed gives the same photo
  bool sixteen_bit = false;     // CV_16UC1 on the 16-bit scale (levels x 257) instead of CV_8UC1
};

// `radiance`: row-major width x height (render/setup_render.h). The vignette
// falls off as 1 - vignette * (r / r_corner)^2 from the image centre.
cv::Mat photo_from_radiance(const std::vector<float>& radiance, int width, int height, const PhotoLook& look = {});

}  // namespace glasspiv
