// WindowCorrelator and BatchCorrelator against the correlation sum written
// out, and the sign of the peak lag.
#include "piv/cross_correlation.h"

#include <cmath>
#include <algorithm>
#include <random>
#include <stdexcept>
#include <vector>

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

// The direct sum on a zero-padded plane, with unusable pixels counted as the mean.
std::vector<double> direct_plane(const std::vector<float>& a, const std::vector<float>& b,
                                 const std::vector<std::uint8_t>& valid, int n, int m) {
  auto mean_of = [&](const std::vector<float>& w) {
    double s = 0;
    int k = 0;
    for (int i = 0; i < n * n; ++i)
      if (valid[i]) s += w[i], ++k;
    return s / k;
  };
  const double ma = mean_of(a), mb = mean_of(b);
  // Mean-subtracted windows on the m x m plane, zero outside the window and at unusable pixels.
  std::vector<double> pa(m * m, 0.0), pb(m * m, 0.0);
  double ea = 0, eb = 0;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const int i = y * n + x;
      if (!valid[i]) continue;
      pa[y * m + x] = a[i] - ma;
      pb[y * m + x] = b[i] - mb;
      ea += pa[y * m + x] * pa[y * m + x];
      eb += pb[y * m + x] * pb[y * m + x];
    }
  std::vector<double> r(m * m);
  for (int dy = 0; dy < m; ++dy)
    for (int dx = 0; dx < m; ++dx) {
      double s = 0;
      for (int y = 0; y < m; ++y)
        for (int x = 0; x < m; ++x) s += pa[y * m + x] * pb[((y + dy) % m) * m + (x + dx) % m];
      r[dy * m + dx] = s / std::sqrt(ea * eb);
    }
  return r;
}

// Planes of every kind the optimal DFT size gives: even and odd, equal to the
// window and padded (11 -> 12, 13 -> 15), with a few unusable pixels.
TEST(BatchCorrelator, MatchesTheDirectSumOnEvenOddAndPaddedPlanes) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> uni(0, 1);
  for (int n : {8, 9, 11, 13, 15, 24, 32}) {
    std::vector<float> a(n * n), b(n * n);
    std::vector<std::uint8_t> valid(n * n, 1);
    for (float& v : a) v = uni(rng);
    for (float& v : b) v = uni(rng);
    valid[3] = valid[n * n / 2] = 0;
    BatchCorrelator c(n, 3);
    const int m = c.plane_px();
    const std::vector<double> want = direct_plane(a, b, valid, n, m);
    ASSERT_EQ(c.add(a.data(), n, valid.data(), b.data(), n, valid.data()), 0);
    ASSERT_EQ(c.add(b.data(), n, nullptr, a.data(), n, nullptr), 1);  // another pair in the same batch
    c.correlate();
    for (int i = 0; i < m * m; ++i) EXPECT_NEAR(c.plane(0)[i], want[i], 2e-6) << "window " << n << " index " << i;
  }
}

// A plane does not depend on the batch it was correlated in (nor on its slot):
// the same numbers, bit for bit, as one pair at a time.
TEST(BatchCorrelator, PlanesDoNotDependOnTheBatch) {
  cv::Mat a = cv::Mat::zeros(96, 160, CV_32F), b = a.clone();
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> pos(-4, 164);
  for (int k = 0; k < 800; ++k) {
    const double x = pos(rng), y = pos(rng) * 0.6;
    add_particle_image(a, x, y, 1, 2.5);
    add_particle_image(b, x + 1.3, y - 0.6, 1, 2.5);
  }
  const int stride = static_cast<int>(a.step1());
  BatchCorrelator batch(32, 5);
  WindowCorrelator single(32);
  std::vector<int> lefts;
  for (int x = 0; x + 32 <= 160; x += 16) lefts.push_back(x);
  int checked = 0;
  for (std::size_t first = 0; first < lefts.size(); first += 5) {
    batch.clear();
    for (std::size_t k = first; k < std::min(first + 5, lefts.size()); ++k)
      ASSERT_GE(batch.add(a.ptr<float>(32) + lefts[k], stride, nullptr, b.ptr<float>(32) + lefts[k], stride, nullptr), 0);
    batch.correlate();
    for (int slot = 0; slot < batch.size(); ++slot) {
      const int x = lefts[first + static_cast<std::size_t>(slot)];
      ASSERT_TRUE(single.correlate(a.ptr<float>(32) + x, stride, nullptr, b.ptr<float>(32) + x, stride, nullptr));
      for (int i = 0; i < 32 * 32; ++i) ASSERT_EQ(batch.plane(slot)[i], single.plane()[i]) << "window at x " << x;
      ++checked;
    }
  }
  EXPECT_EQ(checked, static_cast<int>(lefts.size()));
}

TEST(BatchCorrelator, RefusesWindowsWithoutVariationAndAFullBatch) {
  std::vector<float> flat(16 * 16, 0.5f), varied(16 * 16);
  for (int i = 0; i < 16 * 16; ++i) varied[i] = static_cast<float>((i * 37) % 11);
  BatchCorrelator c(16, 2);
  EXPECT_EQ(c.add(flat.data(), 16, nullptr, varied.data(), 16, nullptr), -1);
  EXPECT_EQ(c.add(varied.data(), 16, nullptr, flat.data(), 16, nullptr), -1);
  EXPECT_EQ(c.size(), 0);
  EXPECT_EQ(c.add(varied.data(), 16, nullptr, varied.data(), 16, nullptr), 0);
  EXPECT_EQ(c.add(varied.data(), 16, nullptr, varied.data(), 16, nullptr), 1);
  EXPECT_TRUE(c.full());
  EXPECT_THROW(c.add(varied.data(), 16, nullptr, varied.data(), 16, nullptr), std::logic_error);
  c.correlate();
  EXPECT_NEAR(c.plane(1)[0], 1.0f, 1e-5);
}

}  // namespace
}  // namespace glasspiv
