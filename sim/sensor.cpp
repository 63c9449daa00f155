#include "sim/sensor.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "sim/random_variates.h"

namespace glasspiv {

void SensorModel::check() const {
  const auto ok = [](double v) { return std::isfinite(v) && v >= 0; };
  if (bit_depth != 8 && bit_depth != 12 && bit_depth != 16)
    throw std::invalid_argument("SensorModel: bit_depth must be 8, 12 or 16");
  if (!ok(electrons_per_radiance) || !ok(gain_counts_per_electron) || !ok(background_counts) ||
      !ok(read_noise_electrons))
    throw std::invalid_argument("SensorModel: exposure, gain, background and read noise must be finite and >= 0");
}

cv::Mat sensor_image(const cv::Mat& radiance, const SensorModel& sensor, std::uint64_t seed) {
  sensor.check();
  if (radiance.type() != CV_32FC1) throw std::invalid_argument("sensor_image: radiance must be CV_32FC1");
  RandomVariates random(seed);
  const double max_count = sensor.max_count();
  cv::Mat counts(radiance.size(), CV_16UC1);
  for (int row = 0; row < radiance.rows; ++row) {
    const float* in = radiance.ptr<float>(row);
    std::uint16_t* out = counts.ptr<std::uint16_t>(row);
    for (int col = 0; col < radiance.cols; ++col) {
      const double l = in[col];
      if (!std::isfinite(l) || l < 0) throw std::invalid_argument("sensor_image: radiance must be finite and >= 0");
      const double mean_electrons = sensor.electrons_per_radiance * l;
      double electrons = sensor.shot_noise ? static_cast<double>(random.poisson(mean_electrons)) : mean_electrons;
      if (sensor.read_noise_electrons > 0) electrons += sensor.read_noise_electrons * random.normal();
      const double value = std::round(sensor.background_counts + sensor.gain_counts_per_electron * electrons);
      out[col] = static_cast<std::uint16_t>(std::clamp(value, 0.0, max_count));
    }
  }
  return counts;
}

}  // namespace glasspiv
