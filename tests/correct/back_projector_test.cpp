#include "correct/back_projector.h"

#include <gtest/gtest.h>

#include <random>

#include "correct/camera_resampler.h"
#include "tests/correct/test_scenes.h"

namespace glasspiv {
namespace {

std::vector<float> noise(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<float> v(n);
  for (float& x : v) x = u(rng);
  return v;
}

// The prepared back-projection gives back_projection's values on every cell it
// computes (valid and needed), for several cameras of different weights too.
TEST(BackProjector, EqualsBackProjectionOnTheCellsItComputes) {
  std::vector<SceneCameraSetup> setups;
  std::vector<CorrectionOperator> ops;
  const SceneCameraSetup first = load_scene_camera("reactor_5cams.yaml", 16, 0);
  const SheetGrid grid = sheet_grid_covering(first.trace.sheet, 1.0);
  for (int k = 0; k < 3; ++k) {
    setups.push_back(load_scene_camera("reactor_5cams.yaml", 16, k));
    ops.push_back(build_correction_operator(
        build_transport_map(setups[k].trace, setups[k].camera, setups[k].pose, TraceOptions{}, 1, 2), grid));
  }
  const std::vector<double> weights = {1.0, 0.5, 2.0};
  std::vector<CameraOperator> cams;
  std::vector<std::vector<float>> images;
  std::vector<float> frame;
  for (std::size_t k = 0; k < ops.size(); ++k) {
    cams.push_back({&ops[k], weights[k]});
    images.push_back(noise(ops[k].pixel_count(), k + 1));
    frame.insert(frame.end(), images[k].begin(), images[k].end());
  }
  std::vector<CameraImage> views;
  for (std::size_t k = 0; k < ops.size(); ++k) views.push_back({&ops[k], images[k].data(), weights[k]});
  const std::vector<CellState> states = classify_cells(cams, setups[0].trace);
  const std::vector<float> reference = back_projection(views, states);

  const BackProjector all = make_back_projector(cams, states);
  EXPECT_EQ(all.frame_pixels, frame.size());
  std::vector<float> l(grid.cell_count(), -1.0f);
  apply_back_projector(all, frame.data(), l.data());
  std::size_t computed = 0;
  for (std::size_t c = 0; c < l.size(); ++c) {
    if (states[c] != CellState::valid) {
      EXPECT_EQ(l[c], -1.0f);  // untouched
      continue;
    }
    ++computed;
    ASSERT_NEAR(l[c], reference[c], 1e-5f * (1 + std::abs(reference[c])));
  }
  EXPECT_GT(computed, grid.cell_count() / 4);

  // Only the needed cells: fewer entries, the same values there.
  std::vector<std::uint8_t> needed(grid.cell_count(), 0);
  for (std::size_t c = 0; c < needed.size(); c += 3) needed[c] = 1;
  const BackProjector some = make_back_projector(cams, states, &needed);
  EXPECT_LT(some.value.size(), all.value.size());
  std::vector<float> m(grid.cell_count(), -1.0f);
  apply_back_projector(some, frame.data(), m.data());
  for (std::size_t c = 0; c < m.size(); ++c)
    if (needed[c] && states[c] == CellState::valid) ASSERT_EQ(m[c], l[c]);
    else ASSERT_EQ(m[c], -1.0f);
}

TEST(BackProjector, RefusesMixedGrids) {
  const SceneCameraSetup s = load_scene_camera("reactor.yaml", 32);
  const TransportMap map = build_transport_map(s.trace, s.camera, s.pose, TraceOptions{}, 1, 2);
  const CorrectionOperator a = build_correction_operator(map, sheet_grid_covering(s.trace.sheet, 2.0));
  const CorrectionOperator b = build_correction_operator(map, sheet_grid_covering(s.trace.sheet, 3.0));
  const std::vector<CellState> states = classify_cells({{&a, 1.0}}, s.trace);
  EXPECT_THROW(make_back_projector({{&a, 1.0}, {&b, 1.0}}, states), std::invalid_argument);
  EXPECT_THROW(make_back_projector({}, states), std::invalid_argument);
}

}  // namespace
}  // namespace glasspiv
