// sim/random_variates.h: the moments of each draw within tolerances from the
// sample size, the engine's standard-fixed bits, reproducibility.
#include "sim/random_variates.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

namespace glasspiv {
namespace {

struct Moments {
  double mean = 0, variance = 0;
};

template <class Draw>
Moments moments(int n, Draw draw) {
  std::vector<double> x(static_cast<std::size_t>(n));
  double sum = 0;
  for (double& v : x) sum += (v = draw());
  Moments m;
  m.mean = sum / n;
  for (double v : x) m.variance += (v - m.mean) * (v - m.mean);
  m.variance /= n - 1;
  return m;
}

// The C++ standard fixes the 10000th output of a default-seeded mt19937_64
// (9981545732273789042); uniform01 keeps its top 53 bits, on every platform.
TEST(RandomVariates, UniformIsTheEnginesTopBits) {
  RandomVariates random(5489u);
  double u = 0;
  for (int i = 0; i < 10000; ++i) u = random.uniform01();
  EXPECT_EQ(u, static_cast<double>(9981545732273789042ull >> 11) * 0x1.0p-53);
}

// Tolerances: 4 standard errors. Mean: sqrt(var / n). Variance: sqrt((mu4 - var^2) / n),
// mu4 = var^2 * 9/5 (uniform), 3 var^2 (normal), lambda (1 + 3 lambda) (Poisson).
TEST(RandomVariates, MomentsMatch) {
  const int n = 200000;
  RandomVariates random(11);
  const Moments u = moments(n, [&] { return random.uniform01(); });
  EXPECT_NEAR(u.mean, 0.5, 4 * std::sqrt(1.0 / 12 / n));
  EXPECT_NEAR(u.variance, 1.0 / 12, 4 * std::sqrt((9.0 / 5 - 1) / 144 / n));
  const Moments g = moments(n, [&] { return random.normal(); });
  EXPECT_NEAR(g.mean, 0, 4 * std::sqrt(1.0 / n));
  EXPECT_NEAR(g.variance, 1, 4 * std::sqrt(2.0 / n));
  // Both Poisson branches (Knuth below 10, PTRS above) and a large mean.
  for (double lambda : {0.3, 4.0, 9.9, 10.0, 37.5, 1e4}) {
    const Moments p = moments(n, [&] { return static_cast<double>(random.poisson(lambda)); });
    EXPECT_NEAR(p.mean, lambda, 4 * std::sqrt(lambda / n)) << lambda;
    EXPECT_NEAR(p.variance, lambda, 4 * std::sqrt((lambda * (1 + 3 * lambda) - lambda * lambda) / n)) << lambda;
  }
}

// The Poisson probabilities themselves at mean 37.5 (PTRS): P(k) for k near the
// mode within 4 binomial standard errors sqrt(P (1 - P) / n).
TEST(RandomVariates, PoissonProbabilitiesMatch) {
  const int n = 400000;
  const double lambda = 37.5;
  RandomVariates random(5);
  std::vector<int> histogram(200, 0);
  for (int i = 0; i < n; ++i) ++histogram[std::min<std::uint64_t>(random.poisson(lambda), 199)];
  for (int k = 25; k <= 50; ++k) {
    const double p = std::exp(-lambda + k * std::log(lambda) - std::lgamma(k + 1.0));
    EXPECT_NEAR(histogram[static_cast<std::size_t>(k)] / double(n), p, 4 * std::sqrt(p * (1 - p) / n)) << k;
  }
  EXPECT_EQ(RandomVariates(1).poisson(0), 0u);
  EXPECT_THROW(RandomVariates(1).poisson(-1), std::invalid_argument);
}

TEST(RandomVariates, SameSeedSameDrawsOtherSeedOthers) {
  RandomVariates a(42), b(42), c(43);
  bool differs = false;
  for (int i = 0; i < 100; ++i) {
    const double x = a.normal(), y = b.normal(), z = c.normal();
    EXPECT_EQ(x, y);
    differs = differs || x != z;
  }
  EXPECT_TRUE(differs);
}

}  // namespace
}  // namespace glasspiv
