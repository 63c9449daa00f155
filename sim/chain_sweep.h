#pragma once
// Run time against error of the whole chain on one simulated experiment
// (sim/piv_experiment.h): for each setting of the correction's knobs, trace
// the maps, build the operators, mask, resampler and back projector, correct
// frames A and B (timed per frame), run PIV on the corrected pair and score it
// against the truth. bench/chain_bench sweeps every knob; glasspiv demo draws a
// smaller sweep's Pareto plot. No I/O.
//
// Each setting changes knobs of glasspiv correct's defaults (ChainSetting's
// defaults are those: 1 sample per pixel axis, correction_trace_options(), the
// glass-removed camera grid at the reference camera's own footprint,
// accumulate = the prepared back-projection, one camera). Errors are in px of
// the reference camera's glass-removed view (sheet-grid errors converted by
// the grid's pitch over the camera's median footprint), over the vectors whose
// window centre the mask keeps. The frames must have been rendered through a
// richer map than any setting corrects with, or a setting inverts its own
// forward model.
#include <cstddef>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include <opencv2/core.hpp>

#include "correct/cell_mask.h"
#include "correct/correction_defaults.h"
#include "piv/piv_evaluate.h"
#include "render/path_tracer.h"
#include "render/transport_map.h"
#include "sim/piv_experiment.h"
#include "sim/piv_score.h"

namespace glasspiv {

enum class ChainGrid { camera, sheet_1x, sheet_half };
const char* chain_grid_name(ChainGrid grid);  // "camera (glass removed)", "sheet 1x", "sheet 0.5x"

struct ChainSetting {
  std::string label;
  int samples = 1;  // map samples per pixel axis
  double min_weight = correction_trace_options().min_weight;
  bool reflections = correction_trace_options().reflections;
  ChainGrid grid = ChainGrid::camera;
  bool least_squares = false;  // false: accumulate (the prepared back-projection)
  int cameras = 1;             // of the experiment's cameras, the reference camera first
  bool is_default = false;

  TraceOptions trace_options() const;  // correction_trace_options() with this cut-off and reflections
};

struct ChainRow {
  ChainSetting setting;
  double map_s = 0;    // the maps this setting needs (each traced once per sweep; every row that needs it counts it)
  double build_s = 0;  // operators, mask, resampler, back projector
  double frame_ms = 0; // correction per frame: the median over frames A and B and the repeats
  double masked = 0;   // of the fluid region the reference camera sees with the glass removed
  PivScore error;      // px of the reference camera's glass-removed view
};

// What a row corrected, for pictures (ChainSweep::run's optional output).
struct ChainImages {
  cv::Mat corrected_a, corrected_b;  // CV_32F, camera or sheet grid
  cv::Mat usable;                    // CV_8U, 255 where the mask keeps the pixel or cell
  std::vector<CellState> states;     // the sheet grid's cells (correct/cell_mask.h)
  PivField field;
};

struct ChainSweepOptions {
  int threads = 0;  // <= 0: all cores
  int repeats = 5;  // timed corrections per frame after one warm-up (least squares: one, no warm-up)
};

class ChainSweep {
 public:
  // The experiment's cameras (the reference first, as the experiment simulated
  // them) and its result; all three must outlive the sweep. piv: the
  // evaluation of every corrected pair.
  ChainSweep(const TraceScene& scene, const std::vector<ExperimentCamera>& cameras, const PivExperiment& experiment,
             const PivOptions& piv, const ChainSweepOptions& options = {});

  // Throws std::invalid_argument for a setting asking more cameras than the
  // experiment has, or samples < 1.
  ChainRow run(const ChainSetting& setting, ChainImages* images = nullptr);

  // Camera k's map through the glass (traced on first use, then kept) and
  // the reference camera's glass-removed map.
  const TransportMap& map(int camera, int samples, double min_weight, bool reflections);
  const TransportMap& glass_removed_map(int samples);

 private:
  struct TimedMap {
    TransportMap map;
    double seconds = 0;
  };
  const TimedMap& timed_map(int camera, const ChainSetting& setting);
  const TimedMap& timed_glass_removed_map(int samples);

  const TraceScene& scene_;
  const std::vector<ExperimentCamera>& cameras_;
  const PivExperiment& experiment_;
  PivOptions piv_;
  ChainSweepOptions options_;
  std::map<std::tuple<int, int, double, bool>, TimedMap> maps_;
  std::map<int, TimedMap> glass_removed_;
};

// Indices of the rows on the Pareto front of error against correction time
// per frame, by time: a row is off it when another is at least as fast and at
// least as accurate and better in one of the two, errors closer than
// error_tolerance (relative) counting as equal. Rows without an error are
// never on it.
std::vector<std::size_t> pareto_front(const std::vector<ChainRow>& rows, double error_tolerance);

// Whether row index `row` is among `front`'s.
bool on_front(const std::vector<std::size_t>& front, std::size_t row);

// The tolerance the bench and the demo use: a difference of under 1 % of the
// error is not worth paying time for (for scale, the RMS over the demo's ~250
// vectors has a sampling error of ~1/sqrt(2 * 250) = 4.5 % of itself).
constexpr double kParetoErrorTolerance = 0.01;

}  // namespace glasspiv
