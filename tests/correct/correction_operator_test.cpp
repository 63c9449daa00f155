#include "correct/correction_operator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "render/forward_render.h"
#include "tests/correct/test_scenes.h"

namespace glasspiv {
namespace {

std::vector<float> random_field(const SheetGrid& g, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<float> v(g.cell_count());
  for (float& x : v) x = u(rng);
  return v;
}

// A l is the footprint-filtered render of a texture laid on the grid: both use
// the same stratified taps and bilinear weights, so they agree to float rounding
// wherever no footprint is longer than SheetTexture's 8 taps (its mip levels
// start there). The flat window keeps every footprint near one cell.
TEST(CorrectionOperator, ForwardEqualsTheFootprintFilteredRender) {
  const SceneCameraSetup s = load_scene_camera("flat_window.yaml", 8);
  const TransportMap map = build_transport_map(s.trace, s.camera, s.pose, TraceOptions{}, 1, 2);
  const SheetGrid grid = sheet_grid_covering(s.trace.sheet, 0.4);
  const CorrectionOperator op = build_correction_operator(map, grid);
  const std::vector<float> l = random_field(grid, 1);
  std::vector<float> image(op.pixel_count());
  apply_forward(op, l.data(), 0.25, image.data());
  const std::vector<float> reference =
      forward_render_values(map, SheetTexture(l.data(), grid.rows, grid.cols, grid.mm_per_px), 0.25);
  double worst = 0;
  for (std::size_t p = 0; p < image.size(); ++p) worst = std::max(worst, double(std::abs(image[p] - reference[p])));
  EXPECT_LT(worst, 2e-6);  // float values of A, sums of ~10 terms in [0, 1]
}

// A pixel traced with k x k samples is still one pixel: the cells' pixel
// counts (what the masks test) do not grow with the samples. Through the flat
// window every pixel sees the sheet once, so both sums are the pixel count of
// the view up to the few pixels whose samples straddle the sheet's edge.
TEST(CorrectionOperator, PixelCountsDoNotGrowWithTheSamples) {
  const SceneCameraSetup s = load_scene_camera("flat_window.yaml", 8);
  const SheetGrid grid = sheet_grid_covering(s.trace.sheet, 0.4);
  double sums[2] = {0, 0};
  for (int k = 1; k <= 3; k += 2) {
    const TransportMap map = build_transport_map(s.trace, s.camera, s.pose, TraceOptions{}, k, 2);
    const CorrectionOperator op = build_correction_operator(map, grid);
    double pixels = 0, direct = 0;
    for (std::size_t c = 0; c < op.cell_pixels.size(); ++c) pixels += op.cell_pixels[c], direct += op.cell_direct_pixels[c];
    sums[k / 2] = pixels;
    EXPECT_LE(direct, pixels * (1 + 1e-6));
  }
  EXPECT_GT(sums[0], 0);
  EXPECT_NEAR(sums[1] / sums[0], 1.0, 0.02);
}

// The same on the reactor, where reflections give several crossings per
// pixel and magnified views give footprints far below a cell.
TEST(CorrectionOperator, ForwardEqualsTheRenderThroughTheReactor) {
  const SceneCameraSetup s = load_scene_camera("reactor.yaml", 16);
  const TransportMap map = build_transport_map(s.trace, s.camera, s.pose, TraceOptions{}, 1, 2);
  const SheetGrid grid = sheet_grid_covering(s.trace.sheet, 1.0);
  OperatorOptions full;  // every crossing its full tap count, as the texture reads it
  full.taps_by_weight = false;
  const CorrectionOperator op = build_correction_operator(map, grid, full);
  const std::vector<float> l = random_field(grid, 2);
  std::vector<float> image(op.pixel_count());
  apply_forward(op, l.data(), 0, image.data());
  const std::vector<float> reference = forward_render_values(map, SheetTexture(l.data(), grid.rows, grid.cols, 1.0));
  // Only pixels whose footprints all stay within the texture's 8 taps per axis compare exactly.
  std::size_t compared = 0;
  double worst = 0;
  for (std::size_t p = 0; p < op.pixel_count(); ++p) {
    bool small = true;
    for (std::uint32_t i = map.pixel_offsets[p]; i < map.pixel_offsets[p + 1]; ++i)
      small = small && std::hypot(map.ds_dcol[i], map.dt_dcol[i]) <= 8 && std::hypot(map.ds_drow[i], map.dt_drow[i]) <= 8;
    if (!small) continue;
    ++compared;
    worst = std::max(worst, double(std::abs(image[p] - reference[p])));
  }
  EXPECT_GT(compared, op.pixel_count() * 8 / 10);  // 85 % on this scene
  EXPECT_LT(worst, 2e-6);
}

// The transpose is the adjoint: <A x, y> = <x, A^T y>.
TEST(CorrectionOperator, TransposeIsTheAdjoint) {
  const SceneCameraSetup s = load_scene_camera("reactor.yaml", 16);
  const TransportMap map = build_transport_map(s.trace, s.camera, s.pose, TraceOptions{}, 1, 2);
  const CorrectionOperator op = build_correction_operator(map, sheet_grid_covering(s.trace.sheet, 1.0));
  const std::vector<float> x = random_field(op.grid, 3);
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<float> y(op.pixel_count()), ax(op.pixel_count()), aty(op.grid.cell_count());
  for (float& v : y) v = u(rng);
  apply_forward(op, x.data(), 0, ax.data());
  apply_transpose(op, y.data(), aty.data());
  double lhs = 0, rhs = 0;
  for (std::size_t p = 0; p < y.size(); ++p) lhs += double(ax[p]) * y[p];
  for (std::size_t c = 0; c < x.size(); ++c) rhs += double(x[c]) * aty[c];
  EXPECT_NEAR(lhs, rhs, 1e-5 * std::abs(lhs));
  // cell_weight is the column sum, A^T applied to ones.
  std::vector<float> ones(op.pixel_count(), 1.0f), sums(op.grid.cell_count());
  apply_transpose(op, ones.data(), sums.data());
  for (std::size_t c = 0; c < sums.size(); ++c) ASSERT_NEAR(sums[c], op.cell_weight[c], 1e-5f * (1 + sums[c]));
}

// Every crossing's weight lands on the grid: the row sums of A are the
// pixels' sheet weights, exactly for footprints that stay inside the grid;
// taps past the grid's edge are lost, a small share of the whole.
TEST(CorrectionOperator, RowSumsAreTheCrossingWeights) {
  const SceneCameraSetup s = load_scene_camera("reactor.yaml", 16);
  const TransportMap map = build_transport_map(s.trace, s.camera, s.pose, TraceOptions{}, 1, 2);
  const CorrectionOperator op = build_correction_operator(map, sheet_grid_covering(s.trace.sheet, 1.0));
  const SheetGrid& g = op.grid;
  double worst_inside = 0, total = 0, lost = 0;
  std::size_t inside = 0;
  for (std::size_t p = 0; p < op.pixel_count(); ++p) {
    double a = 0, w = 0;
    bool within = true;
    for (std::uint32_t i = op.pixel_offsets[p]; i < op.pixel_offsets[p + 1]; ++i) a += op.value[i];
    for (std::uint32_t i = map.pixel_offsets[p]; i < map.pixel_offsets[p + 1]; ++i) {
      w += map.weight[i];
      const double reach = std::abs(map.ds_dcol[i]) + std::abs(map.ds_drow[i]) + std::abs(map.dt_dcol[i]) +
                           std::abs(map.dt_drow[i]) + 2 * g.mm_per_px;
      within = within && std::abs(map.s_mm[i]) + reach < 0.5 * (g.cols - 1) * g.mm_per_px &&
               std::abs(map.t_mm[i]) + reach < 0.5 * (g.rows - 1) * g.mm_per_px;
    }
    total += w;
    lost += w - a;
    if (within) {
      ++inside;
      worst_inside = std::max(worst_inside, std::abs(a - w));
    }
  }
  EXPECT_GT(inside, op.pixel_count() / 2);
  EXPECT_LT(worst_inside, 1e-5);  // float sums of up to a few hundred taps
  EXPECT_GE(lost, -1e-6 * total);
  EXPECT_LT(lost / total, 1e-2);
}

TEST(CorrectionOperator, SameForAnyThreadCountAndWithoutFilterOneSplatPerCrossing) {
  const SceneCameraSetup s = load_scene_camera("reactor.yaml", 16);
  const TransportMap map = build_transport_map(s.trace, s.camera, s.pose, TraceOptions{}, 1, 2);
  const SheetGrid grid = sheet_grid_covering(s.trace.sheet, 1.0);
  const CorrectionOperator a = build_correction_operator(map, grid, {}, 1), b = build_correction_operator(map, grid, {}, 3);
  EXPECT_EQ(a.pixel_offsets, b.pixel_offsets);
  EXPECT_EQ(a.cell, b.cell);
  EXPECT_EQ(a.value, b.value);
  EXPECT_EQ(a.cell_pixels, b.cell_pixels);
  OperatorOptions plain;
  plain.footprint_filter = false;
  const CorrectionOperator c = build_correction_operator(map, grid, plain);
  EXPECT_LE(c.entry_count(), 4 * map.crossing_count());
  EXPECT_LT(c.entry_count(), a.entry_count());
}

TEST(CorrectionOperator, RefusesMapsWithoutJacobiansAndBadOptions) {
  const SceneCameraSetup s = load_scene_camera("reactor.yaml", 32);
  TransportMap map = build_transport_map(s.trace, s.camera, s.pose, TraceOptions{}, 1, 2);
  const SheetGrid grid = sheet_grid_covering(s.trace.sheet, 2.0);
  OperatorOptions bad;
  bad.max_taps_per_axis = 0;
  EXPECT_THROW(build_correction_operator(map, grid, bad), std::invalid_argument);
  SheetGrid empty = grid;
  empty.cols = 0;
  EXPECT_THROW(build_correction_operator(map, empty), std::invalid_argument);
  map.ds_dcol.clear();
  EXPECT_THROW(build_correction_operator(map, grid), std::invalid_argument);
}

}  // namespace
}  // namespace glasspiv
