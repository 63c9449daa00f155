#include "correct/sheet_grid.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include <yaml-cpp/yaml.h>

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

// sheet_grid.yaml reads back as written, whatever the scene's path holds
// ('#' starts a comment, ': ' a mapping, a newline a new key in plain YAML).
TEST(SheetGrid, YamlReadsBackAnyScenePathAndTheNumbers) {
  SheetPlane p = sheet(130, 100);
  p.origin_mm = Eigen::Vector3d(1, 2, 3);
  p.s_axis = Eigen::Vector3d(-1, 0, 0);
  p.t_axis = Eigen::Vector3d(0, 1, 0);
  const SheetGrid g = sheet_grid_covering(p, 0.3485);
  for (const std::string path : {"Experiment #3/reactor.yaml", "a: b/scene.yaml", "x\ny: 1/s.yaml", "'q\"/s.yaml",
                                 "- [x] {y}/s.yaml", " lead/trail.yaml ", "plain/scene.yaml"}) {
    const YAML::Node n = YAML::Load(sheet_grid_yaml(g, p, path));
    EXPECT_EQ(n["scene"].as<std::string>(), path);
    EXPECT_EQ(n["glasspiv_sheet_grid"].as<int>(), 1);
    EXPECT_EQ(n["cols"].as<int>(), g.cols);
    EXPECT_EQ(n["rows"].as<int>(), g.rows);
    EXPECT_EQ(n["mm_per_px"].as<double>(), g.mm_per_px);
    EXPECT_EQ(n["s0_mm"].as<double>(), g.s0_mm);
    EXPECT_EQ(n["t0_mm"].as<double>(), g.t0_mm);
    const SheetGridPlacement w = sheet_grid_placement(g, p);
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(n["cell00_centre_mm"][k].as<double>(), w.cell00_centre_mm[k]);
      EXPECT_EQ(n["col_step_mm"][k].as<double>(), w.col_step_mm[k]);
      EXPECT_EQ(n["row_step_mm"][k].as<double>(), w.row_step_mm[k]);
    }
  }
}

}  // namespace
}  // namespace glasspiv
