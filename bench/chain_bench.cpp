// chain_bench: run time against error for the whole chain, simulate -> correct
// -> PIV -> compare with the truth, on one simulated experiment in the reactor
// (data/scenes/reactor.yaml; five cameras: data/scenes/reactor_5cams.yaml), and
// the Pareto plot of error against correction time per frame (results in
// bench/RESULTS.md).
//   chain_bench [--binning B] [--five-binning B5] [--reps R] [--threads T] [--no-five] [PNG]
// PNG: the Pareto plot (default chain_pareto.png in the current folder).
//
// The experiment (as demo step 8, apps/demo_piv.cpp): a steady Lamb-Oseen
// vortex about the sheet normal through the sheet's centre (core 30 mm, peak
// 1 m/s, pulses 1 ms apart: about 3 px at binning 4, within the one-quarter
// rule of the 32 px windows), 0.04 tracers per px, 2.5 px images, a 12-bit
// sensor, seed 8; the cameras binned B x B (default 4: 640 x 540 px). The
// frames are rendered through a richer map than any setting corrects with
// (one camera: 4 x 4 samples per pixel, min_weight 1e-4; five cameras, for
// time: 2 x 2 samples, 1e-3; reflections on), so no setting inverts its own
// forward model.
//
// Each setting changes one knob from the defaults of glasspiv correct (1
// sample per pixel, min_weight 1e-2, reflections on, the glass-removed camera
// grid at the camera's own footprint, accumulate = the prepared
// back-projection, one camera), plus a few combinations. Per setting: the
// one-off build (maps; operators, mask, resampler, back projector), the
// correction time per frame (median over frames A and B, R repeats), PIV
// 64 -> 32 px (50 % overlap, quintic B-spline deformation) on the corrected
// pair, and its RMS error against the truth over the vectors whose window
// centre is usable, in px of the reference camera's glass-removed view
// (sheet-grid errors converted by the camera's median footprint). Float versus
// double: the operator stores float32 only, so the bench has no such knob.
// Progress on stderr, tables on stdout.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "bench/bench_common.h"
#include "correct/back_projector.h"
#include "correct/camera_resampler.h"
#include "correct/cell_mask.h"
#include "correct/correction_operator.h"
#include "correct/reconstruct.h"
#include "correct/sheet_grid.h"
#include "piv/piv_evaluate.h"
#include "render/scene_yaml.h"
#include "render/trace_scene_builder.h"
#include "render/transport_map.h"
#include "sim/flows.h"
#include "sim/piv_experiment.h"
#include "sim/tracers.h"
#include "util/stopwatch.h"

using namespace glasspiv;
using bench::median;
using bench::seconds_of;

namespace {

std::string fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

// The experiment's flow (apps/demo_piv.cpp): peak velocity 1 m/s at r = 1.1209 rc.
constexpr double kCoreRadiusMm = 30, kPeakVelocityMPerS = 1.0, kDtS = 1e-3;

enum class GridKind { camera, sheet_1x, sheet_half };
const char* grid_name(GridKind g) {
  return g == GridKind::camera ? "camera (glass removed)" : g == GridKind::sheet_1x ? "sheet 1x" : "sheet 0.5x";
}

struct Setting {
  std::string label;  // short, for the plot
  int samples = 1;
  double min_weight = 1e-2;
  bool reflections = true;
  GridKind grid = GridKind::camera;
  bool lsq = false;
  int experiment = 0;  // 0: reactor.yaml (one camera); 1: reactor_5cams.yaml
  int cameras = 1;     // cameras of the experiment used (the reference camera first)
  bool is_default = false;
};

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
  const SheetPlane& plane = e.trace.sheet;
  const double circulation = kPeakVelocityMPerS * 2 * M_PI * (1e-3 * kCoreRadiusMm) / 0.63817;
  const LambOseenVortexFlow flow(plane.origin_mm, plane.normal(), circulation, kCoreRadiusMm);
  PivExperimentSettings s;
  s.dt_s = kDtS;
  s.density_ppp = 0.04;
  s.particle_px = 2.5;
  s.sensor.bit_depth = 12;
  s.sensor.electrons_per_radiance = 4000;
  s.seed = 8;
  s.samples_per_axis = sim_samples;
  s.trace.min_weight = sim_min_weight;
  e.sim_samples = sim_samples;
  e.sim_min_weight = sim_min_weight;
  s.threads = threads;
  const InterrogationGrid g = final_piv_grid(e.cameras[0].model.width_px(), e.cameras[0].model.height_px(), piv);
  s.truth_grids.resize(1);
  for (int c = 0; c < g.cols; ++c) s.truth_grids[0].x_px.push_back(g.x_px(c));
  for (int r = 0; r < g.rows; ++r) s.truth_grids[0].y_px.push_back(g.y_px(r));
  std::fprintf(stderr, "simulating %s, %zu camera(s) at binning %d ...\n", e.scene_name.c_str(), e.cameras.size(), binning);
  const Stopwatch clock;
  e.x = simulate_piv_experiment(e.trace, *e.scene.sheet, e.cameras, flow, s);
  e.seconds = clock.seconds();
  return e;
}

