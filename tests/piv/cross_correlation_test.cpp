// WindowCorrelator against the correlation sum written out, and its sign.
#include "piv/cross_correlation.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "piv/particle_images.h"
#include "piv/subpixel_peak.h"

namespace glasspiv {
namespace {

// R(dx, dy) = sum a'(x, y) b'(x + dx, y + dy) (circular) / sqrt(sum a'^2 sum b'^2), directly.
TEST(WindowCorrelator, MatchesTheDirectCircularSum) {
  const int n = 16;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> uni(0, 1);
  std::vector<float> a(n * n), b(n * n);
  for (float& v : a) v = uni(rng);
  for (float& v : b) v = uni(rng);
  WindowCorrelator c(n);
  ASSERT_EQ(c.plane_px(), n);
  ASSERT_TRUE(c.correlate(a.data(), n, nullptr, b.data(), n, nullptr));
  double ma = 0, mb = 0;
  for (int i = 0; i < n * n; ++i) ma += a[i], mb += b[i];
  ma /= n * n;
  mb /= n * n;
  double ea = 0, eb = 0;
  for (int i = 0; i < n * n; ++i) ea += (a[i] - ma) * (a[i] - ma), eb += (b[i] - mb) * (b[i] - mb);
  for (int dy = -n / 2; dy < n / 2; ++dy)
    for (int dx = -n / 2; dx < n / 2; ++dx) {
      double r = 0;
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
          r += (a[y * n + x] - ma) * (b[((y + dy + n) % n) * n + (x + dx + n) % n] - mb);
      EXPECT_NEAR(c.at_lag(dx, dy), r / std::sqrt(ea * eb), 2e-6) << dx << " " << dy;
    }
}

// A correlation coefficient: identical windows give 1 at zero lag.
TEST(WindowCorrelator, IdenticalWindowsGiveOneAtZeroLag) {
  cv::Mat a = cv::Mat::zeros(32, 32, CV_32F);
  for (int k = 0; k < 40; ++k) add_particle_image(a, 3 + (k * 7) % 26, 2 + (k * 11) % 28, 1, 2.5);
  WindowCorrelator c(32);
  ASSERT_TRUE(c.correlate(a.ptr<float>(), 32, nullptr, a.ptr<float>(), 32, nullptr));
  EXPECT_NEAR(c.at_lag(0, 0), 1.0, 1e-5);
}

// Frame B holds A's pattern moved by +3 px along x and -2 px along y: the peak
// is at lag (+3, -2), which find_correlation_peak reports as u = +3, v = -2.
TEST(WindowCorrelator, PeakLagIsTheDisplacementOfBRelativeToA) {
  cv::Mat a = cv::Mat::zeros(64, 64, CV_32F), b = a.clone();
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> pos(-4, 68);
  for (int k = 0; k < 200; ++k) {
    const double x = pos(rng), y = pos(rng);
    add_particle_image(a, x, y, 1, 2.5);
    add_particle_image(b, x + 3, y - 2, 1, 2.5);
  }
  WindowCorrelator c(32);
  ASSERT_TRUE(c.correlate(a.ptr<float>(16) + 16, 64, nullptr, b.ptr<float>(16) + 16, 64, nullptr));
  const CorrelationPeak p = find_correlation_peak(c);
  ASSERT_TRUE(p.found);
  EXPECT_NEAR(p.u_px, 3, 0.1);
  EXPECT_NEAR(p.v_px, -2, 0.1);
  EXPECT_GT(p.peak_ratio, 2);
}

TEST(WindowCorrelator, UnusablePixelsCountAsTheMean) {
  std::vector<float> a(16 * 16, 0.25f), b(16 * 16, 0.5f);
  std::vector<std::uint8_t> valid(16 * 16, 1);
  a[5] = 100;
  valid[5] = 0;  // the only varying pixel is unusable: a is uniform
  WindowCorrelator c(16);
  EXPECT_FALSE(c.correlate(a.data(), 16, valid.data(), b.data(), 16, nullptr));
  EXPECT_EQ(c.at_lag(0, 0), 0.0f);
  std::vector<std::uint8_t> none(16 * 16, 0);
  b[7] = 1;
  EXPECT_FALSE(c.correlate(b.data(), 16, none.data(), b.data(), 16, nullptr));  // no usable pixel
}

}  // namespace
}  // namespace glasspiv
