// chain_bench: run time against error for the whole chain, simulate -> correct
// -> PIV -> compare with the truth, on one simulated experiment in the reactor
// (data/scenes/reactor.yaml; five cameras: data/scenes/reactor_5cams.yaml), and
// the Pareto plot of error against correction time per frame (results in
// bench/RESULTS.md).
//   chain_bench [--binning B] [--five-binning B5] [--reps R] [--threads T] [--no-five] [PNG]
// PNG: the Pareto plot (default chain_pareto.png in the current folder).
//
// The experiment (sim/vortex_experiment.h, as demo step 9): a steady
// Lamb-Oseen vortex about the sheet normal, about 3 px at binning 4, the
// cameras binned B x B (default 4: 640 x 540 px). The frames are rendered
// through a richer map than any setting corrects with (one camera: 4 x 4
// samples per pixel, min_weight 1e-4; five cameras, for time: 2 x 2 samples,
// 1e-3; reflections on), so no setting inverts its own forward model.
//
// Each setting changes one knob from the defaults of glasspiv correct
// (sim/chain_sweep.h; with five cameras the sheet grid, as glasspiv correct
// --frame), plus a few combinations. Per setting: the one-off build (maps;
// operators, mask, resampler, back projector), the correction time per frame
// (median over frames A and B, R repeats), PIV 64 -> 32 px (50 % overlap,
// quintic B-spline deformation) on the corrected pair, and its RMS error
// against the truth over the vectors whose window centre is usable, in px of
// the reference camera's glass-removed view. The Pareto front is per
// experiment, errors within 1 % counting as equal (kParetoErrorTolerance).
// Float versus double: the operator stores float32 only, so the bench has no
// such knob. Progress on stderr, tables on stdout.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "bench/bench_common.h"
#include "piv/piv_evaluate.h"
#include "render/scene_yaml.h"
#include "render/trace_scene_builder.h"
#include "sim/chain_sweep.h"
#include "sim/pareto_plot.h"
#include "sim/piv_experiment.h"
#include "sim/piv_score.h"
#include "sim/vortex_experiment.h"
#include "util/stopwatch.h"

using namespace glasspiv;

namespace {

struct Experiment {
  std::string scene_name;
  Scene scene;
  TraceScene trace;
  std::vector<ExperimentCamera> cameras;  // the reference camera first
  PivExperiment x;
  int binning = 1;
  int sim_samples = 1;  // the map the frames were rendered through
  double sim_min_weight = 0;
  double seconds = 0;
};

cv::Mat as_float(const cv::Mat& counts) {
  cv::Mat f;
  counts.convertTo(f, CV_32F);
  return f;
}

Experiment simulate(const std::string& path, const std::string& first_camera, int binning, int sim_samples,
                    double sim_min_weight, const PivOptions& piv, int threads) {
  Experiment e;
  e.scene_name = path.substr(path.find_last_of('/') + 1);
  e.scene = read_scene(path);
  e.trace = build_trace_scene(e.scene);
  e.binning = binning;
  for (const SceneCamera& sc : e.scene.cameras) {
    ExperimentCamera c{sc.name, binned(sc.camera.model, binning), *sc.camera.camera_from_world};
    if (sc.name == first_camera) e.cameras.insert(e.cameras.begin(), c);
    else e.cameras.push_back(c);
  }
  const VortexDesign design;
  PivExperimentSettings s = vortex_experiment_settings(design);
  s.samples_per_axis = sim_samples;
  s.trace.min_weight = sim_min_weight;
  s.sheet_truth_step_px = 4;  // bilinear between cells 4 px apart: a few thousandths of a px
  e.sim_samples = sim_samples;
  e.sim_min_weight = sim_min_weight;
  s.threads = threads;
  const InterrogationGrid g = final_piv_grid(e.cameras[0].model.width_px(), e.cameras[0].model.height_px(), piv);
  s.truth_grids.resize(1);
  for (int c = 0; c < g.cols; ++c) s.truth_grids[0].x_px.push_back(g.x_px(c));
  for (int r = 0; r < g.rows; ++r) s.truth_grids[0].y_px.push_back(g.y_px(r));
  std::fprintf(stderr, "simulating %s, %zu camera(s) at binning %d ...\n", e.scene_name.c_str(), e.cameras.size(), binning);
  const Stopwatch clock;
  e.x = simulate_piv_experiment(e.trace, *e.scene.sheet, e.cameras, vortex_flow(e.trace.sheet, design), s);
  e.seconds = clock.seconds();
  return e;
}

}  // namespace

