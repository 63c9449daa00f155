// sim/sensor.h: mean and variance of the digital values against the model
// (shot + read noise, gain, background, rounding), clamping, reproducibility.
#include "sim/sensor.h"

#include <cmath>

#include <gtest/gtest.h>

namespace glasspiv {
namespace {

struct Stats {
  double mean = 0, variance = 0;
  double n = 0;
};

Stats stats(const cv::Mat& counts) {
  Stats s;
  s.n = static_cast<double>(counts.total());
  cv::Mat values;
  counts.convertTo(values, CV_64F);
  cv::Scalar mean, stddev;
  cv::meanStdDev(values, mean, stddev);
  s.mean = mean[0];
  s.variance = stddev[0] * stddev[0] * s.n / (s.n - 1);
  return s;
}

// A flat field of 512 x 512 pixels. Expected mean b + g e, variance
// g^2 (e + r^2) + 1/12 (rounding to counts, Sheppard's correction: the noise is
// several counts wide). Tolerances 4 standard errors: sqrt(var / n) for the
// mean, var sqrt(2 / n) for the (near-Gaussian) variance.
void expect_moments(const SensorModel& sensor, double radiance, double expected_variance) {
  const cv::Mat flat(512, 512, CV_32FC1, cv::Scalar(radiance));
  const Stats s = stats(sensor_image(flat, sensor, 17));
  const double expected_mean =
      sensor.background_counts + sensor.gain_counts_per_electron * sensor.electrons_per_radiance * radiance;
  EXPECT_NEAR(s.mean, expected_mean, 4 * std::sqrt(expected_variance / s.n));
  EXPECT_NEAR(s.variance, expected_variance, 4 * expected_variance * std::sqrt(2 / s.n));
}

TEST(Sensor, ShotAndReadNoiseHaveTheModelsMoments) {
  SensorModel sensor;
  sensor.bit_depth = 12;
  sensor.electrons_per_radiance = 100;
  sensor.gain_counts_per_electron = 0.5;
  sensor.background_counts = 100;
  sensor.read_noise_electrons = 5;
  const double g2 = 0.25;
  // Shot and read: e = 400 electrons.
  expect_moments(sensor, 4.0, g2 * (400 + 25) + 1.0 / 12);
  // Shot alone, at gain 4 (each electron 4 counts; rounding adds nothing: values are whole).
  SensorModel shot = sensor;
  shot.read_noise_electrons = 0;
  shot.gain_counts_per_electron = 4;
  expect_moments(shot, 0.5, 16 * 50);
  // Read alone: sigma 2.5 counts.
  SensorModel read = sensor;
  read.shot_noise = false;
  expect_moments(read, 4.0, g2 * 25 + 1.0 / 12);
}

// Values stay within the bit depth: saturation at 2^bits - 1, zero at the bottom.
TEST(Sensor, ValuesStayWithinTheBitDepth) {
  cv::Mat radiance(64, 64, CV_32FC1);
  for (int r = 0; r < radiance.rows; ++r)
    for (int c = 0; c < radiance.cols; ++c) radiance.at<float>(r, c) = static_cast<float>(std::pow(10.0, (r - 20) / 6.0));
  for (int bits : {8, 12, 16}) {
    SensorModel sensor;
    sensor.bit_depth = bits;
    sensor.background_counts = 0;
    sensor.read_noise_electrons = 20;
    const cv::Mat counts = sensor_image(radiance, sensor, 3);
    ASSERT_EQ(counts.type(), CV_16UC1);
    double lo = 0, hi = 0;
    cv::minMaxLoc(counts, &lo, &hi);
    EXPECT_EQ(lo, 0) << bits;  // the read noise of a dark pixel goes below zero and is clamped
    EXPECT_EQ(hi, (1 << bits) - 1) << bits;
  }
}

TEST(Sensor, SameSeedSameImageOtherSeedOther) {
  const cv::Mat radiance(32, 48, CV_32FC1, cv::Scalar(2.0f));
  const SensorModel sensor;
  const cv::Mat a = sensor_image(radiance, sensor, 1), b = sensor_image(radiance, sensor, 1),
                c = sensor_image(radiance, sensor, 2);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0);
  EXPECT_GT(cv::norm(a, c, cv::NORM_INF), 0);
}

TEST(Sensor, RefusesBadInput) {
  SensorModel sensor;
  const cv::Mat radiance(4, 4, CV_32FC1, cv::Scalar(1.0f));
  sensor.bit_depth = 10;
  EXPECT_THROW(sensor_image(radiance, sensor, 1), std::invalid_argument);
  sensor.bit_depth = 8;
  EXPECT_THROW(sensor_image(cv::Mat(4, 4, CV_64FC1, cv::Scalar(1.0)), sensor, 1), std::invalid_argument);
  cv::Mat negative = radiance.clone();
  negative.at<float>(2, 3) = -1;
  EXPECT_THROW(sensor_image(negative, sensor, 1), std::invalid_argument);
  negative.at<float>(2, 3) = NAN;
  EXPECT_THROW(sensor_image(negative, sensor, 1), std::invalid_argument);
}

}  // namespace
}  // namespace glasspiv
