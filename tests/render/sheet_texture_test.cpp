// Sheet texture: placement and bilinear point samples, and the footprint
// filter: exact means of linear pictures, no aliasing of fine patterns under
// strong minification, bounded work via the mip pyramid.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "render/sheet_texture.h"

namespace glasspiv {
namespace {

TEST(SheetTexture, PointSamplesAreBilinearAndCentred) {
  const std::vector<float> v = {0, 1, 2, 3, 4, 5};  // 2 rows x 3 cols
  const SheetTexture tex(v.data(), 2, 3, 2.0);
  EXPECT_FLOAT_EQ(tex.at(0, 0), 2.5f);     // centre of the picture: mean of the 4 middle texels
  EXPECT_FLOAT_EQ(tex.at(-2, 1), 0.0f);    // column 0, row 0 (t up: row 0 is at t = +1 mm)
  EXPECT_FLOAT_EQ(tex.at(2, -1), 5.0f);    // column 2, row 1
  EXPECT_FLOAT_EQ(tex.at(100, 0), 0.0f);   // outside: dark
  EXPECT_FLOAT_EQ(tex.at(3, -1), 2.5f);    // half a texel past the last column: blends with the dark border
}

TEST(SheetTexture, PyramidGoesDownToOneTexel) {
  const std::vector<float> v(37 * 20, 1.0f);
  const SheetTexture tex(v.data(), 37, 20, 0.1);
  EXPECT_EQ(tex.levels(), 7);  // 37x20, 19x10, 10x5, 5x3, 3x2, 2x1, 1x1
}

// A linear picture's mean over a centrally symmetric footprint is its value at
// the centre, at every mip level (a box filter of a linear function is exact),
// for any footprint shape: anisotropic, rotated, sheared, tiny or huge.
TEST(SheetTexture, FootprintMeanOfALinearPictureIsTheCentreValue) {
  const int rows = 512, cols = 512;
  std::vector<float> v(static_cast<std::size_t>(rows) * cols);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) v[static_cast<std::size_t>(r) * cols + c] = 0.25f * c - 0.125f * r + 1000.0f;
  const double mm = 0.05;
  const SheetTexture tex(v.data(), rows, cols, mm);
  const std::vector<Eigen::Matrix2d> footprints = [] {
    std::vector<Eigen::Matrix2d> f;
    Eigen::Matrix2d j;
    j << 0.01, 0, 0, 0.01;  // magnified: 0.2 texel
    f.push_back(j);
    j << 0.3, 0.1, -0.05, 0.2;  // a few texels, sheared
    f.push_back(j);
    j << 3.0, 0.0, 0.0, 0.05;  // 60 x 1 texels: strongly anisotropic, mip level 3
    f.push_back(j);
    j << 2.0, -1.5, 1.5, 2.0;  // rotated, 50 texels
    f.push_back(j);
    return f;
  }();
  for (const Eigen::Matrix2d& j : footprints) {
    for (double s : {-3.0, 0.0, 2.7}) {
      for (double t : {-1.9, 0.4}) {
        const double col = s / mm + 0.5 * (cols - 1), row = -t / mm + 0.5 * (rows - 1);
        const double expected = 0.25 * col - 0.125 * row + 1000.0;
        // Float texels (1000 + ~100: ulp 6e-5) and float accumulation in the pyramid.
        EXPECT_NEAR(tex.average(s, t, j), expected, 2e-3) << j << " at " << s << ", " << t;
      }
    }
  }
}

// A 1-texel checkerboard seen through a footprint of 40 x 25 texels: a point
// sample reads 0 or 1 (aliasing); the footprint mean is 1/2.
TEST(SheetTexture, MinifiedFinePatternAveragesInsteadOfAliasing) {
  const int n = 1024;
  std::vector<float> v(static_cast<std::size_t>(n) * n);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) v[static_cast<std::size_t>(r) * n + c] = static_cast<float>((r + c) % 2);
  const SheetTexture tex(v.data(), n, n, 0.01);
  Eigen::Matrix2d j;
  j << 0.4, 0.05, -0.03, 0.25;
  double worst = 0;
  for (int i = 0; i < 200; ++i) {
    const double s = -2.0 + 0.0213 * i, t = 1.5 - 0.0171 * i;
    worst = std::max(worst, std::abs(tex.average(s, t, j) - 0.5));
  }
  // Residual: the parallelogram cuts partial checker cells at its border (a
  // fraction ~1/(40 x 25) of its area), plus the mip level's box blur.
  EXPECT_LT(worst, 0.02);
  // The point samples alias: they read whole cells.
  EXPECT_GT(std::abs(tex.at(0.005, 0.005) - 0.5), 0.4);  // a texel centre
}

TEST(SheetTexture, RejectsBadInput) {
  const std::vector<float> v = {1};
  EXPECT_THROW(SheetTexture(v.data(), 0, 1, 1.0), std::invalid_argument);
  EXPECT_THROW(SheetTexture(v.data(), 1, 1, 0.0), std::invalid_argument);
  EXPECT_THROW(SheetTexture(v.data(), 1, 1, std::nan("")), std::invalid_argument);
}

}  // namespace
}  // namespace glasspiv
