// End to end: a simulated PIV experiment through a flat window (sim/piv_experiment.h),
// evaluated by PIV (piv/piv_evaluate.h) on the glass-removed reference pair, on
// the distorted pair corrected onto the glass-removed camera grid (correct/:
// operator, back-projection, resampling) and on the distorted pair as recorded,
// each scored against the experiment's exact displacement.
#include <chrono>
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "correct/camera_resampler.h"
#include "correct/cell_mask.h"
#include "correct/correction_operator.h"
#include "correct/reconstruct.h"
#include "piv/piv_evaluate.h"
#include "render/scene_yaml.h"
#include "render/trace_scene_builder.h"
#include "sim/piv_experiment.h"

namespace glasspiv {
namespace {

constexpr int kBinning = 8;  // 320 x 270 px: a second or two per experiment

// The flat window scene with a 40 mm plate (faces at z = -60 and -20), seen
// 45 degrees off its normal: the plate shifts the view by several mm and
// stretches it unevenly.
struct ObliqueSetup {
  Scene scene;
  TraceScene trace;
  std::vector<ExperimentCamera> cameras;
};
ObliqueSetup oblique_flat_window() {
  ObliqueSetup s;
  s.scene = read_scene(GLASSPIV_SOURCE_DIR "/data/scenes/flat_window.yaml");
  s.scene.slabs.at(0).thickness_mm = 40;
  s.trace = build_trace_scene(s.scene);
  const RigidTransform pose =
      camera_from_world_look_at({400, 0, -400}, {0, 0, 0}, {0, 1, 0});
  s.cameras.push_back({"cam0", binned(s.scene.cameras[0].camera.model, kBinning), pose});
  return s;
}

PivExperimentSettings settings_for(const ObliqueSetup& s, const PivOptions& piv) {
  PivExperimentSettings e;
  e.dt_s = 1e-3;
  e.density_ppp = 0.04;
  e.particle_px = 2.5;
  e.seed = 7;
  e.sensor.bit_depth = 12;
  e.sensor.electrons_per_radiance = 4000;  // an in-plane particle's peak about 2000 counts
  e.keep_maps = true;
  const InterrogationGrid g = final_piv_grid(s.cameras[0].model.width_px(), s.cameras[0].model.height_px(), piv);
  e.truth_grids.resize(1);
  for (int c = 0; c < g.cols; ++c) e.truth_grids[0].x_px.push_back(g.x_px(c));
  for (int r = 0; r < g.rows; ++r) e.truth_grids[0].y_px.push_back(g.y_px(r));
  return e;
}

cv::Mat as_float(const cv::Mat& counts) {
  cv::Mat f;
  counts.convertTo(f, CV_32F);
  return f;
}

// RMS of |measured - true| (px) over the vectors that are not invalid, whose
// truth exists and whose window centre is usable (use: empty or per pixel).
struct Score {
  double rms_px = 0;
  int vectors = 0;
};
Score score(const PivField& f, const CameraTruth& truth, const cv::Mat& use) {
  EXPECT_EQ(static_cast<std::size_t>(f.grid.cols), truth.x_px.size());
  EXPECT_EQ(static_cast<std::size_t>(f.grid.rows), truth.y_px.size());
  double sum = 0;
  Score s;
  for (std::size_t i = 0; i < f.size(); ++i) {
    if (f.flags[i] == VectorFlag::invalid || !std::isfinite(truth.u_px[i])) continue;
    const int x = static_cast<int>(std::lround(f.x_px(i))), y = static_cast<int>(std::lround(f.y_px(i)));
    if (!use.empty() && use.at<std::uint8_t>(y, x) == 0) continue;
    sum += std::pow(f.u_px[i] - truth.u_px[i], 2) + std::pow(f.v_px[i] - truth.v_px[i], 2);
    ++s.vectors;
  }
  s.rms_px = s.vectors ? std::sqrt(sum / s.vectors) : NAN;
  return s;
}

void run_and_score(const Flow& flow, const char* what) {
  const auto start = std::chrono::steady_clock::now();
  const ObliqueSetup s = oblique_flat_window();
  PivOptions piv;
  // A second 32 px pass: the deformation then follows the gradients of the rotation.
  piv.window_px = {64, 32, 32};
  const PivExperiment e = simulate_piv_experiment(s.trace, *s.scene.sheet, s.cameras, flow, settings_for(s, piv));
  const ExperimentCameraResult& cam = e.cameras.front();
  for (const std::string& w : e.warnings) std::printf("warning: %s\n", w.c_str());
  EXPECT_TRUE(e.warnings.empty());
  ASSERT_GT(e.tracers, 1000u);

  // No glass.
  const PivField ref = evaluate_piv(as_float(cam.frame_a_ref), as_float(cam.frame_b_ref), cv::Mat(), piv);
  const Score no_glass = score(ref, cam.truth, cv::Mat());

  // Corrected: back-projection through the operator onto the glass-removed camera grid.
  const SheetGrid grid = sheet_grid_covering(s.trace.sheet, cam.mm_per_px);
  const CorrectionOperator op = build_correction_operator(cam.map, grid);
  const std::vector<CellState> states = classify_cells({{&op, 1.0}}, s.trace);
  const CameraResampler resampler = make_camera_resampler(build_correction_operator(cam.glass_removed_map, grid), states);
  const auto correct = [&](const cv::Mat& counts) {
    const cv::Mat f = as_float(counts);
    const std::vector<float> l = back_projection({{&op, f.ptr<float>(0)}}, states);
    cv::Mat out(f.rows, f.cols, CV_32F);
    resample_to_camera(resampler, l.data(), out.ptr<float>(0));
    return out;
  };
  const cv::Mat usable(cam.height, cam.width, CV_8U, const_cast<std::uint8_t*>(resampler.pixel_valid.data()));
  const PivField corr = evaluate_piv(correct(cam.frame_a), correct(cam.frame_b), usable, piv);
  const Score corrected = score(corr, cam.truth, usable);

  // Uncorrected, scored where the corrected one is.
  const PivField raw = evaluate_piv(as_float(cam.frame_a), as_float(cam.frame_b), cv::Mat(), piv);
  const Score uncorrected = score(raw, cam.truth, usable);
  // Windows with no masked pixel at all: what the mask's rim costs.
  cv::Mat inner;
  cv::erode(usable, inner, cv::Mat::ones(33, 33, CV_8U));
  const Score corrected_inner = score(corr, cam.truth, inner);

  const double masked = 1.0 - cv::countNonZero(usable) / double(usable.total());
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("%s: %zu tracers, largest displacement %.2f px; RMS error no glass %.4f px (%d vectors), corrected "
              "%.4f px (%d), uncorrected %.4f px (%d); corrected in windows clear of the mask %.4f px (%d); %.1f%% of the pixels masked; "
              "%.1f s\n",
              what, e.tracers, e.max_displacement_px, no_glass.rms_px, no_glass.vectors, corrected.rms_px,
              corrected.vectors, uncorrected.rms_px, uncorrected.vectors, corrected_inner.rms_px, corrected_inner.vectors,
              100 * masked, seconds);
  EXPECT_GT(no_glass.vectors, 100);
  EXPECT_GT(corrected.vectors, 100);
  EXPECT_LE(no_glass.rms_px, 0.1);
  EXPECT_LE(corrected.rms_px, 0.2);
  EXPECT_LE(corrected.rms_px, 3 * no_glass.rms_px);
  EXPECT_LE(corrected_inner.rms_px, 0.1);  // the rim's windows carry most of the corrected error
  EXPECT_GT(uncorrected.rms_px, 2 * corrected.rms_px) << "uncorrected frames should be clearly worse";
}

// Solid-body rotation about the sheet normal through the sheet origin: 0.028 rad
// between the pulses, about 6 px at the corners.
TEST(PivExperiment, RotationThroughObliqueWindow) {
  run_and_score(SolidBodyRotationFlow({0, 0, 0}, {0, 0, 1}, 28.0), "rotation");
}

// A uniform stream in the sheet plane, 4 px and 2 px.
TEST(PivExperiment, UniformThroughObliqueWindow) {
  run_and_score(UniformFlow({2.5, -1.2, 0}), "uniform");
}

TEST(PivExperiment, ReproducibleFromTheSeed) {
  const ObliqueSetup s = oblique_flat_window();
  PivExperimentSettings a = settings_for(s, PivOptions{});
  a.keep_maps = false;
  const UniformFlow flow({1.0, 0.5, 0});
  const PivExperiment e1 = simulate_piv_experiment(s.trace, *s.scene.sheet, s.cameras, flow, a);
  const PivExperiment e2 = simulate_piv_experiment(s.trace, *s.scene.sheet, s.cameras, flow, a);
  EXPECT_EQ(e1.tracers, e2.tracers);
  EXPECT_EQ(cv::norm(e1.cameras[0].frame_b, e2.cameras[0].frame_b, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(e1.cameras[0].frame_a_ref, e2.cameras[0].frame_a_ref, cv::NORM_INF), 0.0);
  a.seed += 1;
  const PivExperiment e3 = simulate_piv_experiment(s.trace, *s.scene.sheet, s.cameras, flow, a);
  EXPECT_GT(cv::norm(e1.cameras[0].frame_a, e3.cameras[0].frame_a, cv::NORM_INF), 0.0);
}

// The exact displacement of a uniform flow: 1000 u dt mm on the sheet grid.
TEST(PivExperiment, SheetTruthOfUniformFlow) {
  const ObliqueSetup s = oblique_flat_window();
  PivExperimentSettings a = settings_for(s, PivOptions{});
  a.keep_maps = false;
  const PivExperiment e = simulate_piv_experiment(s.trace, *s.scene.sheet, s.cameras, UniformFlow({2, 1, 0.5}), a);
  const SheetPlane& p = s.trace.sheet;
  const Eigen::Vector3d d_mm(2, 1, 0.5);
  for (std::size_t i = 0; i < e.sheet_truth.ds_mm.size(); i += 7) {
    EXPECT_NEAR(e.sheet_truth.ds_mm[i], d_mm.dot(p.s_axis), 1e-9);
    EXPECT_NEAR(e.sheet_truth.dt_mm[i], d_mm.dot(p.t_axis), 1e-9);
    EXPECT_NEAR(e.sheet_truth.velocity_n_m_per_s[i], 0.5 * p.normal().z(), 1e-12);
  }
}

TEST(PivExperiment, QuarterRuleWarning) {
  EXPECT_TRUE(quarter_rule_warning(7.9).empty());
  EXPECT_NE(quarter_rule_warning(8.5).find("one-quarter rule"), std::string::npos);
  PivExperimentSettings bad;
  bad.density_ppp = 0;
  EXPECT_THROW(bad.check(), std::invalid_argument);
}

}  // namespace
}  // namespace glasspiv
