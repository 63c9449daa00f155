#include "align/sensitivity_picture.h"

#include <algorithm>

#include <opencv2/imgproc.hpp>

namespace glasspiv {

cv::Mat sensitivity_heat_map(const SensitivityMap& m, const std::vector<float>& values, double top) {
  cv::Mat grey(m.height, m.width, CV_8UC1);
  for (int r = 0; r < m.height; ++r)
    for (int c = 0; c < m.width; ++c)
      grey.at<unsigned char>(r, c) = static_cast<unsigned char>(
          std::clamp(255.0 * values[static_cast<std::size_t>(r) * m.width + c] / std::max(top, 1e-30), 0.0, 255.0));
  cv::Mat colour;
  cv::applyColorMap(grey, colour, cv::COLORMAP_VIRIDIS);
  for (int r = 0; r < m.height; ++r)
    for (int c = 0; c < m.width; ++c)
      if (!m.valid[static_cast<std::size_t>(r) * m.width + c]) colour.at<cv::Vec3b>(r, c) = cv::Vec3b(90, 90, 90);
  cv::Mat big;
  cv::resize(colour, big, cv::Size(m.width * m.grid_step_px, m.height * m.grid_step_px), 0, 0, cv::INTER_NEAREST);
  return big;
}

}  // namespace glasspiv
