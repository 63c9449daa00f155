// WindowCorrelator against the correlation sum written out, and its sign.
#include "piv/cross_correlation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>

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

// Both FFT paths (cross_correlation.h) against the same direct sum, with some
// pixels unusable (they count as the mean: a' = 0), on power-of-two planes and
// on a plane only OpenCV's DFT takes (24 = 2^3 3).
TEST(WindowCorrelator, BothFftPathsMatchTheDirectCircularSum) {
  struct Case {
    int n;
    CorrelationFft fft;
  };
  for (const Case& k : {Case{8, CorrelationFft::radix2}, Case{32, CorrelationFft::radix2}, Case{64, CorrelationFft::radix2},
                        Case{32, CorrelationFft::opencv}, Case{24, CorrelationFft::automatic}}) {
    const int n = k.n;
    std::mt19937 rng(7 + n);
    std::uniform_real_distribution<float> uni(0, 1);
    std::vector<float> a(n * n), b(n * n);
    std::vector<std::uint8_t> valid_a(n * n, 1), valid_b(n * n, 1);
    for (float& v : a) v = uni(rng);
    for (float& v : b) v = uni(rng);
    for (int i = 0; i < n * n; i += 7) valid_a[i] = 0;
    for (int i = 3; i < n * n; i += 11) valid_b[i] = 0;
    WindowCorrelator c(n, k.fft);
    ASSERT_EQ(c.plane_px(), n);
    EXPECT_EQ(c.fft(), k.fft == CorrelationFft::automatic ? CorrelationFft::opencv : k.fft);
    ASSERT_TRUE(c.correlate(a.data(), n, valid_a.data(), b.data(), n, valid_b.data()));
    auto centred = [n](const std::vector<float>& v, const std::vector<std::uint8_t>& ok) {
      double sum = 0;
      int count = 0;
      for (int i = 0; i < n * n; ++i) sum += ok[i] ? v[i] : 0.0, count += ok[i];
      std::vector<double> out(n * n);
      for (int i = 0; i < n * n; ++i) out[i] = ok[i] ? v[i] - sum / count : 0.0;
      return out;
    };
    const std::vector<double> ca = centred(a, valid_a), cb = centred(b, valid_b);
    double ea = 0, eb = 0;
    for (int i = 0; i < n * n; ++i) ea += ca[i] * ca[i], eb += cb[i] * cb[i];
    double worst = 0;
    for (int dy = -n / 2; dy < n / 2; ++dy)
      for (int dx = -n / 2; dx < n / 2; ++dx) {
        double r = 0;
        for (int y = 0; y < n; ++y)
          for (int x = 0; x < n; ++x) r += ca[y * n + x] * cb[((y + dy + n) % n) * n + (x + dx + n) % n];
        worst = std::max(worst, std::abs(c.at_lag(dx, dy) - r / std::sqrt(ea * eb)));
      }
    EXPECT_LT(worst, 2e-6) << "n = " << n << ", fft " << static_cast<int>(k.fft);
  }
}

// The radix-2 path and OpenCV's DFT give the same plane on particle images to
// float round-off (measured: at most 1.8e-7 on 32 px windows, R in [-1, 1]).
TEST(WindowCorrelator, Radix2AndOpenCvPlanesAgree) {
  cv::Mat a = cv::Mat::zeros(96, 96, CV_32F), b = a.clone();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> pos(-4, 100);
  for (int k = 0; k < 460; ++k) {
    const double x = pos(rng), y = pos(rng);
    add_particle_image(a, x, y, 1, 2.5);
    add_particle_image(b, x + 2.3, y - 1.7, 1, 2.5);
  }
  WindowCorrelator fast(32, CorrelationFft::radix2), reference(32, CorrelationFft::opencv);
  double worst = 0;
  for (int y = 0; y + 32 <= 96; y += 16)
    for (int x = 0; x + 32 <= 96; x += 16) {
      const float* pa = a.ptr<float>(y) + x;
      const float* pb = b.ptr<float>(y) + x;
      ASSERT_TRUE(fast.correlate(pa, 96, nullptr, pb, 96, nullptr));
      ASSERT_TRUE(reference.correlate(pa, 96, nullptr, pb, 96, nullptr));
      for (int i = 0; i < 32 * 32; ++i) worst = std::max(worst, std::abs(double(fast.plane()[i]) - reference.plane()[i]));
      const CorrelationPeak p = find_correlation_peak(fast), q = find_correlation_peak(reference);
      EXPECT_NEAR(p.u_px, q.u_px, 1e-4);
      EXPECT_NEAR(p.v_px, q.v_px, 1e-4);
    }
  std::printf("radix-2 against OpenCV DFT: largest plane difference %.2g\n", worst);
  EXPECT_LT(worst, 1e-6);
}

TEST(WindowCorrelator, Radix2NeedsAPowerOfTwoPlane) {
  EXPECT_THROW(WindowCorrelator(24, CorrelationFft::radix2), std::invalid_argument);
  EXPECT_EQ(WindowCorrelator(24).fft(), CorrelationFft::opencv);
  EXPECT_EQ(WindowCorrelator(32).fft(), CorrelationFft::radix2);
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