// The true displacement on a sheet grid at window centres (col, row in cells):
// the definition of sim/piv_experiment.h (the tracer on the plane at the point
// at mid-pulse, RK4 back and on by dt/2, projected on the plane), in cells
// (u along +col = +s, v along +row = -t); NaN inside solids.
void sheet_truth_cells(const Experiment& e, const SheetGrid& grid, const InterrogationGrid& g, std::vector<double>* u,
                       std::vector<double>* v) {
  const SheetPlane& plane = e.trace.sheet;
  const SolidInteriors solids(e.trace.solids);
  const double circulation = kPeakVelocityMPerS * 2 * M_PI * (1e-3 * kCoreRadiusMm) / 0.63817;
  const FlowOutsideSolids flow(std::make_shared<LambOseenVortexFlow>(plane.origin_mm, plane.normal(), circulation,
                                                                     kCoreRadiusMm),
                               solids);
  const Eigen::Vector3d n = plane.normal();
  const double mid = 0.5 * kDtS;
  u->assign(static_cast<std::size_t>(g.size()), NAN);
  v->assign(static_cast<std::size_t>(g.size()), NAN);
  for (int r = 0; r < g.rows; ++r)
    for (int c = 0; c < g.cols; ++c) {
      const Eigen::Vector3d p =
          plane.origin_mm + grid.s_mm(g.x_px(c)) * plane.s_axis + grid.t_mm(g.y_px(r)) * plane.t_axis;
      if (solids.inside(p)) continue;
      Eigen::Vector3d a = advect_rk4_mm(flow, p, mid, -0.5 * kDtS, 4), b = advect_rk4_mm(flow, p, mid, 0.5 * kDtS, 4);
      a -= (a - plane.origin_mm).dot(n) * n;
      b -= (b - plane.origin_mm).dot(n) * n;
      const Eigen::Vector3d d = b - a;
      const std::size_t i = static_cast<std::size_t>(g.index(c, r));
      (*u)[i] = d.dot(plane.s_axis) / grid.mm_per_px;
      (*v)[i] = -d.dot(plane.t_axis) / grid.mm_per_px;
    }
}

// RMS of |measured - true| over the vectors that are not invalid, whose truth
// exists and whose window centre is usable (use: empty or per pixel), times scale.
struct Score {
  double rms_px = NAN;
  int vectors = 0;
};
Score score(const PivField& f, const std::vector<double>& tu, const std::vector<double>& tv, const cv::Mat& use,
            double scale) {
  double sum = 0;
  Score s;
  for (std::size_t i = 0; i < f.size(); ++i) {
    if (f.flags[i] == VectorFlag::invalid || !std::isfinite(tu[i]) || !std::isfinite(tv[i])) continue;
    const int x = static_cast<int>(std::lround(f.x_px(i))), y = static_cast<int>(std::lround(f.y_px(i)));
    if (!use.empty() && use.at<std::uint8_t>(y, x) == 0) continue;
    sum += std::pow(f.u_px[i] - tu[i], 2) + std::pow(f.v_px[i] - tv[i], 2);
    ++s.vectors;
  }
  if (s.vectors) s.rms_px = scale * std::sqrt(sum / s.vectors);
  return s;
}

