#pragma once
// The camera sensor of a simulated PIV experiment: radiance image in, digital
// image out (docs/simulation.md). Per pixel, with e = electrons_per_radiance * L:
//   counts = round(background_counts + gain_counts_per_electron * (Poisson(e) + Normal(0, read_noise_electrons)))
// clamped to [0, 2^bit_depth - 1]. Mean background + g e, variance
// g^2 (e + read_noise^2) (+ 1/12 count^2 from the rounding), before clamping.
// Seeded and platform-independent (sim/random_variates.h). No I/O.
#include <cstdint>

#include <opencv2/core.hpp>

namespace glasspiv {

struct SensorModel {
  int bit_depth = 12;                    // 8, 12 or 16
  double electrons_per_radiance = 100;   // exposure: photo-electrons per unit radiance per pixel
  double gain_counts_per_electron = 0.5; // ADC conversion
  double background_counts = 100;        // offset (black level) of every pixel, counts
  double read_noise_electrons = 5;       // Gaussian standard deviation
  bool shot_noise = true;                // false: e itself, no Poisson draw

  // Throws std::invalid_argument unless bit_depth is 8, 12 or 16 and the rest are
  // finite and >= 0.
  void check() const;
  // 2^bit_depth - 1.
  int max_count() const { return (1 << bit_depth) - 1; }
};

// The digital image (CV_16UC1, values within the bit depth) of a radiance image
// (CV_32FC1, finite and >= 0). seed fixes the noise: give each frame its own.
// Throws std::invalid_argument for another type or a negative or non-finite radiance.
cv::Mat sensor_image(const cv::Mat& radiance, const SensorModel& sensor, std::uint64_t seed);

}  // namespace glasspiv
