#pragma once
// A simulated PIV experiment with its ground truth (DESIGN.md section 4,
// docs/simulation.md "Simulated experiments"): tracers seeded in the sheet
// slab outside the solids, carried by a Flow with RK4 over the pulse
// separation, drawn on the sheet as Gaussian particle images, rendered through
// the glass with each camera's transport map (render/forward_render.h) and
// recorded by a sensor model; beside them the same camera with the glass
// removed, and the true displacement. No I/O.
//
// Approximation: each tracer is drawn on the sheet plane at its (s, t), with
// its out-of-plane position only weighting its brightness
// (sheet_relative_intensity). The sheet (about 1 mm) is thin compared with the
// optics' depth of field, so the parallax between a tracer and its projection
// on the plane is neglected; the transport map, made for the plane, then
// images every tracer.
//
// Ground truth: the displacement of the tracer that sits on the sheet plane at
// the pixel's sheet point at the middle of the pulse pair, from RK4 back by
// dt/2 (frame A) and on by dt/2 (frame B), each position projected on the
// plane. It is what central-difference window deformation (Wereley & Meinhart
// 2001; piv/piv_evaluate.h) measures at the window centre, exact to second
// order in the velocity gradient.
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "calib/camera_model.h"
#include "calib/rigid_transform.h"
#include "correct/sheet_grid.h"
#include "render/path_tracer.h"
#include "render/scene.h"
#include "render/transport_map.h"
#include "sim/flows.h"
#include "sim/sensor.h"

namespace glasspiv {

struct ExperimentCamera {
  std::string name;
  CameraModel model;
  RigidTransform camera_from_world;
};

// The PIV design rules the warnings cite (Keane & Adrian 1990; Raffel et al.,
// Particle Image Velocimetry, 3rd ed., sections 6.1 and 8.1).
constexpr double kQuarterRuleWindowPx = 32;  // in-plane displacement below a quarter of this window

struct PivExperimentSettings {
  double dt_s = 1e-3;     // pulse separation
  double time_a_s = 0;    // time of frame A
  // Tracers per pixel of the first camera's glass-removed view, counting the
  // sheet's thickness (sim/tracers.h tracers_per_pixel): the 0.02-0.05 rule.
  double density_ppp = 0.03;
  // Particle image diameter (1/e^2) in px of the first camera's glass-removed view.
  double particle_px = 2.5;
  double peak_radiance = 1;  // sheet radiance at the centre of a tracer on the sheet's plane
  SensorModel sensor;
  std::uint64_t seed = 1;    // tracers and every frame's noise
  int rk4_sub_steps = 4;
  // The particle texture's pitch: the first camera's pixel on the sheet / this,
  // coarser where the texture would exceed max_texels (PivExperiment::texels_per_px says).
  double texels_per_px = 4;
  double max_texels = double(1 << 26);
  TraceOptions trace;        // for the maps through the glass
  int samples_per_axis = 1;  // map samples per pixel axis
  // Where each camera's pixel truth is evaluated (indexed like the cameras):
  // x_px columns times y_px rows of its glass-removed view, e.g. the PIV grid's
  // window centres. A camera without one, or with an empty one: every pixel.
  struct TruthGrid {
    std::vector<double> x_px, y_px;
  };
  std::vector<TruthGrid> truth_grids;
  // The sheet truth's cell: this many px of the first camera's view on the sheet.
  double sheet_truth_step_px = 16;
  bool keep_maps = false;    // keep each camera's transport maps in the result
  int threads = 0;           // <= 0: all cores

  // ExperimentSettingError naming the field ("dt_s", "density_ppp", ...).
  void check() const;
};

// A setting of the experiment, or the flow, that cannot be simulated: `setting`
// names the PivExperimentSettings field ("dt_s", "density_ppp", ...) or "flow",
// so that a command can name its own option instead of the scene.
class ExperimentSettingError : public std::invalid_argument {
 public:
  ExperimentSettingError(std::string setting, const std::string& problem)
      : std::invalid_argument(problem), setting_(std::move(setting)) {}
  const std::string& setting() const { return setting_; }

 private:
  std::string setting_;
};

// The true displacement of frame B relative to frame A on one camera's
// glass-removed view, px, u along +x (columns), v along +y (rows), at
// x_px[c], y_px[r]; NaN where the pixel does not see the sheet or its sheet
// point is inside a solid.
struct CameraTruth {
  std::vector<double> x_px, y_px;
  std::vector<double> u_px, v_px;  // row-major, y_px.size() x x_px.size()
  double max_displacement_px = 0;  // largest |(u, v)|
};

// The same on the rectified sheet grid: in-plane displacement (ds, dt) in mm
// and the flow's velocity at the cell centre at mid-pulse in m/s (s, t and
// normal components). NaN inside solids.
struct SheetTruth {
  SheetGrid grid;
  std::vector<double> ds_mm, dt_mm;
  std::vector<double> velocity_s_m_per_s, velocity_t_m_per_s, velocity_n_m_per_s;
};

struct ExperimentCameraResult {
  std::string name;
  int width = 0, height = 0;
  cv::Mat frame_a, frame_b;          // through the glass, CV_16UC1 counts
  cv::Mat frame_a_ref, frame_b_ref;  // the glass removed, CV_16UC1 counts
  cv::Mat radiance_a, radiance_b, radiance_a_ref, radiance_b_ref;  // before the sensor, CV_32FC1
  CameraTruth truth;
  double mm_per_px = 0;  // median pixel footprint on the sheet, glass removed
  TransportMap map, glass_removed_map;  // when keep_maps
};

struct PivExperiment {
  std::vector<ExperimentCameraResult> cameras;
  SheetTruth sheet_truth;
  std::size_t tracers = 0;
  double tracers_per_mm3 = 0;
  double particle_diameter_mm = 0;
  double mm_per_texel = 0, texels_per_px = 0;  // the texture as made
  double max_displacement_px = 0;              // over all cameras
  std::vector<std::string> warnings;           // design rules broken (one-quarter rule, density, size)
};

// Runs the experiment for every camera. progress (optional) gets the fraction
// done in [0, 1] from the calling thread; it must not throw. Throws
// ExperimentSettingError for bad settings, for a flow whose speed on the sheet
// is not finite or moves tracers farther than the sheet's larger extent between
// the frames ("dt_s": shorten it, or check the flow), and for a flow that
// carries a tracer to a non-finite position ("flow"); std::invalid_argument for
// no cameras and when the first camera does not see the sheet with the glass
// removed.
PivExperiment simulate_piv_experiment(const TraceScene& scene, const Sheet& sheet,
                                      const std::vector<ExperimentCamera>& cameras, const Flow& flow,
                                      const PivExperimentSettings& settings,
                                      const std::function<void(double fraction)>& progress = {});

// The one-quarter rule's warning for a largest displacement (empty when it holds).
std::string quarter_rule_warning(double max_displacement_px);

}  // namespace glasspiv
