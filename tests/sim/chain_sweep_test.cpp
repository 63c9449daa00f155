// Run time against error of the chain (sim/chain_sweep.h): the Pareto front's
// rule on made-up rows (dominance, the error tolerance, rows without an
// error), and a small sweep on the reactor: every setting scores the vortex,
// the default row is glasspiv correct's settings, maps are traced once and
// reused, the pictures come out on the setting's grid, and bad settings are
// refused.
#include "sim/chain_sweep.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "render/scene_yaml.h"
#include "render/trace_scene_builder.h"
#include "sim/pareto_plot.h"
#include "sim/vortex_experiment.h"
#include "tests/sanitized_build.h"

namespace glasspiv {
namespace {

constexpr int kBinning = kSanitizedBuild ? 16 : 8;

ChainRow made_up(double ms, double rms) {
  ChainRow r;
  r.frame_ms = ms;
  r.error.rms_px = rms;
  return r;
}

TEST(ParetoFront, DominanceWithTheErrorTolerance) {
  const std::vector<ChainRow> rows = {
      made_up(10, 0.100),   // 0: dominated by 1 (faster, error within 1 %)
      made_up(2, 0.1005),   // 1: the fastest
      made_up(50, 0.090),   // 2: clearly more accurate: on the front
      made_up(60, 0.0899),  // 3: slower than 2 and not clearly better: off
      made_up(5, NAN),      // 4: no error: never on it
      made_up(100, 0.050),  // 5: the most accurate
      made_up(200, 0.2),    // 6: slow and poor
  };
  const std::vector<std::size_t> front = pareto_front(rows, 0.01);
  EXPECT_EQ(front, (std::vector<std::size_t>{1, 2, 5}));
  // Without the tolerance row 0's 0.5 % lower error keeps it, and row 3's too.
  EXPECT_EQ(pareto_front(rows, 0.0), (std::vector<std::size_t>{1, 0, 2, 3, 5}));
  EXPECT_TRUE(pareto_front({}, 0.01).empty());
}

// The reactor's camera binned 8 x 8 (320 x 270 px), the demo's vortex (1.5 px
// at this binning), frames through a 2 x 2-sample map cut at 1e-3; under the
// sanitizers 16 x 16 with smaller windows (the accuracy asserted in Release).
class SmallSweep : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    scene_ = new Scene(read_scene(GLASSPIV_SOURCE_DIR "/data/scenes/reactor.yaml"));
    trace_ = new TraceScene(build_trace_scene(*scene_));
    const SceneCamera& sc = scene_->cameras.front();
    cameras_ = new std::vector<ExperimentCamera>{{sc.name, binned(sc.camera.model, kBinning), *sc.camera.camera_from_world}};
    piv_ = new PivOptions;
    if (kSanitizedBuild) piv_->window_px = {32, 16};
    PivExperimentSettings e = vortex_experiment_settings();
    e.samples_per_axis = 2;
    e.trace.min_weight = 1e-3;
    e.sheet_truth_step_px = 2;
    const InterrogationGrid g =
        final_piv_grid((*cameras_)[0].model.width_px(), (*cameras_)[0].model.height_px(), *piv_);
    e.truth_grids.resize(1);
    for (int c = 0; c < g.cols; ++c) e.truth_grids[0].x_px.push_back(g.x_px(c));
    for (int r = 0; r < g.rows; ++r) e.truth_grids[0].y_px.push_back(g.y_px(r));
    experiment_ = new PivExperiment(simulate_piv_experiment(*trace_, *scene_->sheet, *cameras_,
                                                            vortex_flow(trace_->sheet), e));
  }
  static void TearDownTestSuite() {
    delete experiment_;
    delete piv_;
    delete cameras_;
    delete trace_;
    delete scene_;
  }
  static Scene* scene_;
  static TraceScene* trace_;
  static std::vector<ExperimentCamera>* cameras_;
  static PivOptions* piv_;
  static PivExperiment* experiment_;
};
Scene* SmallSweep::scene_ = nullptr;
TraceScene* SmallSweep::trace_ = nullptr;
std::vector<ExperimentCamera>* SmallSweep::cameras_ = nullptr;
PivOptions* SmallSweep::piv_ = nullptr;
PivExperiment* SmallSweep::experiment_ = nullptr;

