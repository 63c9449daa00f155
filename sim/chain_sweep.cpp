#include "sim/chain_sweep.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "correct/back_projector.h"
#include "correct/camera_resampler.h"
#include "correct/cell_mask.h"
#include "correct/correction_operator.h"
#include "correct/reconstruct.h"
#include "correct/sheet_grid.h"
#include "util/stopwatch.h"

namespace glasspiv {
namespace {

template <class F>
double seconds_of(F&& f) {
  const Stopwatch clock;
  f();
  return clock.seconds();
}

cv::Mat as_float(const cv::Mat& counts) {
  cv::Mat f;
  counts.convertTo(f, CV_32F);
  return f;
}

}  // namespace

const char* chain_grid_name(ChainGrid grid) {
  return grid == ChainGrid::camera ? "camera (glass removed)" : grid == ChainGrid::sheet_1x ? "sheet 1x" : "sheet 0.5x";
}

TraceOptions ChainSetting::trace_options() const {
  TraceOptions o = correction_trace_options();
  o.min_weight = min_weight;
  o.reflections = reflections;
  return o;
}

ChainSweep::ChainSweep(const TraceScene& scene, const std::vector<ExperimentCamera>& cameras,
                       const PivExperiment& experiment, const PivOptions& piv, const ChainSweepOptions& options)
    : scene_(scene), cameras_(cameras), experiment_(experiment), piv_(piv), options_(options) {
  if (cameras.empty() || experiment.cameras.size() != cameras.size())
    throw std::invalid_argument("chain sweep: the experiment's cameras and its result differ");
  piv_.check();
}

const ChainSweep::TimedMap& ChainSweep::timed_map(int camera, const ChainSetting& st) {
  const auto key = std::make_tuple(camera, st.samples, st.min_weight, st.reflections);
  auto it = maps_.find(key);
  if (it == maps_.end()) {
    const ExperimentCamera& c = cameras_[static_cast<std::size_t>(camera)];
    TimedMap m;
    m.seconds = seconds_of([&] {
      m.map = build_transport_map(scene_, c.model, c.camera_from_world, st.trace_options(), st.samples, options_.threads);
    });
    it = maps_.emplace(key, std::move(m)).first;
  }
  return it->second;
}

const ChainSweep::TimedMap& ChainSweep::timed_glass_removed_map(int samples) {
  auto it = glass_removed_.find(samples);
  if (it == glass_removed_.end()) {
    const ExperimentCamera& c = cameras_.front();
    TimedMap m;
    m.seconds = seconds_of(
        [&] { m.map = glasspiv::glass_removed_map(scene_, c.model, c.camera_from_world, samples, options_.threads); });
    it = glass_removed_.emplace(samples, std::move(m)).first;
  }
  return it->second;
}

const TransportMap& ChainSweep::map(int camera, int samples, double min_weight, bool reflections) {
  ChainSetting st;
  st.samples = samples;
  st.min_weight = min_weight;
  st.reflections = reflections;
  return timed_map(camera, st).map;
}

const TransportMap& ChainSweep::glass_removed_map(int samples) { return timed_glass_removed_map(samples).map; }

ChainRow ChainSweep::run(const ChainSetting& st, ChainImages* images) {
  if (st.cameras < 1 || st.cameras > static_cast<int>(cameras_.size()))
    throw std::invalid_argument("chain sweep: setting '" + st.label + "' asks for more cameras than the experiment has");
  if (st.samples < 1) throw std::invalid_argument("chain sweep: setting '" + st.label + "' has samples < 1");
  ChainRow row;
  row.setting = st;
  const int threads = options_.threads;

  // One-off: the maps (through the glass per camera, and the reference camera's glass-removed view).
  std::vector<const TransportMap*> maps;
  for (int k = 0; k < st.cameras; ++k) {
    const TimedMap& m = timed_map(k, st);
    maps.push_back(&m.map);
    row.map_s += m.seconds;
  }
  const TimedMap& direct = timed_glass_removed_map(st.samples);
  row.map_s += direct.seconds;
  const double footprint = median_footprint_mm(direct.map);
  const double pitch = st.grid == ChainGrid::sheet_half ? 0.5 : 1.0;

  // One-off: operators, the mask, the resampler (camera grid), the prepared back projector (accumulate).
  const Stopwatch build_clock;
  const SheetGrid grid = sheet_grid_covering(scene_.sheet, pitch * footprint);
  std::vector<CorrectionOperator> ops(maps.size());
  for (std::size_t k = 0; k < maps.size(); ++k) ops[k] = build_correction_operator(*maps[k], grid, {}, threads);
  std::vector<CameraOperator> cams;
  for (const CorrectionOperator& op : ops) cams.push_back({&op, 1.0});
  const std::vector<CellState> states = classify_cells(cams, scene_);
  const bool on_camera = st.grid == ChainGrid::camera;
  CorrectionOperator direct_op;
  CameraResampler resampler;
  if (on_camera) {
    direct_op = build_correction_operator(direct.map, grid, {}, threads);
    resampler = make_camera_resampler(direct_op, states);
  }
  BackProjector projector;
  if (!st.least_squares) {
    std::vector<std::uint8_t> read_cells;
    if (on_camera) read_cells = cells_read_by(resampler, grid.cell_count());
    projector = make_back_projector(cams, states, on_camera ? &read_cells : nullptr);
  }
  row.build_s = build_clock.seconds();
  if (!on_camera) direct_op = build_correction_operator(direct.map, grid, {}, threads);  // the masked fraction only

  // Per frame: the cameras' images of one instant -> the corrected image.
  const ExperimentCameraResult& ref = experiment_.cameras.front();
  const int out_w = on_camera ? ref.width : grid.cols, out_h = on_camera ? ref.height : grid.rows;
  std::vector<cv::Mat> in_a, in_b;
  for (int k = 0; k < st.cameras; ++k) {
    in_a.push_back(as_float(experiment_.cameras[static_cast<std::size_t>(k)].frame_a));
    in_b.push_back(as_float(experiment_.cameras[static_cast<std::size_t>(k)].frame_b));
  }
  std::vector<float> concat;
  const auto correct = [&](const std::vector<cv::Mat>& in, cv::Mat* out) {
    *out = cv::Mat(out_h, out_w, CV_32F);
    std::vector<float> l;
    if (!st.least_squares) {
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
  const int repeats = st.least_squares ? 1 : std::max(1, options_.repeats);
  for (int r = 0; r < repeats + (st.least_squares ? 0 : 1); ++r) {  // accumulate: round 0 warms up
    const double ta = seconds_of([&] { correct(in_a, &out_a); });
    const double tb = seconds_of([&] { correct(in_b, &out_b); });
    if (st.least_squares || r > 0) {
      times.push_back(ta);
      times.push_back(tb);
    }
  }
  std::sort(times.begin(), times.end());  // an even count: the mean of the middle two
  row.frame_ms = 1e3 * 0.5 * (times[times.size() / 2 - 1] + times[times.size() / 2]);

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

  // PIV and its error against the truth, in px of the reference camera's glass-removed view.
  PivField f = evaluate_piv(out_a, out_b, usable, piv_);
  if (on_camera) {
    row.error = score_vectors(f, camera_truth_on_vectors(f, ref.truth, usable));
  } else {
    row.error = score_vectors(f, sheet_truth_on_vectors(f, grid, experiment_.sheet_truth, usable));
    const double scale = grid.mm_per_px / ref.mm_per_px;
    row.error.rms_px *= scale;
    row.error.max_px *= scale;
  }
  if (images) {
    images->corrected_a = out_a;
    images->corrected_b = out_b;
    images->usable = usable;
    images->states = states;
    images->field = std::move(f);
  }
  return row;
}

std::vector<std::size_t> pareto_front(const std::vector<ChainRow>& rows, double error_tolerance) {
  std::vector<std::size_t> front;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (!std::isfinite(rows[i].error.rms_px)) continue;
    bool dominated = false;
    for (std::size_t j = 0; j < rows.size() && !dominated; ++j) {
      if (j == i || !std::isfinite(rows[j].error.rms_px)) continue;
      const double ti = rows[i].frame_ms, tj = rows[j].frame_ms, ei = rows[i].error.rms_px, ej = rows[j].error.rms_px;
      const bool as_accurate = ej <= ei * (1 + error_tolerance);
      const bool better = tj < ti || ej < ei * (1 - error_tolerance);
      dominated = tj <= ti && as_accurate && better;
    }
    if (!dominated) front.push_back(i);
  }
  std::sort(front.begin(), front.end(), [&](std::size_t a, std::size_t b) { return rows[a].frame_ms < rows[b].frame_ms; });
  return front;
}

bool on_front(const std::vector<std::size_t>& front, std::size_t row) {
  return std::find(front.begin(), front.end(), row) != front.end();
}

}  // namespace glasspiv