struct Row {
  Setting setting;
  double map_s = 0, build_s = 0, frame_ms = 0;
  double masked = 0;  // of the fluid region in the reference camera's glass-removed view
  Score error;
  std::string note;
};

// Maps are traced once per (experiment, camera, samples, cut-off, reflections) and
// reused by the settings that share them; each row reports the time of its own.
struct TimedMap {
  TransportMap map;
  double seconds = 0;
};

class Chain {
 public:
  Chain(int threads, int reps, const PivOptions& piv) : threads_(threads), reps_(reps), piv_(piv) {}

  Row run(const Experiment& e, const Setting& st) {
    Row row;
    row.setting = st;
    std::fprintf(stderr, "  %s ...\n", st.label.c_str());
    // One-off: the maps (through the glass per camera, and the reference camera's glass-removed view).
    std::vector<const TransportMap*> maps;
    for (int k = 0; k < st.cameras; ++k) {
      const TimedMap& m = map(e, k, st);
      maps.push_back(&m.map);
      row.map_s += m.seconds;
    }
    const TimedMap& direct = direct_map(e, st.samples);
    row.map_s += direct.seconds;
    const double footprint = median_footprint_mm(direct.map);
    const double pitch = st.grid == GridKind::sheet_half ? 0.5 : 1.0;

    // One-off: operators, the mask, the resampler (camera grid), the prepared back projector (accumulate).
    const Stopwatch build_clock;
    const SheetGrid grid = sheet_grid_covering(e.trace.sheet, pitch * footprint);
    std::vector<CorrectionOperator> ops(maps.size());
    for (std::size_t k = 0; k < maps.size(); ++k) ops[k] = build_correction_operator(*maps[k], grid, {}, threads_);
    std::vector<CameraOperator> cams;
    for (const CorrectionOperator& op : ops) cams.push_back({&op, 1.0});
    MaskOptions mask;
    const std::vector<CellState> states = classify_cells(cams, e.trace, mask);
    const bool on_camera = st.grid == GridKind::camera;
    CorrectionOperator direct_op;
    CameraResampler resampler;
    if (on_camera) {
      direct_op = build_correction_operator(direct.map, grid, {}, threads_);
      resampler = make_camera_resampler(direct_op, states);
    }
    BackProjector projector;
    if (!st.lsq) {
      std::vector<std::uint8_t> read_cells;
      if (on_camera) read_cells = cells_read_by(resampler, grid.cell_count());
      projector = make_back_projector(cams, states, on_camera ? &read_cells : nullptr);
    }
    row.build_s = build_clock.seconds();
    if (!on_camera) direct_op = build_correction_operator(direct.map, grid, {}, threads_);  // for the masked fraction only

    // Per frame: the cameras' images of one instant -> the corrected image.
    const ExperimentCameraResult& ref = e.x.cameras.front();
    const int out_w = on_camera ? ref.width : grid.cols, out_h = on_camera ? ref.height : grid.rows;
    std::vector<cv::Mat> in_a, in_b;
    for (int k = 0; k < st.cameras; ++k) {
      in_a.push_back(as_float(e.x.cameras[static_cast<std::size_t>(k)].frame_a));
      in_b.push_back(as_float(e.x.cameras[static_cast<std::size_t>(k)].frame_b));
    }
    std::vector<float> concat;
    for (const cv::Mat& m : in_a) concat.insert(concat.end(), m.ptr<float>(0), m.ptr<float>(0) + m.total());
    const auto correct = [&](const std::vector<cv::Mat>& in, cv::Mat* out) {
      *out = cv::Mat(out_h, out_w, CV_32F);
      std::vector<float> l;
      if (!st.lsq) {
        // The prepared projector reads the cameras' frames one after the other.
        concat.clear();
        for (const cv::Mat& m : in) concat.insert(concat.end(), m.ptr<float>(0), m.ptr<float>(0) + m.total());
        l.assign(grid.cell_count(), 0.0f);
        apply_back_projector(projector, concat.data(), l.data());
      } else {
        std::vector<CameraImage> views;
        for (std::size_t k = 0; k < in.size(); ++k) views.push_back({&ops[k], in[k].ptr<float>(0), 1.0, 0.0});
        l = least_squares(views, states, back_projection(views, states));
      }
      if (on_camera) resample_to_camera(resampler, l.data(), out->ptr<float>(0));
      else std::copy(l.begin(), l.end(), out->ptr<float>(0));
    };
    cv::Mat out_a, out_b;
    std::vector<double> times;
    const int reps = st.lsq ? 1 : reps_;
    for (int r = 0; r < reps + (st.lsq ? 0 : 1); ++r) {  // accumulate: round 0 warms up
      const double ta = seconds_of([&] { correct(in_a, &out_a); });
      const double tb = seconds_of([&] { correct(in_b, &out_b); });
      if (st.lsq || r > 0) {
        times.push_back(ta);
        times.push_back(tb);
      }
    }
    row.frame_ms = 1e3 * median(times);

    // The usable mask and the masked fraction of the fluid region the reference camera sees with the glass removed.
    cv::Mat usable(out_h, out_w, CV_8U, cv::Scalar(0));
    std::size_t seen = 0, masked = 0;
    if (on_camera) {
      std::copy(resampler.pixel_valid.begin(), resampler.pixel_valid.end(), usable.ptr<std::uint8_t>(0));
      for (std::size_t p = 0; p < direct.map.pixel_count(); ++p) {
        const std::uint32_t i = direct.map.pixel_offsets[p];
        if (i == direct.map.pixel_offsets[p + 1]) continue;
        const long c = std::lround(grid.col(direct.map.s_mm[i])), r = std::lround(grid.row(direct.map.t_mm[i]));
        if (c < 0 || r < 0 || c >= grid.cols || r >= grid.rows) continue;
        if (states[static_cast<std::size_t>(r * grid.cols + c)] == CellState::inside_solid) continue;
        ++seen;
        masked += resampler.pixel_valid[p] == 0;
      }
    } else {
      for (std::size_t c = 0; c < states.size(); ++c) {
        if (states[c] == CellState::valid) usable.ptr<std::uint8_t>(0)[c] = 255;
        if (direct_op.cell_pixels[c] <= 0 || states[c] == CellState::inside_solid) continue;
        ++seen;
        masked += states[c] != CellState::valid;
      }
    }
    row.masked = seen ? double(masked) / seen : NAN;

    // PIV and its error against the truth.
    const PivField f = evaluate_piv(out_a, out_b, usable, piv_);
    if (on_camera) {
      row.error = score(f, ref.truth.u_px, ref.truth.v_px, usable, 1.0);
    } else {
      std::vector<double> tu, tv;
      sheet_truth_cells(e, grid, f.grid, &tu, &tv);
      row.error = score(f, tu, tv, usable, grid.mm_per_px / ref.mm_per_px);
    }
    std::fprintf(stderr, "    map %.2f s, build %.2f s, %.2f ms/frame, %.1f %% masked, error %.4f px (%d vectors)\n",
                 row.map_s, row.build_s, row.frame_ms, 100 * row.masked, row.error.rms_px, row.error.vectors);
    return row;
  }