TEST_F(SmallSweep, EverySettingScoresTheVortex) {
  ChainSweepOptions o;
  o.repeats = 1;
  ChainSweep sweep(*trace_, *cameras_, *experiment_, *piv_, o);
  ChainSetting defaults;
  defaults.label = "default";
  EXPECT_EQ(defaults.min_weight, correction_trace_options().min_weight);
  EXPECT_EQ(defaults.reflections, correction_trace_options().reflections);

  ChainSetting cut = defaults, sheet = defaults, lsq = defaults;
  cut.label = "cut 1e-2";
  cut.min_weight = 1e-2;
  sheet.label = "sheet 1x";
  sheet.grid = ChainGrid::sheet_1x;
  lsq.label = "least squares";
  lsq.least_squares = true;
  ChainImages camera_images, sheet_images;
  std::vector<ChainRow> rows = {sweep.run(defaults, &camera_images), sweep.run(cut), sweep.run(sheet, &sheet_images),
                                sweep.run(lsq)};
  for (const ChainRow& r : rows) {
    std::printf("%-14s map %.3f s, build %.3f s, %.3f ms/frame, masked %.3f, error %.4f px (max %.3f) over %d\n",
                r.setting.label.c_str(), r.map_s, r.build_s, r.frame_ms, r.masked, r.error.rms_px, r.error.max_px,
                r.error.vectors);
    EXPECT_GT(r.error.vectors, 20) << r.setting.label;
    if (kSanitizedBuild) continue;
    // 0.2 px: the bound the demo's corrected error must meet (issue 15), at a
    // quarter of the demo's pixels; an unconverted sheet-grid error, a wrong
    // truth or a broken correction is px off.
    EXPECT_LT(r.error.rms_px, 0.2) << r.setting.label;
    EXPECT_GT(r.masked, 0.0) << r.setting.label;  // the spheres hide part of the sheet
    EXPECT_LT(r.masked, 0.6) << r.setting.label;
    EXPECT_GT(r.frame_ms, 0.0);
  }
  // Reused maps: the same setting again gives the same figures and reports the map's one-off time.
  const ChainRow again = sweep.run(defaults);
  EXPECT_EQ(again.error.rms_px, rows[0].error.rms_px);
  EXPECT_EQ(again.map_s, rows[0].map_s);
  // The same map object for the same knobs; a lighter cut-off traces more.
  EXPECT_EQ(&sweep.map(0, 1, defaults.min_weight, true), &sweep.map(0, 1, defaults.min_weight, true));
  EXPECT_GT(sweep.map(0, 1, 1e-2, true).crossing_count(), sweep.map(0, 1, defaults.min_weight, true).crossing_count());

  EXPECT_EQ(camera_images.corrected_a.cols, (*cameras_)[0].model.width_px());
  EXPECT_EQ(camera_images.corrected_a.rows, (*cameras_)[0].model.height_px());
  EXPECT_EQ(camera_images.usable.size(), camera_images.corrected_a.size());
  EXPECT_GT(cv::countNonZero(camera_images.usable), 0);
  EXPECT_EQ(sheet_images.corrected_a.size(), sheet_images.usable.size());
  EXPECT_NE(sheet_images.corrected_a.cols, (*cameras_)[0].model.width_px());
  EXPECT_EQ(sheet_images.field.size(), static_cast<std::size_t>(sheet_images.field.grid.size()));

  const cv::Mat plot = draw_pareto_plot(rows, pareto_front(rows, kParetoErrorTolerance), 0.05, "test");
  EXPECT_EQ(plot.cols, 1280);
  EXPECT_EQ(plot.type(), CV_8UC3);
}

TEST(ChainSweep, RefusesSettingsItCannotRun) {
  // Refused before any work: an experiment with one camera's (empty) result will do.
  const TraceScene trace;
  const std::vector<ExperimentCamera> one = {{"cam", CameraModel(64, 48, 50, 50, 31.5, 23.5), RigidTransform{}}};
  PivExperiment experiment;
  experiment.cameras.resize(1);
  const PivOptions piv;
  ChainSweep sweep(trace, one, experiment, piv);
  ChainSetting two;
  two.cameras = 2;
  EXPECT_THROW(sweep.run(two), std::invalid_argument);
  ChainSetting none;
  none.samples = 0;
  EXPECT_THROW(sweep.run(none), std::invalid_argument);
  const std::vector<ExperimentCamera> no_cameras;
  EXPECT_THROW(ChainSweep(trace, no_cameras, experiment, piv), std::invalid_argument);
}

}  // namespace
}  // namespace glasspiv
