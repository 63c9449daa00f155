// MaskOverlap: the plane divided by the usable pixel pairs at each lag, and
// the bias it removes at a mask's edge.
#include "piv/mask_overlap.h"

#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "piv/cross_correlation.h"
#include "piv/particle_images.h"
#include "piv/subpixel_peak.h"

namespace glasspiv {
namespace {

TEST(MaskOverlap, FullyUsableWindowsAreLeftAlone) {
  const int n = 16;
  std::vector<float> plane(n * n);
  for (int i = 0; i < n * n; ++i) plane[i] = std::sin(0.3f * i);
  const std::vector<float> before = plane;
  const std::vector<std::uint8_t> all(n * n, 1);
  MaskOverlap o(n, n);
  EXPECT_FALSE(o.normalise(plane.data(), nullptr, n, nullptr, n));
  EXPECT_FALSE(o.normalise(plane.data(), all.data(), n, nullptr, n));
  EXPECT_FALSE(o.normalise(plane.data(), all.data(), n, all.data(), n));
  EXPECT_EQ(plane, before);
}

// plane(s) * O(0) / O(s) with O(s) = sum_x m_a(x) m_b(x + s) counted directly
// (circular); lags with under half of O(0)'s pairs hold the lowest value.
TEST(MaskOverlap, DividesByThePairCountAtEachLag) {
  const int n = 16;
  std::mt19937 rng(5);
  std::bernoulli_distribution use(0.8);
  std::uniform_real_distribution<float> uni(-1, 1);
  std::vector<std::uint8_t> ma(n * n), mb(n * n);
  for (auto& m : ma) m = use(rng);
  for (auto& m : mb) m = use(rng);
  ma[0] = 0;  // at least one unusable pixel
  std::vector<float> plane(n * n);
  for (float& v : plane) v = uni(rng);
  const std::vector<float> before = plane;
  MaskOverlap o(n, n);
  ASSERT_TRUE(o.normalise(plane.data(), ma.data(), n, mb.data(), n));
  auto pairs = [&](int dx, int dy) {
    int count = 0;
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) count += ma[y * n + x] && mb[((y + dy + n) % n) * n + (x + dx + n) % n];
    return count;
  };
  const double at_zero = pairs(0, 0);
  float lowest = 1e30f;
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c)
      if (pairs(correlation_lag_px(c, n), correlation_lag_px(r, n)) >= 0.5 * at_zero)
        lowest = std::min(lowest, plane[r * n + c]);
  int kept = 0;
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      const int p = pairs(correlation_lag_px(c, n), correlation_lag_px(r, n));
      const int i = r * n + c;
      if (p >= 0.5 * at_zero) {
        EXPECT_NEAR(plane[i], before[i] * at_zero / p, 1e-5) << c << " " << r;
        ++kept;
      } else {
        EXPECT_EQ(plane[i], lowest) << c << " " << r;
      }
    }
  EXPECT_GT(kept, 0);
}

// A 32 px window pair whose left 40 % is masked in both frames (as in the
// first pass at a mask's edge): the masks overlap best at lag 0, so the plain
// plane's peak is pulled towards zero displacement; divided by the overlap it
// is not. Mean error over 40 particle patterns (0.05 ppp, 2.5 px images),
// displacement (2.0, -1.0) px. Across the edge the masked plane is biased
// towards zero beyond the unmasked windows' own bias (pairs lost at the
// window's border, ~0.03 px); divided by the overlap it is unbiased, since the
// border there wraps onto masked pixels and is counted too. Along the edge
// the division changes nothing: the mask does not vary along it.
TEST(MaskOverlap, RemovesTheBiasOfAMaskEdge) {
  const int n = 32;
  const double du = 2.0, dv = -1.0;
  std::vector<std::uint8_t> mask(n * n, 1);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < 13; ++x) mask[y * n + x] = 0;
  double plain_u = 0, plain_v = 0, fixed_u = 0, fixed_v = 0, open_u = 0, open_v = 0;
  const int patterns = 40;
  MaskOverlap overlap(n, n);
  for (int k = 0; k < patterns; ++k) {
    ParticleImageOptions p;
    p.width_px = p.height_px = n;
    p.seed = 100 + k;
    const ParticleImagePair images = particle_image_pair(p, [&](double, double) { return std::array<double, 2>{du, dv}; });
    WindowCorrelator c(n);
    ASSERT_TRUE(c.correlate(images.a.ptr<float>(0), n, nullptr, images.b.ptr<float>(0), n, nullptr));
    const CorrelationPeak open = find_correlation_peak(c.plane(), n);
    ASSERT_TRUE(c.correlate(images.a.ptr<float>(0), n, mask.data(), images.b.ptr<float>(0), n, mask.data()));
    std::vector<float> plane(c.plane(), c.plane() + n * n);
    const CorrelationPeak plain = find_correlation_peak(plane.data(), n);
    ASSERT_TRUE(overlap.normalise(plane.data(), mask.data(), n, mask.data(), n));
    const CorrelationPeak fixed = find_correlation_peak(plane.data(), n);
    plain_u += (plain.u_px - du) / patterns;
    plain_v += (plain.v_px - dv) / patterns;
    fixed_u += (fixed.u_px - du) / patterns;
    fixed_v += (fixed.v_px - dv) / patterns;
    open_u += (open.u_px - du) / patterns;
    open_v += (open.v_px - dv) / patterns;
  }
  std::printf("mean error unmasked (%.4f, %.4f) px, masked (%.4f, %.4f) px, masked and divided by the overlap "
              "(%.4f, %.4f) px\n", open_u, open_v, plain_u, plain_v, fixed_u, fixed_v);
  EXPECT_LT(plain_u, -0.05);
  EXPECT_LT(plain_u, open_u - 0.015);
  EXPECT_LT(std::abs(fixed_u), 0.015);
  EXPECT_NEAR(fixed_v, plain_v, 0.002);
}

}  // namespace
}  // namespace glasspiv
