// The demo's five-camera PIV on the rectified sheet grid (apps/demo_piv_sheet.h)
// on the five-camera reactor scene the demo embeds: five cameras mask less of
// the sheet than the centre camera alone and measure the demo's vortex within
// 0.2 px; a uniform flow comes out with the grid's orientation (+u along +s,
// +v along -t); a second run reuses the cached operators.
#include "apps/demo_piv_sheet.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "sim/vortex_experiment.h"
#include "tests/sanitized_build.h"
#include "tests/temp_dir.h"

namespace glasspiv {
namespace {

// Under the sanitizers the same chain on cameras binned twice as much, with
// smaller windows to keep a grid of vectors; the accuracy is asserted in Release.
const int kBinning = kSanitizedBuild ? 16 : 8;

CorrectionScene five_cameras() {
  return read_correction_scene(std::string(GLASSPIV_SOURCE_DIR) + "/data/scenes/reactor_5cams.yaml");
}

// The demo's PIV design: 0.04 tracers per px, 2.5 px images, 12 bits.
PivExperimentSettings experiment() { return vortex_experiment_settings(); }

PivOptions piv_options() {
  PivOptions p;
  if (kSanitizedBuild) p.window_px = {32, 16};
  return p;
}

TEST(DemoPivSheet, FiveCamerasMaskLessAndMeasureTheVortex) {
  const TempDir dir("demo_piv_sheet");
  const CorrectionScene cs = five_cameras();
  // The demo's flow: a Lamb-Oseen vortex about the sheet normal, rc = 30 mm, peak 1 m/s.
  const LambOseenVortexFlow flow = vortex_flow(cs.trace.sheet);
  const SheetPivSummary s =
      run_sheet_piv(cs, "cam_centre", flow, experiment(), kBinning, "", piv_options(), dir.file("out"));

  std::printf("grid %dx%d at %.4f mm/px, %zu tracers, largest displacement %.2f px, %dx%d vectors; "
              "masked: five %.4f, centre %.4f; RMS (max) px, least squares: five %.4f (%.3f) over %d, on the centre's "
              "%.4f over %d, centre %.4f (%.3f) over %d; back-projection: five %.4f, centre %.4f; lsq iterations "
              "%d/%d, %d/%d; seconds: simulate %.2f, operators %.2f, reconstruct %.2f, PIV %.2f, total %.2f\n",
              s.grid.cols, s.grid.rows, s.grid.mm_per_px, s.tracers, s.max_displacement_px, s.piv_cols, s.piv_rows,
              s.all.masked_fraction, s.centre.masked_fraction, s.all.least_squares.rms_px,
              s.all.least_squares.max_px, s.all.least_squares.vectors, s.all_on_centre_vectors.rms_px,
              s.all_on_centre_vectors.vectors, s.centre.least_squares.rms_px, s.centre.least_squares.max_px,
              s.centre.least_squares.vectors, s.all.back_projection.rms_px, s.centre.back_projection.rms_px,
              s.all.lsq_iterations_a, s.all.lsq_iterations_b, s.centre.lsq_iterations_a, s.centre.lsq_iterations_b,
              s.simulate_seconds, s.operator_seconds, s.reconstruct_seconds, s.piv_seconds, s.seconds);
  EXPECT_EQ(s.centre_camera, "cam_centre");
  EXPECT_EQ(s.all.cameras.size(), 5u);
  ASSERT_EQ(s.centre.cameras.size(), 1u);
  EXPECT_EQ(s.centre.cameras[0], "cam_centre");
  EXPECT_LT(s.all.masked_fraction, s.centre.masked_fraction);
  EXPECT_GT(s.all.least_squares.vectors, s.centre.least_squares.vectors);
  // The vortex peaks at 1 mm between the pulses (its peak ring partly inside the spheres).
  EXPECT_GT(s.max_displacement_px * s.grid.mm_per_px, 0.9);
  EXPECT_LT(s.max_displacement_px * s.grid.mm_per_px, 1.0 + 1e-6);
  for (const std::string& f : {s.all.frame_a_png, s.all.error_png, s.centre.frame_a_png, s.centre.error_png})
    EXPECT_TRUE(std::filesystem::is_regular_file(f)) << f;
  if (kSanitizedBuild) return;
  EXPECT_GE(s.all.least_squares.vectors, 60);
  EXPECT_LE(s.all.least_squares.rms_px, 0.2);
  EXPECT_LE(s.all_on_centre_vectors.rms_px, 0.2);
  EXPECT_LE(s.centre.least_squares.rms_px, 0.25);
}

TEST(DemoPivSheet, UniformFlowHasTheGridsOrientationAndReusesTheCache) {
  const TempDir dir("demo_piv_sheet");
  const CorrectionScene cs = five_cameras();
  // 1 mm along +s and 0.5 mm along +t between the pulses.
  const SheetPlane& plane = cs.trace.sheet;
  const UniformFlow flow(1.0 * plane.s_axis + 0.5 * plane.t_axis);
  const std::string cache = dir.file("cache");
  const SheetPivSummary s =
      run_sheet_piv(cs, "cam_centre", flow, experiment(), kBinning, cache, piv_options(), dir.file("out"));
  const double pitch = s.grid.mm_per_px;
  ASSERT_GT(pitch, 0);
  // Columns grow with +s, rows with -t.
  EXPECT_NEAR(s.all.mean_u_px, 1.0 / pitch, 0.05);
  EXPECT_NEAR(s.all.mean_v_px, -0.5 / pitch, 0.05);
  EXPECT_NEAR(s.centre.mean_u_px, 1.0 / pitch, 0.05);
  EXPECT_NEAR(s.centre.mean_v_px, -0.5 / pitch, 0.05);
  EXPECT_EQ(s.operators_reused, 0);
  if (!kSanitizedBuild) {
    EXPECT_LE(s.all.least_squares.rms_px, 0.1);
  }

  // The same run again: every operator from the cache, the same figures.
  const SheetPivSummary again =
      run_sheet_piv(cs, "cam_centre", flow, experiment(), kBinning, cache, piv_options(), dir.file("out"));
  EXPECT_EQ(again.operators_reused, 5);
  EXPECT_EQ(again.all.least_squares.rms_px, s.all.least_squares.rms_px);
  EXPECT_EQ(again.all.least_squares.vectors, s.all.least_squares.vectors);
}

}  // namespace
}  // namespace glasspiv