 private:
  const TimedMap& map(const Experiment& e, int k, const Setting& st) {
    const auto key = std::make_tuple(&e, k, st.samples, st.min_weight, st.reflections);
    auto it = maps_.find(key);
    if (it == maps_.end()) {
      TraceOptions o;
      o.min_weight = st.min_weight;
      o.reflections = st.reflections;
      const ExperimentCamera& c = e.cameras[static_cast<std::size_t>(k)];
      TimedMap m;
      m.seconds = seconds_of([&] { m.map = build_transport_map(e.trace, c.model, c.camera_from_world, o, st.samples, threads_); });
      it = maps_.emplace(key, std::move(m)).first;
    }
    return it->second;
  }
  const TimedMap& direct_map(const Experiment& e, int samples) {
    const auto key = std::make_pair(&e, samples);
    auto it = direct_.find(key);
    if (it == direct_.end()) {
      const ExperimentCamera& c = e.cameras.front();
      TimedMap m;
      m.seconds = seconds_of([&] { m.map = glass_removed_map(e.trace, c.model, c.camera_from_world, samples, threads_); });
      it = direct_.emplace(key, std::move(m)).first;
    }
    return it->second;
  }

  int threads_, reps_;
  PivOptions piv_;
  std::map<std::tuple<const Experiment*, int, int, double, bool>, TimedMap> maps_;
  std::map<std::pair<const Experiment*, int>, TimedMap> direct_;
};

