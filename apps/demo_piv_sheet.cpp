#include "apps/demo_piv_sheet.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>

#include <fmt/format.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "apps/plots.h"
#include "apps/png_file.h"
#include "calib/camera_model.h"
#include "correct/cell_mask.h"
#include "correct/correction_operator_file.h"
#include "correct/reconstruct.h"
#include "render/transport_map_file.h"
#include "util/input_error.h"
#include "util/stopwatch.h"

namespace glasspiv {
namespace {
namespace fs = std::filesystem;

// The sheet truth's cell, in grid px: bilinear interpolation between cells 4 px
// apart errs by about h^2/8 |d''|, a few thousandths of a px for the demo's vortex.
constexpr double kSheetTruthStepPx = 4;
// The cameras' own truth (only the design-rule warnings use it): every 16th px.
constexpr double kCameraTruthStepPx = 16;
constexpr int kPictureWidthPx = 600;

cv::Mat valid_mask(const std::vector<CellState>& states, const SheetGrid& grid) {
  cv::Mat m(grid.rows, grid.cols, CV_8U);
  for (std::size_t i = 0; i < states.size(); ++i) m.data[i] = states[i] == CellState::valid ? 255 : 0;
  return m;
}

// A reconstructed frame to 8 bits: the 99.5th percentile of the valid cells white, masked cells dark grey.
cv::Mat to8(const std::vector<float>& l, const std::vector<CellState>& states, const SheetGrid& grid) {
  std::vector<float> seen;
  for (std::size_t i = 0; i < l.size(); ++i)
    if (states[i] == CellState::valid) seen.push_back(l[i]);
  float white = 1;
  if (!seen.empty()) {
    auto at = seen.begin() + static_cast<std::ptrdiff_t>(0.995 * (seen.size() - 1));
    std::nth_element(seen.begin(), at, seen.end());
    white = std::max(*at, 1e-6f);
  }
  cv::Mat out(grid.rows, grid.cols, CV_8U);
  for (std::size_t i = 0; i < l.size(); ++i)
    out.data[i] = states[i] == CellState::valid
                      ? static_cast<std::uint8_t>(std::clamp(std::lround(255.0 * l[i] / white), 0L, 255L))
                      : 60;
  return out;
}

// A camera's operator on the grid: from the cache when it was made for exactly
// this map (fingerprint), else built from the experiment's map and cached. A
// damaged cache file is not replaced (as add_correction_camera).
CorrectionOperator camera_operator(const CorrectionScene& cs, int scene_index, const ExperimentCamera& cam,
                                   const TransportMap& map, const SheetGrid& grid, const PivExperimentSettings& e,
                                   const CorrectionSettings& cache, bool* reused) {
  const OperatorOptions options;
  const std::uint64_t fp = correction_operator_fingerprint(
      transport_map_fingerprint(cs.trace, cam.model, cam.camera_from_world, e.trace, e.samples_per_axis), grid,
      options);
  const std::string path = correction_cache_files(cs.scene, scene_index, cache, grid.cols, grid.rows).op;
  *reused = false;
  if (!path.empty()) {
    std::string why;
    if (std::optional<CorrectionOperator> op = load_cached_correction_operator(path, fp, &why)) {
      *reused = true;
      return std::move(*op);
    }
    if (why.rfind("unreadable", 0) == 0)
      throw InputError(path, "", "cached correction operator is " + why + "; delete it to build a new one");
  }
  CorrectionOperator op = build_correction_operator(map, grid, options, e.threads);
  if (!path.empty()) {
    fs::create_directories(cache.cache_dir);
    write_correction_operator(path, op, fp);
  }
  return op;
}

struct Reconstruction {
  std::vector<float> bp, lsq;
  int iterations = 0;
};

Reconstruction reconstruct(const std::vector<const CorrectionOperator*>& ops,
                           const std::vector<const std::vector<float>*>& frames, const std::vector<CellState>& states) {
  std::vector<CameraImage> views;
  for (std::size_t k = 0; k < ops.size(); ++k) views.push_back({ops[k], frames[k]->data()});
  Reconstruction r;
  r.bp = back_projection(views, states);
  LeastSquaresReport rep;
  r.lsq = least_squares(views, states, r.bp, {}, &rep);
  r.iterations = rep.iterations;
  return r;
}

cv::Mat as_image(const std::vector<float>& l, const SheetGrid& grid) {
  return cv::Mat(grid.rows, grid.cols, CV_32F, const_cast<float*>(l.data()));
}

}  // namespace

SheetPivSummary run_sheet_piv(const CorrectionScene& cs, const std::string& centre_camera, const Flow& flow,
                              const PivExperimentSettings& base, int binning, const std::string& cache_dir,
                              const PivOptions& piv, const std::string& out_folder) {
  if (binning < 1) throw std::invalid_argument("sheet piv: binning must be at least 1");
  piv.check();
  const Stopwatch total;
  SheetPivSummary s;
  s.binning = binning;
  const int centre = find_camera(cs.scene, centre_camera, "cameras");
  s.centre_camera = cs.scene.cameras[static_cast<std::size_t>(centre)].name;

  // The centre camera first: the experiment's density and particle size are per
  // px of its glass-removed view, and so per px of the grid.
  std::vector<int> order = {centre};
  for (int k = 0; k < static_cast<int>(cs.scene.cameras.size()); ++k)
    if (k != centre) order.push_back(k);
  std::vector<ExperimentCamera> cameras;
  for (int k : order) {
    const SceneCamera& sc = cs.scene.cameras[static_cast<std::size_t>(k)];
    cameras.push_back({sc.name, binning > 1 ? binned(sc.camera.model, binning) : sc.camera.model,
                       *sc.camera.camera_from_world});
  }
  s.width = cameras[0].model.width_px();
  s.height = cameras[0].model.height_px();

  PivExperimentSettings e = base;
  e.keep_maps = true;
  e.sheet_truth_step_px = kSheetTruthStepPx;
  e.truth_grids.assign(cameras.size(), {});
  for (std::size_t k = 0; k < cameras.size(); ++k) {
    for (double x = 0; x < cameras[k].model.width_px(); x += kCameraTruthStepPx) e.truth_grids[k].x_px.push_back(x);
    for (double y = 0; y < cameras[k].model.height_px(); y += kCameraTruthStepPx) e.truth_grids[k].y_px.push_back(y);
  }
  s.density_ppp = e.density_ppp;
  s.particle_px = e.particle_px;

  const Stopwatch sim_clock;
  PivExperiment x = simulate_piv_experiment(cs.trace, *cs.scene.sheet, cameras, flow, e);
  s.simulate_seconds = sim_clock.seconds();
  s.tracers = x.tracers;
  s.warnings = x.warnings;

  // The grid at the centre camera's glass-removed pixel (as glass_removed_view's footprint_mm).
  const SheetGrid grid = sheet_grid_covering(cs.trace.sheet, x.cameras[0].mm_per_px);
  s.grid = grid;
  for (std::size_t i = 0; i < x.sheet_truth.ds_mm.size(); ++i)
    if (std::isfinite(x.sheet_truth.ds_mm[i]))
      s.max_displacement_px = std::max(s.max_displacement_px,
                                       std::hypot(x.sheet_truth.ds_mm[i], x.sheet_truth.dt_mm[i]) / grid.mm_per_px);

  const Stopwatch op_clock;
  CorrectionSettings cache;
  cache.binning = binning;
  cache.cache_dir = cache_dir;
  std::vector<CorrectionOperator> ops;
  for (std::size_t k = 0; k < cameras.size(); ++k) {
    bool reused = false;
    ops.push_back(camera_operator(cs, order[k], cameras[k], x.cameras[k].map, grid, e, cache, &reused));
    s.operators_reused += reused;
    if (ops.back().entry_count() == 0)
      throw InputError(cs.scene.source, cs.scene.cameras[static_cast<std::size_t>(order[k])].field,
                       fmt::format("camera '{}' sees none of the sheet: check its pose and the sheet's extent",
                                   cameras[k].name));
    x.cameras[k].map = TransportMap{};
    x.cameras[k].glass_removed_map = TransportMap{};
  }
  s.operator_seconds = op_clock.seconds();

  // The frames as the operators model them: the sensor's black level removed.
  std::vector<std::vector<float>> frames_a, frames_b;
  for (const ExperimentCameraResult& r : x.cameras)
    for (int f = 0; f < 2; ++f) {
      cv::Mat v;
      (f == 0 ? r.frame_a : r.frame_b).convertTo(v, CV_32F, 1.0, -e.sensor.background_counts);
      (f == 0 ? frames_a : frames_b).emplace_back(v.ptr<float>(0), v.ptr<float>(0) + v.total());
    }

  const fs::path out(out_folder);
  fs::create_directories(out);
  std::vector<bool> centre_scored;
  for (int which = 1; which >= 0; --which) {  // the centre camera alone first, then all
    const bool all = which == 0;
    SheetPivCase& c = all ? s.all : s.centre;
    std::vector<CameraOperator> mask_ops;
    std::vector<const CorrectionOperator*> rec_ops;
    std::vector<const std::vector<float>*> a, b;
    for (std::size_t k = 0; k < (all ? cameras.size() : 1); ++k) {
      c.cameras.push_back(cameras[k].name);
      mask_ops.push_back({&ops[k], 1.0});
      rec_ops.push_back(&ops[k]);
      a.push_back(&frames_a[k]);
      b.push_back(&frames_b[k]);
    }
    const std::vector<CellState> states = classify_cells(mask_ops, cs.trace);
    c.masked_fraction = 1 - count_cells(states).valid_fraction_of_fluid();

    const Stopwatch rec_clock;
    const Reconstruction ra = reconstruct(rec_ops, a, states), rb = reconstruct(rec_ops, b, states);
    s.reconstruct_seconds += rec_clock.seconds();
    c.lsq_iterations_a = ra.iterations;
    c.lsq_iterations_b = rb.iterations;

    const Stopwatch piv_clock;
    const cv::Mat usable = valid_mask(states, grid);
    const PivField lsq = evaluate_piv(as_image(ra.lsq, grid), as_image(rb.lsq, grid), usable, piv);
    const PivField bp = evaluate_piv(as_image(ra.bp, grid), as_image(rb.bp, grid), usable, piv);
    s.piv_seconds += piv_clock.seconds();
    s.piv_cols = lsq.grid.cols;
    s.piv_rows = lsq.grid.rows;

    const std::vector<Eigen::Vector2d> truth = sheet_truth_on_vectors(lsq, grid, x.sheet_truth);
    GridValues errors;
    Eigen::Vector2d mean_px;
    c.least_squares = score_vectors(lsq, truth, &errors, nullptr, all ? nullptr : &centre_scored, &mean_px);
    c.mean_u_px = mean_px.x();
    c.mean_v_px = mean_px.y();
    c.back_projection = score_vectors(bp, truth, nullptr);
    if (all) s.all_on_centre_vectors = score_vectors(lsq, truth, nullptr, &centre_scored);

    // The pictures enlarged (nearest neighbour) to about 600 px wide: the grid is as coarse as a binned camera.
    const int zoom = std::max(1, kPictureWidthPx / grid.cols);
    const std::string stem = all ? "sheet_all_cameras" : "sheet_centre_camera";
    c.frame_a_png = (out / (stem + "_frame_a.png")).string();
    cv::Mat frame8;
    cv::resize(to8(ra.lsq, states, grid), frame8, cv::Size(), zoom, zoom, cv::INTER_NEAREST);
    write_png(c.frame_a_png, frame8);
    c.error_png = (out / (stem + "_error.png")).string();
    PlotLabels labels{all ? fmt::format("PIV error on the sheet grid, {} cameras (measured - true)", cameras.size())
                          : fmt::format("PIV error on the sheet grid, {} alone (measured - true)", s.centre_camera),
                      "|error| px"};
    labels.cells = true;
    write_magnitude_png(errors, zoom * grid.cols, zoom * grid.rows, labels, c.error_png);
  }
  s.seconds = total.seconds();
  return s;
}

}  // namespace glasspiv
