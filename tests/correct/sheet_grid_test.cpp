#include "correct/sheet_grid.h"

#include <gtest/gtest.h>

#include <stdexcept>

#include "render/sheet_texture.h"

namespace glasspiv {
namespace {

SheetPlane sheet(double es, double et) {
  SheetPlane p;
  p.extent_s_mm = es;
  p.extent_t_mm = et;
  return p;
}

TEST(SheetGrid, CoversTheExtentCentredOnTheOrigin) {
  const SheetGrid g = sheet_grid_covering(sheet(130, 100), 0.5);
  EXPECT_EQ(g.cols, 260);
  EXPECT_EQ(g.rows, 200);
  EXPECT_DOUBLE_EQ(g.s_mm(0) + g.s_mm(g.cols - 1), 0.0);
  EXPECT_DOUBLE_EQ(g.t_mm(0) + g.t_mm(g.rows - 1), 0.0);
  EXPECT_GT(g.t_mm(0), 0.0);  // row 0 at the top: t is up
  EXPECT_DOUBLE_EQ(g.col(g.s_mm(17.25)), 17.25);
  EXPECT_DOUBLE_EQ(g.row(g.t_mm(3.5)), 3.5);
  // Rounded up: 130 / 0.3 = 433.3 cells.
  EXPECT_EQ(sheet_grid_covering(sheet(130, 130), 0.3).cols, 434);
}

// The grid and a SheetTexture of the same size and pitch lie on the same cells:
// a texture read at a cell centre returns that cell's value.
TEST(SheetGrid, SamePlacementAsASheetTexture) {
  const SheetGrid g = sheet_grid_covering(sheet(7, 5), 1.0);
  std::vector<float> v(g.cell_count());
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = static_cast<float>(i);
  const SheetTexture tex(v.data(), g.rows, g.cols, g.mm_per_px);
  for (int r = 0; r < g.rows; ++r)
    for (int c = 0; c < g.cols; ++c) EXPECT_FLOAT_EQ(tex.at(g.s_mm(c), g.t_mm(r)), v[static_cast<std::size_t>(r) * g.cols + c]);
}

TEST(SheetGrid, PlacementInTheWorld) {
  SheetPlane p = sheet(4, 2);
  p.origin_mm = Eigen::Vector3d(1, 2, 3);
  p.s_axis = -Eigen::Vector3d::UnitX();
  const SheetGrid g = sheet_grid_covering(p, 1.0);
  const SheetGridPlacement w = sheet_grid_placement(g, p);
  EXPECT_TRUE(w.cell00_centre_mm.isApprox(Eigen::Vector3d(1 + 1.5, 2 + 0.5, 3)));
  EXPECT_TRUE(w.col_step_mm.isApprox(Eigen::Vector3d(-1, 0, 0)));
  EXPECT_TRUE(w.row_step_mm.isApprox(Eigen::Vector3d(0, -1, 0)));
}

TEST(SheetGrid, RefusesBadPitchAndTooManyCells) {
  EXPECT_THROW(sheet_grid_covering(sheet(10, 10), 0), std::invalid_argument);
  EXPECT_THROW(sheet_grid_covering(sheet(10, 10), -1), std::invalid_argument);
  EXPECT_THROW(sheet_grid_covering(sheet(10, 10), std::nan("")), std::invalid_argument);
  EXPECT_THROW(sheet_grid_covering(sheet(1e6, 1e6), 1e-3), std::invalid_argument);
}

}  // namespace
}  // namespace glasspiv