// Indices of the rows on the Pareto front (no other row is at least as fast and
// at least as accurate, and strictly better in one), by time.
std::vector<std::size_t> pareto_front(const std::vector<Row>& rows) {
  std::vector<std::size_t> front;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (!std::isfinite(rows[i].error.rms_px)) continue;
    bool dominated = false;
    for (std::size_t j = 0; j < rows.size() && !dominated; ++j) {
      if (j == i || !std::isfinite(rows[j].error.rms_px)) continue;
      const double ti = rows[i].frame_ms, tj = rows[j].frame_ms, ei = rows[i].error.rms_px, ej = rows[j].error.rms_px;
      dominated = tj <= ti && ej <= ei && (tj < ti || ej < ei);
    }
    if (!dominated) front.push_back(i);
  }
  std::sort(front.begin(), front.end(), [&](std::size_t a, std::size_t b) { return rows[a].frame_ms < rows[b].frame_ms; });
  return front;
}

// Error against time per frame (both log scale), each setting a numbered point
// with its label in the legend on the right, the front a line, the default
// ringed; the glass-free PIV's error a dashed line.
void write_pareto_png(const std::vector<Row>& rows, const std::vector<std::size_t>& front, double no_glass_px,
                      const std::string& title, const std::string& path) {
  const int W = 1280, H = 720, left = 70, plot_right = 880, top = 50, bottom = 70;
  cv::Mat img(H, W, CV_8UC3, cv::Scalar(255, 255, 255));
  double tmin = 1e300, tmax = 0, emin = no_glass_px > 0 ? no_glass_px : 1e300, emax = no_glass_px;
  for (const Row& r : rows)
    if (std::isfinite(r.error.rms_px)) {
      tmin = std::min(tmin, r.frame_ms);
      tmax = std::max(tmax, r.frame_ms);
      emin = std::min(emin, r.error.rms_px);
      emax = std::max(emax, r.error.rms_px);
    }
  const double lx0 = std::floor(std::log10(tmin)), lx1 = std::ceil(std::log10(tmax));
  const double ly0 = std::floor(std::log10(emin)), ly1 = std::ceil(std::log10(emax));
  const auto X = [&](double ms) { return left + (std::log10(ms) - lx0) / (lx1 - lx0) * (plot_right - left); };
  const auto Y = [&](double e) { return H - bottom - (std::log10(e) - ly0) / (ly1 - ly0) * (H - top - bottom); };
  const cv::Scalar grey(200, 200, 200), light(235, 235, 235), black(0, 0, 0), blue(180, 90, 20), red(30, 30, 220);
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  for (double d = lx0; d <= lx1; d += 1)
    for (double m : {1.0, 2.0, 5.0}) {
      const double ms = m * std::pow(10.0, d);
      if (std::log10(ms) > lx1 + 1e-9) continue;
      const int x = static_cast<int>(X(ms));
      cv::line(img, {x, top}, {x, H - bottom}, m == 1 ? grey : light, 1);
      cv::putText(img, fmt("%g", ms), {x - 10, H - bottom + 18}, font, 0.45, black, 1, cv::LINE_AA);
    }
  for (double d = ly0; d <= ly1; d += 1)
    for (double m : {1.0, 2.0, 5.0}) {
      const double e = m * std::pow(10.0, d);
      if (std::log10(e) > ly1 + 1e-9) continue;
      const int y = static_cast<int>(Y(e));
      cv::line(img, {left, y}, {plot_right, y}, m == 1 ? grey : light, 1);
      cv::putText(img, fmt("%g", e), {left - 45, y + 5}, font, 0.45, black, 1, cv::LINE_AA);
    }
  cv::rectangle(img, {left, top}, {plot_right, H - bottom}, black, 1);
  cv::putText(img, "correction time per frame (ms, log scale)", {left + 250, H - 25}, font, 0.55, black, 1, cv::LINE_AA);
  cv::putText(img, "PIV RMS error vs truth (px, log scale)", {10, top - 12}, font, 0.55, black, 1, cv::LINE_AA);
  cv::putText(img, title, {left + 380, top - 12}, font, 0.5, black, 1, cv::LINE_AA);
  if (no_glass_px > 0) {
    const int y = static_cast<int>(Y(no_glass_px));
    for (int x = left; x < plot_right; x += 12) cv::line(img, {x, y}, {std::min(x + 6, plot_right), y}, blue, 1);
    cv::putText(img, fmt("no glass %.3f px", no_glass_px), {plot_right - 150, y - 6}, font, 0.45, blue, 1, cv::LINE_AA);
  }
  for (std::size_t k = 1; k < front.size(); ++k) {
    const Row &a = rows[front[k - 1]], &b = rows[front[k]];
    cv::line(img, {int(X(a.frame_ms)), int(Y(a.error.rms_px))}, {int(X(b.frame_ms)), int(Y(b.error.rms_px))}, red, 2,
             cv::LINE_AA);
  }
  int legend_y = top + 10;
  cv::putText(img, "settings (red: on the Pareto front; ringed: default)", {plot_right + 15, legend_y}, font, 0.42,
              black, 1, cv::LINE_AA);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    const bool on_front = std::find(front.begin(), front.end(), i) != front.end();
    const std::string id = std::to_string(i + 1);
    legend_y += 22;
    cv::putText(img, id + "  " + r.setting.label + (r.setting.is_default ? " (default)" : ""),
                {plot_right + 15, legend_y}, font, 0.42, on_front ? red : black, 1, cv::LINE_AA);
    if (!std::isfinite(r.error.rms_px)) continue;
    const cv::Point p(int(X(r.frame_ms)), int(Y(r.error.rms_px)));
    cv::circle(img, p, 4, on_front ? red : black, cv::FILLED, cv::LINE_AA);
    if (r.setting.is_default) cv::circle(img, p, 9, red, 2, cv::LINE_AA);
    // Numbers fanned around the point so that neighbours stay readable.
    const int k = static_cast<int>(i % 4);
    const cv::Point off = k == 0 ? cv::Point(6, -6) : k == 1 ? cv::Point(6, 16) : k == 2 ? cv::Point(-20, -6) : cv::Point(-20, 16);
    cv::putText(img, id, p + off, font, 0.42, on_front ? red : black, 1, cv::LINE_AA);
  }
  if (!cv::imwrite(path, img)) throw std::runtime_error("cannot write " + path);
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

  std::vector<Setting> settings;
  const auto add = [&](Setting s) { settings.push_back(std::move(s)); };
  Setting d;
  d.label = "default";
  d.is_default = true;
  add(d);
  {
    Setting s = d;
    s.is_default = false;
    s.label = "2x2 samples";
    s.samples = 2;
    add(s);
    s.label = "3x3 samples";
    s.samples = 3;
    add(s);
    s = d;
    s.is_default = false;
    s.label = "cut 1e-1";
    s.min_weight = 1e-1;
    add(s);
    s.label = "cut 1e-3";
    s.min_weight = 1e-3;
    add(s);
    s = d;
    s.is_default = false;
    s.label = "no reflections";
    s.reflections = false;
    add(s);
    s = d;
    s.is_default = false;
    s.label = "sheet 1x";
    s.grid = GridKind::sheet_1x;
    add(s);
    s.label = "sheet 0.5x";
    s.grid = GridKind::sheet_half;
    add(s);
    s = d;
    s.is_default = false;
    s.label = "least squares";
    s.lsq = true;
    add(s);
    s.label = "lsq, sheet 1x";
    s.grid = GridKind::sheet_1x;
    add(s);
    s = d;
    s.is_default = false;
    s.label = "cheapest: cut 1e-1, no refl.";
    s.min_weight = 1e-1;
    s.reflections = false;
    add(s);
    s = d;
    s.is_default = false;
    s.label = "richest: 3x3, cut 1e-3, lsq";
    s.samples = 3;
    s.min_weight = 1e-3;
    s.lsq = true;
    add(s);
    if (five) {
      s = d;
      s.is_default = false;
      s.experiment = 1;
      s.label = "5-cam scene: centre alone";
      add(s);
      s.label = "5-cam scene: centre alone, sheet 1x";
      s.grid = GridKind::sheet_1x;
      add(s);
      s.cameras = 5;
      s.label = "5 cams, sheet 1x";
      add(s);
      s.label = "5 cams, camera grid";
      s.grid = GridKind::camera;
      add(s);
      s.label = "5 cams, lsq, sheet 1x";
      s.grid = GridKind::sheet_1x;
      s.lsq = true;
      add(s);
    }
  }

  Chain chain(threads, reps, piv);
  std::vector<Row> rows;
  for (const Setting& s : settings) {
    std::fprintf(stderr, "setting %zu of %zu:\n", rows.size() + 1, settings.size());
    rows.push_back(chain.run(experiments[static_cast<std::size_t>(s.experiment)], s));
  }

  // References: PIV on the glass-free and on the uncorrected pairs of the one-camera experiment,
  // scored where the default's mask keeps the window centre.
  const ExperimentCameraResult& ref = experiments[0].x.cameras.front();
  const PivField no_glass = evaluate_piv(as_float(ref.frame_a_ref), as_float(ref.frame_b_ref), cv::Mat(), piv);
  const PivField raw = evaluate_piv(as_float(ref.frame_a), as_float(ref.frame_b), cv::Mat(), piv);
  const Score no_glass_all = score(no_glass, ref.truth.u_px, ref.truth.v_px, cv::Mat(), 1.0);
  const Score raw_all = score(raw, ref.truth.u_px, ref.truth.v_px, cv::Mat(), 1.0);

  const std::vector<std::size_t> front = pareto_front(rows);
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
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    const Setting& s = r.setting;
    const bool on_front = std::find(front.begin(), front.end(), i) != front.end();
    std::printf("| %zu | %s%s | %d | %g | %s | %s | %s | %d%s | %.2f | %.2f | %.2f | %.1f %% | %d | %.4f | %s |\n", i + 1,
                s.is_default ? "**default**" : s.label.c_str(), "", s.samples, s.min_weight, s.reflections ? "on" : "off",
                grid_name(s.grid), s.lsq ? "least squares" : "accumulate", s.cameras,
                s.experiment == 1 ? " (5-cam scene)" : "", r.map_s, r.build_s, r.frame_ms, 100 * r.masked,
                r.error.vectors, r.error.rms_px, on_front ? "yes" : "");
  }
  std::printf("\nReferences (%s, %dx%d, every vector with a truth): no glass %.4f px (%d vectors), uncorrected "
              "%.4f px (%d vectors).\n",
              experiments[0].scene_name.c_str(), ref.width, ref.height, no_glass_all.rms_px, no_glass_all.vectors,
              raw_all.rms_px, raw_all.vectors);
  const auto def = std::find_if(rows.begin(), rows.end(), [](const Row& r) { return r.setting.is_default; });
  const bool def_on_front = std::find(front.begin(), front.end(), std::size_t(def - rows.begin())) != front.end();
  std::printf("The default settings are %son the Pareto front of error against correction time per frame.\n",
              def_on_front ? "" : "NOT ");
  write_pareto_png(rows, front, no_glass_all.rms_px,
                   fmt("chain_bench: reactor binned %.0f, PIV 64->32 px vs truth", binning), png);
  std::printf("Pareto plot: %s; bench ran %.0f s\n", png.c_str(), total.seconds());
  return 0;
}
