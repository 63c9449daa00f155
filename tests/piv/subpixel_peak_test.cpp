// The three-point fits on sampled Gaussians at known sub-pixel places, and
// the integer peak and peak ratio against their definition.
#include "piv/subpixel_peak.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace glasspiv {
namespace {

double gauss(double x, double x0, double sigma) { return std::exp(-(x - x0) * (x - x0) / (2 * sigma * sigma)); }

// A point-sampled Gaussian is fitted exactly by the Gaussian three-point
// estimator (its log is a parabola), whatever its width: error ~1e-12 px.
TEST(SubpixelPeak, GaussianFitIsExactOnSampledGaussians) {
  for (double sigma : {0.6, 1.0, 2.0})
    for (double x0 = -0.5; x0 <= 0.5; x0 += 0.05)
      EXPECT_NEAR(gaussian_peak_offset_px(gauss(-1, x0, sigma), gauss(0, x0, sigma), gauss(1, x0, sigma)), x0, 1e-9)
          << sigma << " " << x0;
}

// The parabola is exact on a parabola, and is the fallback where a sample is <= 0.
TEST(SubpixelPeak, ParabolicFallbackWhereANeighbourIsNotPositive) {
  auto par = [](double x, double x0) { return 1 - (x - x0) * (x - x0); };
  EXPECT_NEAR(parabolic_peak_offset_px(par(-1, 0.3), par(0, 0.3), par(1, 0.3)), 0.3, 1e-12);
  // left = 1 - 1.69 < 0: the Gaussian fit falls back to the parabola, exactly.
  EXPECT_NEAR(gaussian_peak_offset_px(par(-1, 0.3), par(0, 0.3), par(1, 0.3)), 0.3, 1e-12);
  EXPECT_NEAR(gaussian_peak_offset_px(0.0, 1.0, 0.5), parabolic_peak_offset_px(0.0, 1.0, 0.5), 1e-15);
  EXPECT_EQ(gaussian_peak_offset_px(1, 1, 1), 0.0);  // flat: no offset, no NaN
}

// On a plane: a 2-D sampled Gaussian blob at lag (3.3, -2.7) in the unshifted
// layout (wrapped), and its peak ratio against a second blob of half height.
TEST(SubpixelPeak, PlanePeakAtAKnownSubpixelLag) {
  const int m = 32;
  std::vector<float> plane(m * m);
  for (int r = 0; r < m; ++r)
    for (int c = 0; c < m; ++c) {
      const int lx = correlation_lag_px(c, m), ly = correlation_lag_px(r, m);
      plane[r * m + c] = static_cast<float>(gauss(lx, 3.3, 1.2) * gauss(ly, -2.7, 1.2) +
                                            0.5 * gauss(lx, -8, 1.2) * gauss(ly, 6, 1.2));
    }
  const CorrelationPeak p = find_correlation_peak(plane.data(), m);
  ASSERT_TRUE(p.found);
  EXPECT_NEAR(p.u_px, 3.3, 1e-5);  // float samples
  EXPECT_NEAR(p.v_px, -2.7, 1e-5);
  // Highest sample (3, -3) = g(0.3) g(0.3); second (-8, 6) = 0.5; lowest ~0.
  EXPECT_NEAR(p.peak_ratio, gauss(3, 3.3, 1.2) * gauss(-3, -2.7, 1.2) / 0.5, 1e-5);
}

// Across the wrap: a peak at lag -16 (index 16 of 32) takes its neighbour from index 15 and 17.
TEST(SubpixelPeak, NeighboursWrapAround) {
  const int m = 8;
  std::vector<float> plane(m * m, 0.01f);
  // Peak at index (0, 0) = lag (0, 0); its left neighbour is index 7 = lag -1.
  plane[0] = 1.0f;
  plane[7] = static_cast<float>(gauss(-1, -0.2, 1));
  plane[1] = static_cast<float>(gauss(1, -0.2, 1));
  plane[0] = static_cast<float>(gauss(0, -0.2, 1));
  const CorrelationPeak p = find_correlation_peak(plane.data(), m);
  EXPECT_NEAR(p.u_px, -0.2, 1e-5);
  std::vector<float> flat(m * m, 0.3f);
  EXPECT_FALSE(find_correlation_peak(flat.data(), m).found);
}

// The integer peak (first highest sample, row-major) and the peak ratio
// against the definition written out (second peak: the highest sample at more
// than the exclusion radius in x or y, distances wrapped), with peaks at the
// plane's edges, ties, odd sizes and several radii.
TEST(SubpixelPeak, IntegerPeakAndRatioMatchTheDefinition) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> uni(-0.2f, 0.6f);
  for (int m : {8, 9, 15, 16, 32}) {
    for (int trial = 0; trial < 40; ++trial) {
      std::vector<float> plane(m * m);
      for (float& v : plane) v = uni(rng);
      const int r = trial % 3 == 0 ? 0 : trial % 3 == 1 ? m - 1 : static_cast<int>(rng() % m);
      const int c = trial % 4 == 0 ? m - 1 : trial % 4 == 1 ? 0 : static_cast<int>(rng() % m);
      plane[r * m + c] = 1.0f;
      if (trial % 5 == 0) plane[((r + 3) % m) * m + (c + 4) % m] = 1.0f;  // a tie later or earlier in scan order
      const int e = 1 + trial % 3;
      int best = 0;
      for (int i = 1; i < m * m; ++i)
        if (plane[i] > plane[best]) best = i;
      const int br = best / m, bc = best % m;
      const float lowest = *std::min_element(plane.begin(), plane.end());
      float second = lowest;
      for (int row = 0; row < m; ++row)
        for (int col = 0; col < m; ++col) {
          const int dr = std::abs(row - br), dc = std::abs(col - bc);
          if (std::min(dr, m - dr) > e || std::min(dc, m - dc) > e) second = std::max(second, plane[row * m + col]);
        }
      const CorrelationPeak p = find_correlation_peak(plane.data(), m, e);
      ASSERT_TRUE(p.found);
      EXPECT_DOUBLE_EQ(p.u_px, correlation_lag_px(bc, m) + gaussian_peak_offset_px(plane[br * m + (bc + m - 1) % m], 1.0,
                                                                                     plane[br * m + (bc + 1) % m]));
      EXPECT_DOUBLE_EQ(p.v_px, correlation_lag_px(br, m) + gaussian_peak_offset_px(plane[((br + m - 1) % m) * m + bc], 1.0,
                                                                                     plane[((br + 1) % m) * m + bc]));
      const double span = 1.0 - lowest;
      EXPECT_DOUBLE_EQ(p.peak_ratio, span / std::max(static_cast<double>(second) - lowest, span / kMaxPeakRatio))
          << "m " << m << " trial " << trial;
    }
  }
}

}  // namespace
}  // namespace glasspiv
