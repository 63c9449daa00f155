#include "correct/cell_mask.h"

#include <gtest/gtest.h>

#include <stdexcept>

namespace glasspiv {
namespace {

// A 1-pixel operator on a 6 x 1 grid with the per-cell figures set by hand.
CorrectionOperator hand_made(const std::vector<float>& pixels, const std::vector<float>& direct,
                             const std::vector<float>& weight) {
  CorrectionOperator op;
  op.width = op.height = 1;
  op.grid.cols = static_cast<int>(pixels.size());
  op.grid.rows = 1;
  op.grid.mm_per_px = 1;
  op.grid.s0_mm = -0.5 * (op.grid.cols - 1);
  op.pixel_offsets = {0, 0};
  op.background_weight = {0};
  op.cell_pixels = pixels;
  op.cell_direct_pixels = direct;
  finish_correction_operator(op);
  op.cell_weight = weight;
  return op;
}

TEST(CellMask, EachStateFromItsFigure) {
  // cells: inside a sphere, unseen, 0.1 px, reflections only, dim, valid
  const CorrectionOperator op =
      hand_made({1, 0, 0.1f, 1, 1, 1}, {1, 0, 0.1f, 0.1f, 1, 1}, {1, 0, 0.1f, 0.04f, 0.05f, 0.8f});
  TraceScene scene;
  scene.sheet.extent_s_mm = 6;
  scene.sheet.extent_t_mm = 1;
  scene.solids.push_back({Sphere{Eigen::Vector3d(op.grid.s_mm(0), 0, 0), 0.4}, TraceMaterial::glass(1.5)});
  const std::vector<CellState> s = classify_cells({{&op, 1.0}}, scene);
  ASSERT_EQ(s.size(), 6u);
  EXPECT_EQ(s[0], CellState::inside_solid);
  EXPECT_EQ(s[1], CellState::never_seen);
  EXPECT_EQ(s[2], CellState::few_pixels);
  EXPECT_EQ(s[3], CellState::mostly_reflected);
  EXPECT_EQ(s[4], CellState::low_weight);
  EXPECT_EQ(s[5], CellState::valid);
  const CellCounts n = count_cells(s);
  EXPECT_EQ(n.fluid(), 5u);
  EXPECT_DOUBLE_EQ(n.valid_fraction_of_fluid(), 0.2);
  EXPECT_DOUBLE_EQ(n.valid_fraction_of_seen(), 0.5);
  // Thresholds are the user's: none at all leaves only geometry.
  MaskOptions none;
  none.min_pixels_per_cell = 0;
  none.min_mean_weight = 0;
  const std::vector<CellState> t = classify_cells({{&op, 1.0}}, scene, none);
  EXPECT_EQ(t[2], CellState::valid);
  EXPECT_EQ(t[3], CellState::valid);
  EXPECT_EQ(t[4], CellState::valid);
}

// A second camera's direct view makes a cell the first sees only in a reflection valid.
TEST(CellMask, CamerasAddUp) {
  const CorrectionOperator a = hand_made({1}, {0}, {0.04f}), b = hand_made({1}, {1}, {0.9f});
  TraceScene scene;
  EXPECT_EQ(classify_cells({{&a, 1.0}}, scene)[0], CellState::mostly_reflected);
  EXPECT_EQ(classify_cells({{&a, 1.0}, {&b, 1.0}}, scene)[0], CellState::valid);
  EXPECT_EQ(classify_cells({{&a, 1.0}, {&b, 0.0}}, scene)[0], CellState::mostly_reflected);
}

// Camera weights weigh the data, never the mask: equal small weights (or any
// positive ones) give the mask of weight 1; only 0 leaves a camera out.
TEST(CellMask, WeightsDoNotScaleTheMask) {
  const CorrectionOperator a = hand_made({1}, {1}, {0.9f}), b = hand_made({1}, {0.2f}, {0.9f});
  TraceScene scene;
  const std::vector<CellState> unit = classify_cells({{&a, 1.0}, {&b, 1.0}}, scene);
  ASSERT_EQ(unit[0], CellState::valid);
  EXPECT_EQ(classify_cells({{&a, 1e-4}, {&b, 1e-4}}, scene), unit);
  EXPECT_EQ(classify_cells({{&a, 3.0}, {&b, 1e-6}}, scene), unit);
  EXPECT_EQ(classify_cells({{&a, 1e-4}}, scene), classify_cells({{&a, 1.0}}, scene));
  const CorrectionOperator faint = hand_made({0.3f}, {0.3f}, {0.9f});
  EXPECT_EQ(classify_cells({{&faint, 1.0}}, scene)[0], CellState::valid);
  EXPECT_EQ(classify_cells({{&faint, 0.5}}, scene)[0], CellState::valid);
}

TEST(CellMask, RefusesMixedGridsAndBadThresholds) {
  const CorrectionOperator a = hand_made({1}, {1}, {1}), b = hand_made({1, 1}, {1, 1}, {1, 1});
  TraceScene scene;
  EXPECT_THROW(classify_cells({}, scene), std::invalid_argument);
  EXPECT_THROW(classify_cells({{&a, 1.0}, {&b, 1.0}}, scene), std::invalid_argument);
  MaskOptions bad;
  bad.min_mean_weight = std::nan("");
  EXPECT_THROW(classify_cells({{&a, 1.0}}, scene, bad), std::invalid_argument);
  EXPECT_THROW(classify_cells({{&a, -1.0}}, scene), std::invalid_argument);
}

}  // namespace
}  // namespace glasspiv
