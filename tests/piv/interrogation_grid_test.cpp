#include "piv/interrogation_grid.h"

#include <stdexcept>

#include <gtest/gtest.h>

namespace glasspiv {
namespace {

// The worked example of the header.
TEST(InterrogationGrid, WorkedExample) {
  const InterrogationGrid g = interrogation_grid(1024, 768, 32, step_from_overlap(32, 0.5));
  EXPECT_EQ(g.step_px, 16);
  EXPECT_EQ(g.cols, 63);
  EXPECT_EQ(g.rows, 47);
  EXPECT_DOUBLE_EQ(g.x_px(0), 15.5);
  EXPECT_DOUBLE_EQ(g.x_px(62), 1007.5);
  EXPECT_DOUBLE_EQ(g.y_px(46), 751.5);
  EXPECT_EQ(g.left_px(62) + g.window_px, 1024);  // the last window ends on the last pixel
}

TEST(InterrogationGrid, LeftoverIsSplitSmallerHalfFirst) {
  const InterrogationGrid g = interrogation_grid(1000, 1000, 32, 16);
  EXPECT_EQ(g.cols, 61);
  EXPECT_EQ(g.left0_px, 4);
  EXPECT_DOUBLE_EQ(g.x_px(0), 19.5);
  EXPECT_LE(g.left_px(60) + 32, 1000);
}

TEST(InterrogationGrid, StepFromOverlap) {
  EXPECT_EQ(step_from_overlap(64, 0.5), 32);
  EXPECT_EQ(step_from_overlap(32, 0.75), 8);
  EXPECT_EQ(step_from_overlap(32, 0), 32);
  EXPECT_EQ(step_from_overlap(8, 0.9), 1);  // never below 1 px
  EXPECT_THROW(step_from_overlap(32, 1.0), std::invalid_argument);
  EXPECT_THROW(step_from_overlap(32, -0.1), std::invalid_argument);
}

TEST(InterrogationGrid, WindowLargerThanImageIsRefused) {
  EXPECT_THROW(interrogation_grid(31, 100, 32, 16), std::invalid_argument);
  const InterrogationGrid one = interrogation_grid(32, 32, 32, 16);
  EXPECT_EQ(one.size(), 1);
  EXPECT_DOUBLE_EQ(one.x_px(0), 15.5);  // the exact centre of a 32 px image
}

}  // namespace
}  // namespace glasspiv
