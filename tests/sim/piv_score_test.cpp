// A PIV field scored against a simulated truth (sim/piv_score.h): the sheet
// truth's bilinear lookup reproduces a linear displacement field exactly (to
// rounding), refuses cells next to a solid and respects the usable mask; the
// camera truth follows the vector index; the score is the RMS and the largest
// |measured - true| over the vectors not invalid with a truth.
#include "sim/piv_score.h"

#include <gtest/gtest.h>

#include <cmath>

namespace glasspiv {
namespace {

// A 4 x 3 field of 16 px windows at 8 px steps, every vector (1, -2) px.
PivField field() {
  PivField f;
  f.grid.window_px = 16;
  f.grid.step_px = 8;
  f.grid.cols = 4;
  f.grid.rows = 3;
  f.u_px.assign(12, 1.0);
  f.v_px.assign(12, -2.0);
  f.flags.assign(12, VectorFlag::valid);
  f.peak_ratio.assign(12, 2.0);
  return f;
}

// A sheet truth on a grid of 1 mm cells, 20 x 20, linear in s and t.
SheetTruth linear_truth() {
  SheetTruth t;
  t.grid.cols = t.grid.rows = 20;
  t.grid.mm_per_px = 1;
  t.grid.s0_mm = -9.5;
  t.grid.t0_mm = 9.5;
  for (int r = 0; r < 20; ++r)
    for (int c = 0; c < 20; ++c) {
      const double s = t.grid.s_mm(c), tt = t.grid.t_mm(r);
      t.ds_mm.push_back(0.1 + 0.01 * s - 0.02 * tt);
      t.dt_mm.push_back(-0.05 + 0.03 * s + 0.004 * tt);
    }
  return t;
}

TEST(PivScore, SheetTruthBilinearIsExactForALinearField) {
  const SheetTruth truth = linear_truth();
  SheetGrid grid;  // the evaluation grid: 0.25 mm cells, not aligned with the truth's
  grid.cols = grid.rows = 40;
  grid.mm_per_px = 0.25;
  grid.s0_mm = -4.9;
  grid.t0_mm = 4.7;
  const PivField f = field();
  const std::vector<Eigen::Vector2d> px = sheet_truth_on_vectors(f, grid, truth);
  ASSERT_EQ(px.size(), f.size());
  for (std::size_t i = 0; i < f.size(); ++i) {
    const double s = grid.s_mm(f.x_px(i)), t = grid.t_mm(f.y_px(i));
    const double ds = 0.1 + 0.01 * s - 0.02 * t, dt = -0.05 + 0.03 * s + 0.004 * t;
    // Column along +s, row along -t, in grid px.
    EXPECT_NEAR(px[i].x(), ds / 0.25, 1e-12) << i;
    EXPECT_NEAR(px[i].y(), -dt / 0.25, 1e-12) << i;
  }
}

TEST(PivScore, SheetTruthRefusesSolidsOffGridAndMaskedCentres) {
  SheetTruth truth = linear_truth();
  SheetGrid grid = truth.grid;  // the same grid: window centres at cells 7.5 + 8k, 7.5 + 8k
  const PivField f = field();
  // A solid's cell next to vector 0's centre (7.5, 7.5): cell (8, 8).
  truth.ds_mm[8 * 20 + 8] = NAN;
  cv::Mat usable(20, 20, CV_8U, cv::Scalar(255));
  usable.at<std::uint8_t>(8, 16) = 0;  // vector 1's centre (15.5, 7.5) rounds to (16, 8)
  const std::vector<Eigen::Vector2d> px = sheet_truth_on_vectors(f, grid, truth, usable);
  EXPECT_FALSE(px[0].allFinite());
  EXPECT_FALSE(px[1].allFinite());
  EXPECT_TRUE(px[4].allFinite());
  // Vectors 2 and 3 (x = 23.5, 31.5) lie off the 20-cell truth.
  EXPECT_FALSE(px[2].allFinite());
  EXPECT_FALSE(px[3].allFinite());
}

TEST(PivScore, CameraTruthAndTheScore) {
  PivField f = field();
  CameraTruth truth;
  for (int i = 0; i < 12; ++i) {
    truth.u_px.push_back(1.0 + (i == 5 ? 0.3 : 0.0));  // vector 5 off by 0.3 along u
    truth.v_px.push_back(i == 7 ? NAN : -2.0);         // vector 7 without truth
  }
  f.flags[9] = VectorFlag::invalid;  // never scored
  f.u_px[9] = f.v_px[9] = NAN;
  f.u_px[10] += 0.4;  // off by 0.4 along u
  const std::vector<Eigen::Vector2d> px = camera_truth_on_vectors(f, truth);
  EXPECT_FALSE(px[7].allFinite());
  std::vector<bool> scored;
  Eigen::Vector2d mean;
  GridValues errors;
  const PivScore s = score_vectors(f, px, &errors, nullptr, &scored, &mean);
  EXPECT_EQ(s.vectors, 10);
  EXPECT_NEAR(s.rms_px, std::sqrt((0.3 * 0.3 + 0.4 * 0.4) / 10), 1e-12);
  EXPECT_NEAR(s.max_px, 0.4, 1e-12);
  EXPECT_FALSE(scored[7]);
  EXPECT_FALSE(scored[9]);
  EXPECT_TRUE(scored[5]);
  EXPECT_NEAR(mean.x(), 1.04, 1e-12);
  EXPECT_EQ(errors.grid.cols, 4);
  EXPECT_EQ(errors.grid.step_x_px, 8);

  // A mask at the window centres and "only" both restrict the score.
  cv::Mat usable(40, 40, CV_8U, cv::Scalar(255));
  usable.at<std::uint8_t>(24, 24) = 0;  // vector 10's centre (23.5, 23.5)
  const PivScore m = score_vectors(f, camera_truth_on_vectors(f, truth, usable));
  EXPECT_EQ(m.vectors, 9);
  EXPECT_NEAR(m.max_px, 0.3, 1e-12);
  std::vector<bool> only(12, false);
  only[5] = true;
  EXPECT_EQ(score_vectors(f, px, nullptr, &only).vectors, 1);
  // No vector scored: no figure, not zero.
  only.assign(12, false);
  const PivScore none = score_vectors(f, px, nullptr, &only);
  EXPECT_EQ(none.vectors, 0);
  EXPECT_TRUE(std::isnan(none.rms_px));
}

}  // namespace
}  // namespace glasspiv
