// The three-point fits on sampled Gaussians at known sub-pixel places.
#include "piv/subpixel_peak.h"

#include <cmath>
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

}  // namespace
}  // namespace glasspiv
