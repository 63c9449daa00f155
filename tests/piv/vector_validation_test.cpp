#include "piv/vector_validation.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

namespace glasspiv {
namespace {

struct Field {
  int cols = 10, rows = 8;
  std::vector<double> u, v;
  std::vector<VectorFlag> flags;
};

// A smooth field (a gradient of 0.05 px per vector plus 0.02 px noise, the
// random error of a good evaluation).
Field smooth_field(unsigned seed) {
  Field f;
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, 0.02);
  for (int r = 0; r < f.rows; ++r)
    for (int c = 0; c < f.cols; ++c) {
      f.u.push_back(1 + 0.05 * r + noise(rng));
      f.v.push_back(-0.5 + 0.04 * c + noise(rng));
      f.flags.push_back(VectorFlag::valid);
    }
  return f;
}

TEST(NormalisedMedianTest, SmoothFieldHasNoOutliers) {
  Field f = smooth_field(1);
  const MedianTestCounts n = normalised_median_test(f.cols, f.rows, f.u, f.v, f.flags);
  EXPECT_EQ(n.outliers, 0);  // the border vectors of the gradient included
}

// A planted outlier is found and replaced by the median of its neighbours.
TEST(NormalisedMedianTest, PlantedOutlierIsReplaced) {
  for (int at : {3 * 10 + 4, 0, 9, 7 * 10 + 5}) {  // interior, corners, border
    Field f = smooth_field(2);
    const double truth_u = f.u[at], truth_v = f.v[at];
    f.u[at] += 3.0;
    f.v[at] -= 1.0;
    const MedianTestCounts n = normalised_median_test(f.cols, f.rows, f.u, f.v, f.flags);
    EXPECT_EQ(n.outliers, 1) << at;
    EXPECT_EQ(n.replaced, 1) << at;
    EXPECT_EQ(f.flags[at], VectorFlag::replaced) << at;
    // The median of neighbours up to two grid steps (0.1 / 0.08 px) away in the gradient.
    EXPECT_NEAR(f.u[at], truth_u, 0.12) << at;
    EXPECT_NEAR(f.v[at], truth_v, 0.1) << at;
    for (std::size_t i = 0; i < f.flags.size(); ++i) {
      if (static_cast<int>(i) == at) continue;
      EXPECT_EQ(f.flags[i], VectorFlag::valid);
    }
  }
}

// Invalid vectors are neither tested nor used; their values do not matter.
TEST(NormalisedMedianTest, InvalidNeighboursAreIgnored) {
  Field f = smooth_field(3);
  const int at = 4 * 10 + 4;
  for (int j : {at - 1, at + 1, at - 10}) {
    f.flags[j] = VectorFlag::invalid;
    f.u[j] = f.v[j] = std::nan("");
  }
  const MedianTestCounts n = normalised_median_test(f.cols, f.rows, f.u, f.v, f.flags);
  EXPECT_EQ(n.outliers, 0);
  EXPECT_EQ(f.flags[at - 1], VectorFlag::invalid);
}

// An outlier whose neighbours are all outliers too has nothing to be replaced by.
TEST(NormalisedMedianTest, OutlierWithoutGoodNeighboursBecomesInvalid) {
  Field f;
  f.cols = f.rows = 3;
  f.u = {0, 0, 0, 0, 9, 0, 0, 0, 0};
  f.v.assign(9, 0);
  f.flags.assign(9, VectorFlag::valid);
  for (int j : {0, 1, 2, 3, 5, 6, 7}) f.flags[j] = VectorFlag::invalid;  // only 8 and the centre left
  MedianTestOptions o;
  o.min_neighbours = 1;
  const MedianTestCounts n = normalised_median_test(f.cols, f.rows, f.u, f.v, f.flags, o);
  // Both are tested against each other: each fails, neither can replace the other.
  EXPECT_EQ(n.outliers, 2);
  EXPECT_EQ(n.unreplaceable, 2);
  EXPECT_EQ(f.flags[4], VectorFlag::invalid);
  EXPECT_TRUE(std::isnan(f.u[4]));
}

// A strong gradient (0.5 px per vector, a vortex core's on the demo's grid)
// next to a masked region: the vectors at the mask's edge see one side only.
// The paper's test flags good vectors there and replaces them a grid step's
// change away; following the gradient it flags none, and a planted outlier on
// the edge is replaced by the field's own value.
TEST(NormalisedMedianTest, FollowsTheGradientAtAMasksEdge) {
  auto sheared = [](unsigned seed) {
    Field f;
    f.cols = f.rows = 12;
    std::mt19937 rng(seed);
    std::normal_distribution<double> noise(0, 0.02);
    for (int r = 0; r < f.rows; ++r)
      for (int c = 0; c < f.cols; ++c) {
        const bool masked = c < 4 || (c < 7 && r < 5);  // an L-shaped mask
        f.u.push_back(masked ? std::nan("") : 0.5 * r + noise(rng));
        f.v.push_back(masked ? std::nan("") : -0.3 * c + 0.2 * r + noise(rng));
        f.flags.push_back(masked ? VectorFlag::invalid : VectorFlag::valid);
      }
    return f;
  };
  int paper_outliers = 0;
  for (unsigned seed = 1; seed <= 5; ++seed) {
    Field paper = sheared(seed), followed = sheared(seed);
    MedianTestOptions o;
    o.follow_gradient = false;
    paper_outliers += normalised_median_test(paper.cols, paper.rows, paper.u, paper.v, paper.flags, o).outliers;
    EXPECT_EQ(normalised_median_test(followed.cols, followed.rows, followed.u, followed.v, followed.flags).outliers, 0)
        << seed;
  }
  EXPECT_GT(paper_outliers, 5);  // what following the gradient avoids

  Field f = sheared(9);
  const int at = 8 * 12 + 4;  // on the mask's straight edge: five neighbours
  const double truth_u = 0.5 * 8, truth_v = -0.3 * 4 + 0.2 * 8;
  f.u[at] += 2.0;
  const MedianTestCounts n = normalised_median_test(f.cols, f.rows, f.u, f.v, f.flags);
  EXPECT_EQ(n.outliers, 1);
  EXPECT_EQ(f.flags[at], VectorFlag::replaced);
  for (std::size_t i = 0; i < f.flags.size(); ++i)
    if (static_cast<int>(i) != at) {
      EXPECT_NE(f.flags[i], VectorFlag::replaced) << i;
    }
  EXPECT_NEAR(f.u[at], truth_u, 0.05);  // the neighbours' noise, not a grid step (0.5 px)
  EXPECT_NEAR(f.v[at], truth_v, 0.05);
}

}  // namespace
}  // namespace glasspiv
