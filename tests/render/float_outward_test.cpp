#include "render/float_outward.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace glasspiv {
namespace {

// Same float to the bit (NaN: both NaN).
void expect_same(float got, float expected, double x) {
  if (std::isnan(expected)) {
    EXPECT_TRUE(std::isnan(got)) << x;
    return;
  }
  std::uint32_t a, b;
  std::memcpy(&a, &got, sizeof a);
  std::memcpy(&b, &expected, sizeof b);
  EXPECT_EQ(a, b) << x;
}

// float_up and float_down are std::nextafter(float(x), +-infinity) to the bit:
// zeros of both signs, the smallest subnormals, the largest finite floats,
// infinities, NaN, and random doubles of every sign and magnitude from 1e-40
// to 1e40 (beyond float's range both ways).
TEST(FloatOutward, EqualsNextafterOfTheRoundedValueToTheBit) {
  constexpr float inf = std::numeric_limits<float>::infinity();
  const float tiny = std::numeric_limits<float>::denorm_min(), big = std::numeric_limits<float>::max();
  std::vector<double> xs = {0.0, -0.0, tiny, -tiny, big, -big, 1e39, -1e39, inf, -inf,
                            std::numeric_limits<double>::quiet_NaN(), 1.0, -1.0, 600.0, 1e-3};
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> exponent(-40, 40), sign(-1, 1);
  for (int i = 0; i < 100000; ++i) xs.push_back(std::copysign(std::pow(10.0, exponent(rng)), sign(rng)));
  for (double x : xs) {
    const float f = static_cast<float>(x);
    expect_same(float_up(x), std::nextafter(f, inf), x);
    expect_same(float_down(x), std::nextafter(f, -inf), x);
  }
}

}  // namespace
}  // namespace glasspiv
