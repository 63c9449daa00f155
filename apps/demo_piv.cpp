#include "apps/demo_piv.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "apps/correction_setup.h"
#include "apps/html_text.h"
#include "apps/png_file.h"
#include "apps/plots.h"
#include "calib/fit/calibration_diagnostics.h"
#include "calib/lens_maps.h"
#include "piv/piv_evaluate.h"
#include "piv/vector_file.h"
#include "sim/chain_sweep.h"
#include "sim/pareto_plot.h"
#include "sim/piv_experiment.h"
#include "sim/piv_score.h"
#include "sim/vortex_experiment.h"
#include "util/json_document.h"
#include "util/atomic_file.h"
#include "util/input_error.h"
#include "util/stopwatch.h"

namespace glasspiv {
namespace {
namespace fs = std::filesystem;

// The map the one camera's frames are rendered through: richer than any
// setting of the run-time-versus-error sweep (samples, cut-off).
constexpr int kSimulationSamples = 2;
constexpr double kSimulationMinWeight = 1e-3;

// The demo's run time against error: glasspiv correct's defaults (first) and
// one knob changed per row (bench/chain_bench sweeps them all at more cost).
std::vector<ChainSetting> demo_sweep_settings() {
  std::vector<ChainSetting> v(6);
  v[0].label = "default";
  v[0].is_default = true;
  v[1].label = "cut 1e-2";
  v[1].min_weight = 1e-2;
  v[2].label = "no reflections";
  v[2].reflections = false;
  v[3].label = "2x2 samples";
  v[3].samples = 2;
  v[4].label = "sheet grid 1x";
  v[4].grid = ChainGrid::sheet_1x;
  v[5].label = "least squares";
  v[5].least_squares = true;
  return v;
}

cv::Mat as_float(const cv::Mat& counts) {
  cv::Mat f;
  counts.convertTo(f, CV_32F);
  return f;
}

// Counts (or corrected counts) to 8 bits: the in-plane particle's peak (about 2100 counts) white.
cv::Mat to8(const cv::Mat& m, const cv::Mat& usable = cv::Mat()) {
  cv::Mat out;
  m.convertTo(out, CV_8U, 255.0 / 2100.0);
  if (!usable.empty()) out.setTo(cv::Scalar(60), usable == 0);
  return out;
}

// RMS and max of |measured - true| over the vectors that are not invalid,
// whose truth exists and whose window centre is usable (use: empty or per
// pixel); errors (NaN where not scored) per vector for the plot.
PivScore score(const PivField& f, const CameraTruth& truth, const cv::Mat& use, GridValues* errors) {
  return score_vectors(f, camera_truth_on_vectors(f, truth, use), errors);
}

std::string file_name(const std::string& path) { return fs::path(path).filename().string(); }

std::string windows_text(const std::vector<int>& w) {
  std::string t;
  for (int v : w) t += (t.empty() ? "" : "-") + std::to_string(v);
  return t;
}

std::string write_page(const fs::path& out, const DemoPivSummary& s) {
  std::string page;
  page += "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n";
  page += "<title>glasspiv demo: PIV through the reactor</title>\n";
  page += "<style>body{font-family:sans-serif;max-width:1000px;margin:2em auto;color:#222}"
          "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}"
          "th{background:#f4f4f4}td:first-child,th:first-child{text-align:left}img{max-width:100%;border:1px solid #ddd}"
          "figure{margin:1.5em 0}.pair{display:flex;gap:1em}.pair figure{flex:1;margin:0.5em 0}</style>\n";
  page += "</head><body>\n<h1>A simulated PIV experiment in the packed-bed reactor</h1>\n";
  page += fmt::format(
      "<p>A steady Lamb&ndash;Oseen vortex (core radius {:g} mm, circulation {:.4g} m&sup2;/s) about the sheet's "
      "normal through its centre, {} tracers ({:g} per px of the glass-removed view), {:g} px particle images, a "
      "{}-bit sensor, pulses {:g} ms apart; the camera of <code>scenes/reactor.yaml</code> binned {}&times;{} "
      "({}&times;{} px); largest true displacement {:.2f} px. PIV {} px windows, {:g}&nbsp;% overlap ({}&times;{} "
      "vectors). Errors are |measured &minus; true| over the vectors whose window centre the correction's mask keeps "
      "and where the truth exists (no glass: wherever the truth exists).</p>\n",
      s.core_radius_mm, s.circulation_m2_per_s, s.tracers, s.density_ppp, s.particle_px, s.bit_depth, 1e3 * s.dt_s,
      s.binning, s.binning, s.width, s.height, s.max_displacement_px, windows_text(s.window_px), 100 * s.overlap,
      s.grid_cols, s.grid_rows);
  for (const std::string& w : s.warnings) page += "<p><b>Warning:</b> " + html_escape(w) + "</p>\n";
  page += "<table><tr><th>frames</th><th>RMS error px</th><th>max error px</th><th>vectors scored</th></tr>\n";
  const auto row = [&](const char* what, const PivScore& sc) {
    page += fmt::format("<tr><td>{}</td><td>{:.4f}</td><td>{:.3f}</td><td>{}</td></tr>\n", what, sc.rms_px, sc.max_px,
                        sc.vectors);
  };
  row("no glass (reference)", s.no_glass);
  row("distorted, corrected onto the glass-removed camera grid", s.corrected);
  row("distorted, corrected: windows clear of the mask", s.corrected_inner);
  if (s.own_model) row("distorted, corrected with the demo's own camera (calibrated, aligned)", s.corrected_own_model);
  row("distorted, uncorrected", s.uncorrected);
  page += "</table>\n";
  if (s.own_model)
    page += fmt::format(
        "<p>The demo's own camera: the intrinsics from its calibration on 20 synthetic ChArUco photos "
        "({:.3f} px RMS from the truth's projection over the image at 1 m, {:.3f} px after the rotation it implies, "
        "which the pose absorbs) and the pose its alignment found on the photograph (camera centre {:.3f} mm from "
        "the truth's). The frames are the same; only the model that corrects them differs.</p>\n",
        s.own_projection_difference_px, s.own_projection_difference_rotated_px, s.own_pose_error_mm);
  page += fmt::format(
      "<p>{:.1f}&nbsp;% of the camera's pixels are masked by the correction. On the rectified sheet grid, "
      "{:.1f}&nbsp;% of the fluid region is masked with this camera; with <code>reactor_5cams.yaml</code> (binned "
      "{}&times;{}) {:.1f}&nbsp;% with its centre camera alone and {:.1f}&nbsp;% with all five.</p>\n",
      100 * s.masked_pixel_fraction, 100 * s.one_camera_sheet_masked, s.five_binning, s.five_binning,
      100 * s.sheet.centre.masked_fraction, 100 * s.sheet.all.masked_fraction);
  const SheetPivSummary& f = s.sheet;
  page += fmt::format(
      "<h2>Five cameras on the sheet grid</h2>\n<p>The same experiment recorded by the five cameras of "
      "<code>reactor_5cams.yaml</code> (binned {0}&times;{0}), frames A and B reconstructed on the rectified sheet "
      "grid ({1}&times;{2} cells of {3:.3f} mm, the centre camera's pixel) by least squares from all five and from "
      "the centre camera alone; PIV there ({4}&times;{5} vectors), scored against the sheet's true in-plane "
      "displacement in grid px.</p>\n",
      s.five_binning, f.grid.cols, f.grid.rows, f.grid.mm_per_px, f.piv_cols, f.piv_rows);
  page += "<table><tr><th>cameras</th><th>masked of the fluid region</th><th>RMS error px</th><th>max error px</th>"
          "<th>vectors scored</th></tr>\n";
  const auto sheet_row = [&](const std::string& what, double masked, const PivScore& sc) {
    page += fmt::format("<tr><td>{}</td><td>{:.1f}&nbsp;%</td><td>{:.4f}</td><td>{:.3f}</td><td>{}</td></tr>\n", what,
                        100 * masked, sc.rms_px, sc.max_px, sc.vectors);
  };
  sheet_row("all five", f.all.masked_fraction, f.all.least_squares);
  sheet_row("all five, on the centre camera's vectors", f.all.masked_fraction, f.all_on_centre_vectors);
  sheet_row("the centre camera alone", f.centre.masked_fraction, f.centre.least_squares);
  const auto figure = [&](const std::string& src, const std::string& caption) {
    page += fmt::format("<figure><img src=\"{}\"><figcaption>{}</figcaption></figure>", src, caption);
  };
  page += "</table>\n<div class=\"pair\">";
  figure("five/" + file_name(f.all.frame_a_png), "Frame A reconstructed from all five.");
  figure("five/" + file_name(f.centre.frame_a_png), "From the centre camera alone.");
  page += "</div>\n<div class=\"pair\">";
  figure("five/" + file_name(f.all.error_png), "|measured &minus; true|, five cameras.");
  figure("five/" + file_name(f.centre.error_png), "|measured &minus; true|, the centre camera alone.");
  page += "</div>\n<div class=\"pair\">";
  figure(file_name(s.distorted_png), "Frame A through the glass, as recorded.");
  figure(file_name(s.corrected_png), "Frame A corrected onto the glass-removed camera grid (masked pixels dark).");
  page += "</div>\n<div class=\"pair\">";
  figure(file_name(s.true_field_png), "The true displacement where the corrected frames are scored.");
  figure(file_name(s.measured_field_png), "The displacement measured on the corrected frames.");
  page += "</div>\n";
  figure(file_name(s.error_corrected_png), "|measured &minus; true| per vector, corrected frames; grey: not scored.");
  page += "\n";
  figure(file_name(s.error_uncorrected_png),
         "The same for the uncorrected frames, scored where the corrected ones are.");
  page += "\n";
  page += "<h2>Run time against error</h2>\n<p>The same frames corrected with glasspiv correct's default settings "
          "and with one knob changed per row (all on the glass-removed camera grid but the sheet-grid row; errors in "
          "px of that grid, over the vectors the row's mask keeps); the Pareto front of error against correction "
          "time per frame, errors within 1&nbsp;% counting as equal. The maps and operators are built once per "
          "series; <code>bench/chain_bench</code> sweeps every knob and the five-camera scene.</p>\n";
  page += "<table><tr><th>setting</th><th>map s</th><th>build s</th><th>ms per frame</th><th>masked</th>"
          "<th>RMS error px</th><th>vectors</th><th>Pareto</th></tr>\n";
  for (std::size_t i = 0; i < s.sweep.size(); ++i) {
    const ChainRow& r = s.sweep[i];
    const bool on = on_front(s.sweep_front, i);
    page += fmt::format(
        "<tr><td>{}{}</td><td>{:.2f}</td><td>{:.2f}</td><td>{:.2f}</td><td>{:.1f}&nbsp;%</td><td>{:.4f}</td>"
        "<td>{}</td><td>{}</td></tr>\n",
        html_escape(r.setting.label), r.setting.is_default ? " (glasspiv correct)" : "", r.map_s, r.build_s,
        r.frame_ms, 100 * r.masked, r.error.rms_px, r.error.vectors, on ? "yes" : "");
  }
  page += "</table>\n";
  figure(file_name(s.pareto_png), "PIV error against correction time per frame (red: the Pareto front; ringed: "
                                  "the default).");
  page += "\n";
  page += fmt::format("<p>Vectors of the corrected frames: <a href=\"{0}\">{0}</a> (glasspiv piv's text format). "
                      "This step ran in {1:.1f} s (simulation {2:.1f} s, the correction settings with their PIV "
                      "{3:.1f} s, PIV on the reference and uncorrected pairs {4:.1f} s).</p>\n",
                      file_name(s.vectors_txt), s.seconds, s.simulate_seconds, s.sweep_seconds, s.piv_seconds);
  page += "</body></html>\n";
  const std::string path = (out / "piv.html").string();
  write_file_atomically(path, page);
  return path;
}


nlohmann::json sweep_json(const DemoPivSummary& s) {
  nlohmann::json rows = nlohmann::json::array();
  for (std::size_t i = 0; i < s.sweep.size(); ++i) {
    const ChainRow& r = s.sweep[i];
    const ChainSetting& st = r.setting;
    rows.push_back({{"setting", st.label}, {"default", st.is_default}, {"samples_per_axis", st.samples},
                    {"min_weight", st.min_weight}, {"reflections", st.reflections}, {"grid", chain_grid_name(st.grid)},
                    {"method", st.least_squares ? "least squares" : "accumulate"}, {"map_seconds", r.map_s},
                    {"build_seconds", r.build_s}, {"frame_ms", r.frame_ms}, {"masked_fraction", r.masked},
                    {"error_px", score_json(r.error)},
                    {"pareto", on_front(s.sweep_front, i)}});
  }
  return {{"rows", rows}, {"error_tolerance", kParetoErrorTolerance}, {"plot", file_name(s.pareto_png)}};
}

std::string write_metrics(const fs::path& out, const DemoPivSummary& s) {
  nlohmann::json j = {
      {"camera", {{"width_px", s.width}, {"height_px", s.height}, {"binning", s.binning}}},
      {"flow",
       {{"kind", "lamb_oseen"}, {"core_radius_mm", s.core_radius_mm}, {"circulation_m2_per_s", s.circulation_m2_per_s},
        {"dt_s", s.dt_s}}},
      {"experiment",
       {{"tracers", s.tracers}, {"density_ppp", s.density_ppp}, {"particle_px", s.particle_px},
        {"bit_depth", s.bit_depth}, {"max_displacement_px", s.max_displacement_px}, {"warnings", s.warnings}}},
      {"piv", {{"window_px", s.window_px}, {"overlap", s.overlap}, {"cols", s.grid_cols}, {"rows", s.grid_rows}}},
      {"error_px",
       {{"no_glass", score_json(s.no_glass)}, {"corrected", score_json(s.corrected)},
        {"corrected_windows_clear_of_mask", score_json(s.corrected_inner)},
        {"uncorrected", score_json(s.uncorrected)}}},
      {"own_model",
       s.own_model ? nlohmann::json{{"error_px", score_json(s.corrected_own_model)},
                                    {"camera_centre_error_mm", s.own_pose_error_mm},
                                    {"intrinsics_projection_difference_px", s.own_projection_difference_px},
                                    {"intrinsics_projection_difference_after_implied_rotation_px",
                                     s.own_projection_difference_rotated_px},
                                    {"seconds", s.own_model_seconds}}
                   : nlohmann::json()},
      {"masked_pixel_fraction", s.masked_pixel_fraction},
      {"sheet_masked_fraction_of_fluid",
       {{"one_camera", s.one_camera_sheet_masked}, {"five_cameras_binning", s.five_binning},
        {"five_cameras_centre_alone", s.sheet.centre.masked_fraction}, {"five_cameras", s.sheet.all.masked_fraction}}},
      {"five_cameras_sheet_grid",
       {{"binning", s.five_binning}, {"grid_mm_per_px", s.sheet.grid.mm_per_px},
        {"cols", s.sheet.grid.cols}, {"rows", s.sheet.grid.rows}, {"piv_cols", s.sheet.piv_cols},
        {"piv_rows", s.sheet.piv_rows}, {"tracers", s.sheet.tracers},
        {"max_displacement_px", s.sheet.max_displacement_px},
        {"all", {{"masked_fraction", s.sheet.all.masked_fraction}, {"error_px", score_json(s.sheet.all.least_squares)},
                 {"error_back_projection_px", score_json(s.sheet.all.back_projection)}}},
        {"all_on_centre_vectors_error_px", score_json(s.sheet.all_on_centre_vectors)},
        {"centre_alone", {{"masked_fraction", s.sheet.centre.masked_fraction},
                          {"error_px", score_json(s.sheet.centre.least_squares)},
                          {"error_back_projection_px", score_json(s.sheet.centre.back_projection)}}}}},
      {"sweep", sweep_json(s)},
      {"seconds",
       {{"simulate", s.simulate_seconds}, {"piv", s.piv_seconds}, {"sweep", s.sweep_seconds},
        {"five_cameras", s.five_seconds}}},
  };
  const std::string path = (out / "metrics.json").string();
  write_file_atomically(path, json_text(j));
  return path;
}

}  // namespace

nlohmann::json score_json(const PivScore& s) {
  return {{"rms_px", s.rms_px}, {"max_px", s.max_px}, {"vectors", s.vectors}};
}

DemoPivSummary run_piv_demo(const std::string& folder, const std::string& scenes_dir, int binning,
                            const std::string& five_cache_dir, const Camera* recovered) {
  const Stopwatch total;
  const fs::path out(folder);
  fs::create_directories(out);
  DemoPivSummary s;
  s.binning = binning;

  const CorrectionScene cs = read_correction_scene((fs::path(scenes_dir) / "reactor.yaml").string());
  const SceneCamera& sc = cs.scene.cameras.front();
  const std::vector<ExperimentCamera> cameras = {
      {sc.name, binning > 1 ? binned(sc.camera.model, binning) : sc.camera.model, *sc.camera.camera_from_world}};
  s.width = cameras[0].model.width_px();
  s.height = cameras[0].model.height_px();

  const VortexDesign design;
  s.core_radius_mm = design.core_radius_mm;
  s.dt_s = design.dt_s;
  s.circulation_m2_per_s = design.circulation_m2_per_s();
  const LambOseenVortexFlow flow = vortex_flow(cs.trace.sheet, design);

  PivOptions piv;  // 64 then 32 px windows, 50 % overlap: the published evaluation
  s.window_px = piv.window_px;
  s.overlap = piv.overlap;
  const InterrogationGrid g = final_piv_grid(s.width, s.height, piv);
  s.grid_cols = g.cols;
  s.grid_rows = g.rows;

  PivExperimentSettings e = vortex_experiment_settings(design);
  // The five cameras' frames through their default maps, whose operators they
  // reuse (run_sheet_piv); the one camera's through a richer map than any
  // correction setting below traces, so that none inverts its own forward model.
  const PivExperimentSettings five_e = e;
  e.samples_per_axis = kSimulationSamples;
  e.trace.min_weight = kSimulationMinWeight;
  e.truth_grids.resize(1);
  for (int c = 0; c < g.cols; ++c) e.truth_grids[0].x_px.push_back(g.x_px(c));
  for (int r = 0; r < g.rows; ++r) e.truth_grids[0].y_px.push_back(g.y_px(r));
  s.density_ppp = e.density_ppp;
  s.particle_px = e.particle_px;
  s.bit_depth = e.sensor.bit_depth;

  std::printf("   simulating the experiment: tracers, the maps through the glass and without it, four frames...\n");
  std::fflush(stdout);
  const Stopwatch sim_clock;
  const PivExperiment x = simulate_piv_experiment(cs.trace, *cs.scene.sheet, cameras, flow, e);
  s.simulate_seconds = sim_clock.seconds();
  const ExperimentCameraResult& cam = x.cameras.front();
  s.tracers = x.tracers;
  s.max_displacement_px = x.max_displacement_px;
  s.warnings = x.warnings;

  // The correction onto the glass-removed camera grid, with the true model
  // and glasspiv correct's default settings: the sweep's first row.
  const std::vector<ChainSetting> settings = demo_sweep_settings();
  ChainSweep sweep(cs.trace, cameras, x, piv);
  std::printf("   correcting with glasspiv correct's defaults: the maps, the operator, PIV...\n");
  std::fflush(stdout);
  Stopwatch sweep_clock;
  ChainImages truth_correction;
  s.sweep.push_back(sweep.run(settings.front(), &truth_correction));
  s.sweep_seconds = sweep_clock.seconds();
  s.one_camera_sheet_masked = 1 - count_cells(truth_correction.states).valid_fraction_of_fluid();
  const cv::Mat& usable = truth_correction.usable;
  s.masked_pixel_fraction = 1.0 - cv::countNonZero(usable) / double(usable.total());
  const cv::Mat& corrected_a = truth_correction.corrected_a;
  const PivField& corr = truth_correction.field;

  std::printf("   PIV on the reference and uncorrected pairs...\n");
  std::fflush(stdout);
  const Stopwatch piv_clock;
  const PivField ref = evaluate_piv(as_float(cam.frame_a_ref), as_float(cam.frame_b_ref), cv::Mat(), piv);
  const PivField raw = evaluate_piv(as_float(cam.frame_a), as_float(cam.frame_b), cv::Mat(), piv);
  s.piv_seconds = piv_clock.seconds();
  GridValues ref_err, corr_err, raw_err;
  s.no_glass = score(ref, cam.truth, cv::Mat(), &ref_err);
  s.corrected = score(corr, cam.truth, usable, &corr_err);
  s.uncorrected = score(raw, cam.truth, usable, &raw_err);  // scored where the corrected one is
  cv::Mat inner;
  cv::erode(usable, inner, cv::Mat::ones(piv.window_px.back() + 1, piv.window_px.back() + 1, CV_8U));
  GridValues inner_err;
  s.corrected_inner = score(corr, cam.truth, inner, &inner_err);

  // The same frames corrected with the camera the demo recovered itself
  // (its calibration's intrinsics, the pose its alignment found), scored
  // against the same truth: what a user's own model costs.
  if (recovered) {
    std::printf("   correcting with the demo's own camera (calibrated, aligned): its maps...\n");
    std::fflush(stdout);
    const Stopwatch own_clock;
    const RigidTransform& pose = *recovered->camera_from_world;
    const std::vector<ExperimentCamera> own_camera = {{sc.name, recovered->model, pose}};
    s.corrected_own_model = ChainSweep(cs.trace, own_camera, x, piv).run(settings.front()).error;
    s.own_model = true;
    s.own_model_seconds = own_clock.seconds();
    s.own_pose_error_mm = (pose.inverse().translation_mm - cameras[0].camera_from_world.inverse().translation_mm).norm();
    s.own_projection_difference_px = projection_difference(cameras[0].model, recovered->model, 1000.0, 16.0).rms_px;
    s.own_projection_difference_rotated_px =
        projection_difference(cameras[0].model, recovered->model, 1000.0, 16.0,
                              implied_rotation(cameras[0].model, recovered->model, 16.0))
            .rms_px;
  }

  // Run time against error: the sweep's rows, its Pareto front and plot.
  std::printf("   run time against error: %zu more correction settings...\n", settings.size() - 1);
  std::fflush(stdout);
  sweep_clock.restart();
  for (std::size_t i = 1; i < settings.size(); ++i) s.sweep.push_back(sweep.run(settings[i]));
  s.sweep_front = pareto_front(s.sweep, kParetoErrorTolerance);
  s.pareto_png = (out / "pareto.png").string();
  write_png(s.pareto_png, draw_pareto_plot(s.sweep, s.sweep_front, s.no_glass.rms_px,
                                           "glasspiv demo: the reactor camera, PIV 64->32 px vs truth"));
  s.sweep_seconds += sweep_clock.seconds();

  // Pictures and the corrected vectors.
  s.distorted_png = (out / "frame_a_distorted.png").string();
  s.corrected_png = (out / "frame_a_corrected.png").string();
  write_png(s.distorted_png, to8(cam.frame_a));
  write_png(s.corrected_png, to8(corrected_a, usable));
  s.error_corrected_png = (out / "error_corrected.png").string();
  s.error_uncorrected_png = (out / "error_uncorrected.png").string();
  PlotLabels labels{"PIV error, corrected frames (measured - true)", "|error| px"};
  labels.cells = true;
  write_magnitude_png(corr_err, s.width, s.height, labels, s.error_corrected_png);
  labels.title = "PIV error, uncorrected frames (measured - true)";
  write_magnitude_png(raw_err, s.width, s.height, labels, s.error_uncorrected_png);
  // The true and the measured (corrected) field, where the corrected one is scored.
  GridValues true_field, measured_field;
  true_field.vector_px.assign(corr.size(), Eigen::Vector2d::Constant(NAN));
  measured_field.vector_px = true_field.vector_px;
  for (std::size_t i = 0; i < corr.size(); ++i) {
    if (!corr_err.vector_px[i].allFinite()) continue;
    true_field.vector_px[i] = Eigen::Vector2d(cam.truth.u_px[i], cam.truth.v_px[i]);
    measured_field.vector_px[i] = Eigen::Vector2d(corr.u_px[i], corr.v_px[i]);
  }
  use_vector_cells(corr.grid, &true_field);
  use_vector_cells(corr.grid, &measured_field);
  s.true_field_png = (out / "field_true.png").string();
  s.measured_field_png = (out / "field_measured_corrected.png").string();
  PlotLabels field_labels{"true displacement (glass-removed camera grid)", "|displacement| px"};
  field_labels.cells = true;
  write_vector_field_png(true_field, s.width, s.height, field_labels, s.true_field_png);
  field_labels.title = "measured displacement, corrected frames";
  write_vector_field_png(measured_field, s.width, s.height, field_labels, s.measured_field_png);
  s.vectors_txt = (out / "vectors_corrected.txt").string();
  write_vector_files(s.vectors_txt, "", corr,
                     {"glasspiv demo step 9: the reactor camera's corrected frames, a Lamb-Oseen vortex",
                      fmt::format("windows {} px, overlap {:g}", windows_text(s.window_px), s.overlap)});

  // Five cameras: the sheet grid's masked area (operators from the correction step's cache when valid).
  // Five cameras: the experiment recorded by all of reactor_5cams.yaml's cameras,
  // reconstructed on the sheet grid from all five and from the centre camera
  // alone, PIV there against the sheet truth (operators from the correction
  // step's cache when valid).
  std::printf("   five cameras: the experiment through each, reconstructed on the sheet grid, PIV (operators from the "
              "cache if valid)...\n");
  std::fflush(stdout);
  {
    const Stopwatch five_clock;
    s.five_binning = 2 * binning;
    const CorrectionScene fcs = read_correction_scene((fs::path(scenes_dir) / "reactor_5cams.yaml").string());
    s.sheet =
        run_sheet_piv(fcs, "cam_centre", flow, five_e, s.five_binning, five_cache_dir, piv, (out / "five").string());
    s.five_seconds = five_clock.seconds();
  }

  s.seconds = total.seconds();
  s.metrics_json = write_metrics(out, s);
  s.html = write_page(out, s);
  return s;
}

}  // namespace glasspiv