int main(int argc, char** argv) {
  int binning = 4, five_binning = -1, reps = 5, threads = 0;
  bool five = true;
  std::string png = "chain_pareto.png";
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--binning") && i + 1 < argc) binning = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--five-binning") && i + 1 < argc) five_binning = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) reps = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--threads") && i + 1 < argc) threads = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--no-five")) five = false;
    else if (argv[i][0] != '-') png = argv[i];
    else {
      std::fprintf(stderr,
                   "usage: chain_bench [--binning B] [--five-binning B5] [--reps R] [--threads T] [--no-five] [PNG]\n");
      return 2;
    }
  }
  if (binning < 1 || reps < 1) {
    std::fprintf(stderr, "chain_bench: --binning >= 1, --reps >= 1\n");
    return 2;
  }
  if (five_binning < 1) five_binning = binning;
  if (threads <= 0) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const Stopwatch total;
  PivOptions piv;  // 64 -> 32 px, 50 % overlap, quintic B-splines
  piv.threads = threads;

  std::vector<Experiment> experiments;
  // The one-camera frames through a 4 x 4-sample, 1e-4 map; the five cameras' through 2 x 2 samples, 1e-3 (time).
  experiments.push_back(
      simulate(GLASSPIV_SOURCE_DIR "/data/scenes/reactor.yaml", "cam0", binning, 4, 1e-4, piv, threads));
  if (five)
    experiments.push_back(simulate(GLASSPIV_SOURCE_DIR "/data/scenes/reactor_5cams.yaml", "cam_centre", five_binning,
                                   2, 1e-3, piv, threads));

  // Settings per experiment: each changes one knob of glasspiv correct's defaults.
  struct Planned {
    int experiment;
    ChainSetting setting;
  };
  std::vector<Planned> plan;
  const auto add = [&](int experiment, const std::string& label, auto change) {
    ChainSetting s;
    s.label = label;
    change(s);
    plan.push_back({experiment, s});
  };
  add(0, "default", [](ChainSetting& s) { s.is_default = true; });
  add(0, "2x2 samples", [](ChainSetting& s) { s.samples = 2; });
  add(0, "3x3 samples", [](ChainSetting& s) { s.samples = 3; });
  add(0, "cut 1e-2", [](ChainSetting& s) { s.min_weight = 1e-2; });
  add(0, "cut 1e-3", [](ChainSetting& s) { s.min_weight = 1e-3; });
  add(0, "no reflections", [](ChainSetting& s) { s.reflections = false; });
  add(0, "sheet 1x", [](ChainSetting& s) { s.grid = ChainGrid::sheet_1x; });
  add(0, "sheet 0.5x", [](ChainSetting& s) { s.grid = ChainGrid::sheet_half; });
  add(0, "least squares", [](ChainSetting& s) { s.least_squares = true; });
  add(0, "lsq, sheet 1x", [](ChainSetting& s) {
    s.least_squares = true;
    s.grid = ChainGrid::sheet_1x;
  });
  add(0, "lsq, cut 1e-2", [](ChainSetting& s) {
    s.least_squares = true;
    s.min_weight = 1e-2;
  });
  add(0, "richest: 3x3, cut 1e-3, lsq", [](ChainSetting& s) {
    s.samples = 3;
    s.min_weight = 1e-3;
    s.least_squares = true;
  });
  if (five) {
    add(1, "5-cam scene: centre alone", [](ChainSetting&) {});
    add(1, "5-cam scene: centre alone, sheet 1x", [](ChainSetting& s) { s.grid = ChainGrid::sheet_1x; });
    add(1, "5 cams, sheet 1x: default", [](ChainSetting& s) {  // glasspiv correct --frame's defaults
      s.cameras = 5;
      s.grid = ChainGrid::sheet_1x;
      s.is_default = true;
    });
    add(1, "5 cams, cut 1e-2, sheet 1x", [](ChainSetting& s) {
      s.cameras = 5;
      s.grid = ChainGrid::sheet_1x;
      s.min_weight = 1e-2;
    });
    add(1, "5 cams, camera grid", [](ChainSetting& s) { s.cameras = 5; });
    add(1, "5 cams, lsq, sheet 1x", [](ChainSetting& s) {
      s.cameras = 5;
      s.grid = ChainGrid::sheet_1x;
      s.least_squares = true;
    });
  }

  ChainSweepOptions so;
  so.threads = threads;
  so.repeats = reps;
  std::vector<std::unique_ptr<ChainSweep>> sweeps;
  for (const Experiment& e : experiments)
    sweeps.push_back(std::make_unique<ChainSweep>(e.trace, e.cameras, e.x, piv, so));
  std::vector<std::vector<ChainRow>> rows(experiments.size());
  for (std::size_t i = 0; i < plan.size(); ++i) {
    const Planned& p = plan[i];
    std::fprintf(stderr, "setting %zu of %zu: %s ...\n", i + 1, plan.size(), p.setting.label.c_str());
    const ChainRow r = sweeps[static_cast<std::size_t>(p.experiment)]->run(p.setting);
    std::fprintf(stderr, "    map %.2f s, build %.2f s, %.2f ms/frame, %.1f %% masked, error %.4f px (%d vectors)\n",
                 r.map_s, r.build_s, r.frame_ms, 100 * r.masked, r.error.rms_px, r.error.vectors);
    rows[static_cast<std::size_t>(p.experiment)].push_back(r);
  }

  // References: PIV on the glass-free and on the uncorrected pairs of the one-camera experiment.
  const ExperimentCameraResult& ref = experiments[0].x.cameras.front();
  const PivField no_glass = evaluate_piv(as_float(ref.frame_a_ref), as_float(ref.frame_b_ref), cv::Mat(), piv);
  const PivField raw = evaluate_piv(as_float(ref.frame_a), as_float(ref.frame_b), cv::Mat(), piv);
  const PivScore no_glass_all = score_vectors(no_glass, camera_truth_on_vectors(no_glass, ref.truth));
  const PivScore raw_all = score_vectors(raw, camera_truth_on_vectors(raw, ref.truth));

  std::printf("chain_bench: %s binned %d (%dx%d px), %zu tracers, largest displacement %.2f px, frames rendered "
              "through a %dx%d-sample map cut at %g, simulated in %.1f s",
              experiments[0].scene_name.c_str(), binning, ref.width, ref.height, experiments[0].x.tracers,
              experiments[0].x.max_displacement_px, experiments[0].sim_samples, experiments[0].sim_samples,
              experiments[0].sim_min_weight, experiments[0].seconds);
  if (five)
    std::printf("; %s binned %d, %zu tracers, largest %.2f px, %dx%d samples cut at %g, simulated in %.1f s",
                experiments[1].scene_name.c_str(), five_binning, experiments[1].x.tracers,
                experiments[1].x.max_displacement_px, experiments[1].sim_samples, experiments[1].sim_samples,
                experiments[1].sim_min_weight, experiments[1].seconds);
  std::printf("; %d threads; per-frame times: median of %d repeats x 2 frames (least squares: 1 x 2)\n", threads, reps);
  for (const Experiment& e : experiments)
    for (const std::string& w : e.x.warnings) std::printf("warning (%s): %s\n", e.scene_name.c_str(), w.c_str());
  std::printf("\n| # | setting | samples | cut-off | refl. | grid | method | cameras | map s | build s | correct ms/frame "
              "| masked | vectors | RMS error px | Pareto |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  std::vector<std::vector<std::size_t>> fronts;
  int number = 0;
  for (std::size_t x = 0; x < rows.size(); ++x) {
    fronts.push_back(pareto_front(rows[x], kParetoErrorTolerance));
    for (std::size_t i = 0; i < rows[x].size(); ++i) {
      const ChainRow& r = rows[x][i];
      const ChainSetting& s = r.setting;
      const bool front = on_front(fronts[x], i);
      std::printf("| %d | %s%s%s | %d | %g | %s | %s | %s | %d%s | %.2f | %.2f | %.2f | %.1f %% | %d | %.4f | %s |\n",
                  ++number, s.is_default ? "**" : "", s.label.c_str(), s.is_default ? "**" : "", s.samples,
                  s.min_weight, s.reflections ? "on" : "off", chain_grid_name(s.grid),
                  s.least_squares ? "least squares" : "accumulate", s.cameras, x == 1 ? " (5-cam scene)" : "",
                  r.map_s, r.build_s, r.frame_ms, 100 * r.masked, r.error.vectors, r.error.rms_px,
                  front ? "yes" : "");
    }
  }
  std::printf("\nReferences (%s, %dx%d, every vector with a truth): no glass %.4f px (%d vectors), uncorrected "
              "%.4f px (%d vectors).\n",
              experiments[0].scene_name.c_str(), ref.width, ref.height, no_glass_all.rms_px, no_glass_all.vectors,
              raw_all.rms_px, raw_all.vectors);
  for (std::size_t x = 0; x < rows.size(); ++x) {
    const auto def = std::find_if(rows[x].begin(), rows[x].end(), [](const ChainRow& r) { return r.setting.is_default; });
    if (def == rows[x].end()) continue;
    const bool on = on_front(fronts[x], std::size_t(def - rows[x].begin()));
    std::printf("%s: the default settings are %son the Pareto front of error against correction time per frame "
                "(errors within %.0f %% count as equal).\n",
                experiments[x].scene_name.c_str(), on ? "" : "NOT ", 100 * kParetoErrorTolerance);
  }
  const std::string title = "chain_bench: reactor binned " + std::to_string(binning) + ", PIV 64->32 px vs truth";
  if (!cv::imwrite(png, draw_pareto_plot(rows[0], fronts[0], no_glass_all.rms_px, title)))
    throw std::runtime_error("cannot write " + png);
  std::printf("Pareto plot: %s (the one-camera experiment); bench ran %.0f s\n", png.c_str(), total.seconds());
  return 0;
}
