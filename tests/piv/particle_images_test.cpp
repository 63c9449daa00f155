#include "piv/particle_images.h"

#include <cmath>

#include <gtest/gtest.h>

namespace glasspiv {
namespace {

// Exact pixel integration: the image of one particle sums to its whole
// integral I0 * 2 pi sigma^2 (sigma = D / 4), and its centroid is its place
// to 1e-3 px (the centroid of pixel bins is the mean of round(t), not of t:
// 1.4e-4 px off for sigma = 0.625 px).
TEST(ParticleImages, IntegralAndCentroid) {
  cv::Mat img = cv::Mat::zeros(32, 32, CV_32F);
  const double d = 2.5, s = d / 4;
  add_particle_image(img, 15.3, 16.7, 0.8, d);
  double sum = 0, sx = 0, sy = 0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) {
      sum += img.at<float>(y, x);
      sx += x * img.at<float>(y, x);
      sy += y * img.at<float>(y, x);
    }
  EXPECT_NEAR(sum, 0.8 * 2 * M_PI * s * s, 1e-6);
  EXPECT_NEAR(sx / sum, 15.3, 1e-3);
  EXPECT_NEAR(sy / sum, 16.7, 1e-3);
}

TEST(ParticleImages, SeededAndDense) {
  ParticleImageOptions o;
  o.width_px = o.height_px = 64;
  const auto still = [](double, double) { return std::array<double, 2>{0, 0}; };
  const ParticleImagePair p = particle_image_pair(o, still), q = particle_image_pair(o, still);
  EXPECT_EQ(cv::norm(p.a - q.a, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(p.a - p.b, cv::NORM_INF), 0.0);  // no displacement: the frames agree
  // 0.05 per pixel over (64 + 32)^2 px of image and margin, mean integral 0.75 * 2 pi sigma^2:
  // the image's share (64/96)^2 of it, within 10 % (Poisson: ~3 %).
  const double expected = 0.05 * 96 * 96 * 0.75 * 2 * M_PI * (2.5 / 4) * (2.5 / 4) * (64.0 * 64) / (96.0 * 96);
  EXPECT_NEAR(cv::sum(p.a)[0], expected, 0.1 * expected);
}

}  // namespace
}  // namespace glasspiv
