#include "piv/frame_deformation.h"

#include <cmath>

#include <gtest/gtest.h>

#include "piv/particle_images.h"

namespace glasspiv {
namespace {

// Resampling a particle image by a uniform sub-pixel shift against rendering
// it there: the interpolation's RMS error relative to the image's RMS, per
// kind. Measured: bilinear 0.24, Keys 0.15, cubic B-spline 0.10, quintic
// 0.086 (2.5 px particles are barely sampled); the order is what is required.
TEST(FrameDeformation, ShiftedParticlesMatchARenderAtTheShiftedPlace) {
  ParticleImageOptions po;
  po.width_px = po.height_px = 96;
  const double du = 0.6, dv = -0.3;  // B relative to A
  const ParticleImagePair p = particle_image_pair(po, [&](double, double) { return std::array<double, 2>{du, dv}; });
  const cv::Mat u(96, 96, CV_32F, cv::Scalar(du)), v(96, 96, CV_32F, cv::Scalar(dv));
  double rms[4];
  for (int k = 0; k < 4; ++k) {
    // B sampled at x + d matches A.
    const DeformedFrame d = deform_frame(p.b, cv::Mat(), u, v, 1.0, static_cast<DeformInterpolation>(k), 2);
    double s2 = 0, s2ref = 0;
    int n = 0;
    for (int y = 8; y < 88; ++y)
      for (int x = 8; x < 88; ++x) {
        ASSERT_EQ(d.usable.at<std::uint8_t>(y, x), 1);
        const double e = d.values.at<float>(y, x) - p.a.at<float>(y, x);
        s2 += e * e;
        s2ref += p.a.at<float>(y, x) * p.a.at<float>(y, x);
        ++n;
      }
    rms[k] = std::sqrt(s2 / s2ref);
  }
  std::printf("relative RMS resampling error: bilinear %.4f, Keys %.4f, B-spline 3 %.4f, B-spline 5 %.4f\n", rms[0],
              rms[1], rms[2], rms[3]);
  EXPECT_LT(rms[3], rms[2]);
  EXPECT_LT(rms[2], rms[1]);
  EXPECT_LT(rms[1], rms[0]);
  EXPECT_LT(rms[3], 0.1);
}

// Zero displacement reproduces the frame (the B-splines interpolate).
TEST(FrameDeformation, ZeroFieldIsIdentity) {
  cv::Mat f(20, 30, CV_32F);
  cv::randu(f, 0.0, 1.0);
  const cv::Mat zero = cv::Mat::zeros(20, 30, CV_32F);
  for (int k = 0; k < 4; ++k) {
    const DeformedFrame d = deform_frame(f, cv::Mat(), zero, zero, 0.5, static_cast<DeformInterpolation>(k), 1);
    EXPECT_LT(cv::norm(d.values - f, cv::NORM_INF), 2e-5) << k;
    EXPECT_EQ(cv::countNonZero(d.usable), 600) << k;
  }
}

// Samples from outside the frame or on unusable pixels are unusable.
TEST(FrameDeformation, UnusableWhereTapsLeaveTheFrameOrHitTheMask) {
  cv::Mat f(20, 20, CV_32F, cv::Scalar(1)), usable(20, 20, CV_8U, cv::Scalar(1));
  usable.at<std::uint8_t>(10, 10) = 0;
  const cv::Mat u(20, 20, CV_32F, cv::Scalar(2.5f)), v = cv::Mat::zeros(20, 20, CV_32F);
  const DeformedFrame d = deform_frame(f, usable, u, v, 1.0, DeformInterpolation::bilinear, 1);
  EXPECT_EQ(d.usable.at<std::uint8_t>(5, 16), 1);   // samples x = 18.5
  EXPECT_EQ(d.usable.at<std::uint8_t>(5, 17), 0);   // x = 19.5, beyond the last pixel centre
  EXPECT_EQ(d.usable.at<std::uint8_t>(10, 7), 0);   // taps 9, 10 with (10, 10) masked
  EXPECT_EQ(d.usable.at<std::uint8_t>(10, 8), 0);   // taps 10, 11
  EXPECT_EQ(d.usable.at<std::uint8_t>(10, 6), 1);   // taps 8, 9
}

// The grid field is interpolated bilinearly and carried on linearly past the outer centres.
TEST(FrameDeformation, GridFieldIsLinearInALinearField) {
  const InterrogationGrid g = interrogation_grid(128, 96, 32, 16);
  std::vector<double> field;
  for (int r = 0; r < g.rows; ++r)
    for (int c = 0; c < g.cols; ++c) field.push_back(0.1 * g.x_px(c) - 0.05 * g.y_px(r) + 1);
  for (double x : {0.0, 7.25, 60.0, 127.0})
    for (double y : {0.0, 33.0, 95.0}) EXPECT_NEAR(grid_field_at(g, field, x, y), 0.1 * x - 0.05 * y + 1, 1e-12);
  const cv::Mat dense = dense_field(g, field, 128, 96);
  EXPECT_NEAR(dense.at<float>(95, 0), -0.05 * 95 + 1, 1e-5);
}

}  // namespace
}  // namespace glasspiv
