#include "sim/setup_photo.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

namespace glasspiv {

cv::Mat photo_from_radiance(const std::vector<float>& radiance, int width, int height, const PhotoLook& look) {
  if (width <= 0 || height <= 0 || radiance.size() != static_cast<std::size_t>(width) * height)
    throw std::invalid_argument("photo_from_radiance: radiance does not hold width x height values");
  cv::Mat image(height, width, CV_32F, const_cast<float*>(radiance.data()));
  cv::Mat blurred;
  if (look.blur_sigma_px > 0)
    cv::GaussianBlur(image, blurred, cv::Size(), look.blur_sigma_px, look.blur_sigma_px, cv::BORDER_REPLICATE);
  else
    blurred = image.clone();
  std::mt19937 rng(look.seed);
  std::normal_distribution<double> noise(0.0, look.noise_sigma);
  const double cx = 0.5 * (width - 1), cy = 0.5 * (height - 1);
  const double corner2 = cx * cx + cy * cy;
  const double scale = look.sixteen_bit ? 257.0 : 1.0, top = look.sixteen_bit ? 65535.0 : 255.0;
  cv::Mat out(height, width, look.sixteen_bit ? CV_16UC1 : CV_8UC1);
  for (int r = 0; r < height; ++r) {
    const float* in = blurred.ptr<float>(r);
    for (int c = 0; c < width; ++c) {
      const double r2 = ((c - cx) * (c - cx) + (r - cy) * (r - cy)) / (corner2 > 0 ? corner2 : 1);
      const double light = in[c] * (1 - look.vignette * r2);
      double level = look.black_level + (look.white_level - look.black_level) * light;
      if (look.noise_sigma > 0) level += noise(rng);
      const double value = std::clamp(std::round(level * scale), 0.0, top);
      if (look.sixteen_bit)
        out.at<std::uint16_t>(r, c) = static_cast<std::uint16_t>(value);
      else
        out.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(value);
    }
  }
  return out;
}

}  // namespace glasspiv
