// Round trips through the example reactor: a known particle field on the sheet,
// rendered through the glass by the transport map (footprint-filtered texture,
// independent of the operator), then corrected.
#include "correct/reconstruct.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <cstdio>
#include <random>

#include "correct/camera_resampler.h"
#include "correct/cell_mask.h"
#include "render/forward_render.h"
#include "sim/sheet_particles.h"
#include "tests/correct/test_scenes.h"

namespace glasspiv {
namespace {

double ncc(const std::vector<float>& a, const std::vector<float>& b, const std::vector<CellState>& states) {
  return ncc_where(a, b, valid_cells(states));
}
double rms_error(const std::vector<float>& a, const std::vector<float>& b, const std::vector<CellState>& states) {
  return rms_difference_where(a, b, valid_cells(states));
}

TEST(Reconstruct, OneCameraRoundTripThroughTheReactor) {
  const SceneCameraSetup s = load_scene_camera("reactor.yaml", 4);
  const TransportMap map = build_transport_map(s.trace, s.camera, s.pose, TraceOptions{}, 1, 2);
  const TransportMap direct = glass_removed_map(s.trace, s.camera, s.pose, 1, 2);
  const double mm = median_footprint_mm(direct);  // the camera's own pixel on the sheet
  const SheetGrid grid = sheet_grid_covering(s.trace.sheet, mm);
  // PIV-like particles: 3 px images, 0.03 particles per px of the undistorted view.
  const SheetParticles field = random_sheet_particles(s.trace.sheet, 0.03 / (mm * mm), 3 * mm, 7);
  const std::vector<float> image = forward_render_values(map, field.texture(s.trace.sheet, mm / 4));

  const CorrectionOperator op = build_correction_operator(map, grid);
  const std::vector<CellState> states = classify_cells({{&op, 1.0}}, s.trace);
  const CellCounts counts = count_cells(states);
  const std::vector<float> l = back_projection({{&op, image.data()}}, states);
  // A camera's weight cancels in the normalisation (the general path against the one-camera one).
  const std::vector<float> weighted = back_projection({{&op, image.data(), 2.0}}, states);
  for (std::size_t i = 0; i < l.size(); ++i) ASSERT_NEAR(weighted[i], l[i], 1e-5f * (1 + std::abs(l[i])));
  const std::vector<float> truth = field.on(grid);
  // Centroids on a sparse field of the same particles: isolated ones.
  const SheetParticles sparse = random_sheet_particles(s.trace.sheet, 0.003 / (mm * mm), 3 * mm, 8);
  const std::vector<float> sparse_image = forward_render_values(map, sparse.texture(s.trace.sheet, mm / 4));
  int n = 0;
  const double centroid =
      mean_centroid_error_cells(back_projection({{&op, sparse_image.data()}}, states), sparse, grid, valid_cells(states), &n);
  const double c = ncc(l, truth, states);
  std::printf("one camera: grid %dx%d at %.3f mm; valid %.1f%% of the fluid region (never seen %zu, few pixels %zu, "
              "low weight %zu, mostly reflected %zu cells); NCC %.4f; centroid error %.4f px over %d particles\n",
              grid.cols, grid.rows, mm, 100 * counts.valid_fraction_of_fluid(), counts.never_seen, counts.few_pixels,
              counts.low_weight, counts.mostly_reflected, c, centroid, n);
  EXPECT_GE(c, 0.95);
  EXPECT_LT(centroid, 0.1);
  EXPECT_GT(n, 50);
  // Least squares from the back-projection: a smaller residual and no worse a match.
  LeastSquaresReport rep;
  const std::vector<float> lsq = least_squares({{&op, image.data()}}, states, l, {}, &rep);
  const double c_lsq = ncc(lsq, truth, states);
  std::printf("least squares: %d iterations, residual RMS %.4g -> %.4g, NCC %.4f, RMS error %.4f (back-projection %.4f)\n",
              rep.iterations, rep.residual_start, rep.residual_end, c_lsq, rms_error(lsq, truth, states),
              rms_error(l, truth, states));
  EXPECT_LT(rep.residual_end, 0.5 * rep.residual_start);
  EXPECT_GE(c_lsq, c);
  EXPECT_GT(counts.valid_fraction_of_fluid(), 0.3);
}

// Five cameras around the reactor: together they see nearly all of the
// sheet's fluid region, and where one camera's pixels are lit through several
// paths (reflections) least squares explains the ghosts away.
TEST(Reconstruct, FiveCamerasFillTheRimsAndLeastSquaresRemovesGhosts) {
  constexpr int kBinning = 8, kCameras = 5;
  std::vector<SceneCameraSetup> setups;
  std::vector<TransportMap> maps;
  for (int k = 0; k < kCameras; ++k) {
    setups.push_back(load_scene_camera("reactor_5cams.yaml", kBinning, k));
    maps.push_back(build_transport_map(setups[k].trace, setups[k].camera, setups[k].pose, TraceOptions{}, 1, 2));
  }
  const TraceScene& trace = setups[0].trace;
  const double mm = median_footprint_mm(glass_removed_map(trace, setups[1].camera, setups[1].pose, 1, 2));
  const SheetGrid grid = sheet_grid_covering(trace.sheet, mm);
  const SheetParticles field = random_sheet_particles(trace.sheet, 0.03 / (mm * mm), 3 * mm, 9);
  const SheetTexture texture = field.texture(trace.sheet, mm / 4);
  std::vector<CorrectionOperator> ops;
  std::vector<std::vector<float>> images;
  std::vector<CameraOperator> cams;
  std::vector<CameraImage> views;
  for (int k = 0; k < kCameras; ++k) {
    ops.push_back(build_correction_operator(maps[k], grid));
    images.push_back(forward_render_values(maps[k], texture));
  }
  for (int k = 0; k < kCameras; ++k) {
    cams.push_back({&ops[k], 1.0});
    views.push_back({&ops[k], images[k].data()});
  }
  const std::vector<CellState> together = classify_cells(cams, trace);
  const CellCounts all = count_cells(together);
  const CellCounts centre = count_cells(classify_cells({cams[1]}, trace));
  std::printf("five cameras: valid %.1f%% of the fluid region (%.2f%% of what they see); the centre camera alone %.1f%%\n",
              100 * all.valid_fraction_of_fluid(), 100 * all.valid_fraction_of_seen(),
              100 * centre.valid_fraction_of_fluid());
  std::printf("  few pixels %zu, low weight %zu, mostly reflected %zu, never seen %zu, valid %zu cells\n", all.few_pixels, all.low_weight, all.mostly_reflected, all.never_seen, all.valid);
  EXPECT_GE(all.valid_fraction_of_seen(), 0.99);
  EXPECT_GT(all.valid_fraction_of_fluid(), centre.valid_fraction_of_fluid());

  const std::vector<float> truth = field.on(grid);
  const std::vector<float> acc = back_projection(views, together);
  LeastSquaresReport rep;
  const std::vector<float> lsq = least_squares(views, together, acc, {}, &rep);
  const double e_acc = rms_error(acc, truth, together), e_lsq = rms_error(lsq, truth, together);
  std::printf("accumulation RMS error %.4f, NCC %.4f; least squares (%d iterations) RMS error %.4f, NCC %.4f\n", e_acc,
              ncc(acc, truth, together), rep.iterations, e_lsq, ncc(lsq, truth, together));
  EXPECT_LT(e_lsq, 0.8 * e_acc);
}

// A small operator by hand: pixel p sees the cells and weights of rows[p]
// (a cell of a 6 x 1 grid each); no background.
CorrectionOperator hand_operator(const std::vector<std::vector<std::pair<std::uint32_t, float>>>& rows) {
  CorrectionOperator op;
  op.width = static_cast<int>(rows.size());
  op.height = 1;
  op.grid.cols = 6;
  op.grid.rows = 1;
  op.grid.mm_per_px = 1;
  op.pixel_offsets = {0};
  for (const auto& row : rows) {
    for (const auto& [cell, value] : row) {
      op.cell.push_back(cell);
      op.value.push_back(value);
    }
    op.pixel_offsets.push_back(static_cast<std::uint32_t>(op.cell.size()));
  }
  op.background_weight.assign(rows.size(), 0.0f);
  op.cell_pixels.assign(6, 1.0f);
  op.cell_direct_pixels.assign(6, 1.0f);
  finish_correction_operator(op);
  return op;
}

// Every cell seen directly, cells 1 and 4 also through a ghost of pixels 4 and 1;
// pixel 5 alone sees cell 5.
std::vector<std::vector<std::pair<std::uint32_t, float>>> ghost_rows() {
  return {{{0, 1.0f}}, {{1, 0.9f}, {4, 0.1f}}, {{2, 1.0f}}, {{3, 1.0f}}, {{4, 0.9f}, {1, 0.1f}}, {{5, 1.0f}},
          {{2, 0.5f}, {3, 0.5f}}};
}

// A non-finite pixel is left out: the result is that of the operator without
// its row (an independent reference), for both methods, and least squares
// iterates instead of returning its start. A cell only that pixel sees has no data.
TEST(Reconstruct, NonFinitePixelsAreLeftOut) {
  const auto rows = ghost_rows();
  const CorrectionOperator op = hand_operator(rows);
  const std::vector<CellState> states(6, CellState::valid);
  const std::vector<float> image = {0.2f, 0.7f, 0.4f, 0.9f, 0.3f, 0.6f, 0.65f};
  for (const float bad : {std::nanf(""), std::numeric_limits<float>::infinity()})
    for (const std::size_t p : {std::size_t(1), std::size_t(5)}) {
      std::vector<float> with_bad = image;
      with_bad[p] = bad;
      auto without_rows = rows;
      without_rows[p].clear();
      const CorrectionOperator reference = hand_operator(without_rows);
      std::vector<float> zeroed = image;
      zeroed[p] = 0;
      const std::vector<float> bp = back_projection({{&op, with_bad.data()}}, states);
      const std::vector<float> bp_ref = back_projection({{&reference, zeroed.data()}}, states);
      LeastSquaresOptions exact;
      exact.smoothness = 0;  // lambda from the column norms would differ between the two operators
      exact.tolerance = 1e-6;
      LeastSquaresReport rep;
      const std::vector<float> ls = least_squares({{&op, with_bad.data()}}, states, bp, exact, &rep);
      const std::vector<float> ls_ref = least_squares({{&reference, zeroed.data()}}, states, bp_ref, exact);
      EXPECT_EQ(rep.masked_pixels, 1u);
      EXPECT_GT(rep.iterations, 0);
      for (std::size_t c = 0; c < 6; ++c) {
        if (p == 5 && c == 5) {  // seen by the left-out pixel only
          EXPECT_TRUE(std::isnan(bp[c]));
          EXPECT_TRUE(std::isnan(ls[c]));
          continue;
        }
        ASSERT_TRUE(std::isfinite(bp[c])) << c;
        EXPECT_NEAR(bp[c], bp_ref[c], 1e-6) << "pixel " << p << ", cell " << c;
        ASSERT_TRUE(std::isfinite(ls[c])) << c;
        EXPECT_NEAR(ls[c], ls_ref[c], 1e-4) << "pixel " << p << ", cell " << c;
      }
      // The ghost is explained away: least squares differs from its start where the ghost lies.
      if (p == 5) EXPECT_GT(std::abs(ls[4] - bp[4]), 1e-3);
    }
}

// A frame without a finite pixel: back-projection says no data (NaN, not 0)
// and least squares refuses instead of returning zeros.
TEST(Reconstruct, AFrameWithoutFinitePixelsHasNoData) {
  const CorrectionOperator op = hand_operator(ghost_rows());
  const std::vector<CellState> states(6, CellState::valid);
  const std::vector<float> image(7, std::nanf(""));
  const std::vector<float> bp = back_projection({{&op, image.data()}}, states);
  for (float v : bp) EXPECT_TRUE(std::isnan(v));
  EXPECT_THROW(least_squares({{&op, image.data()}}, states, bp), std::invalid_argument);
  EXPECT_EQ(count_non_finite(image.data(), image.size()), 7u);
}

}  // namespace
}  // namespace glasspiv
