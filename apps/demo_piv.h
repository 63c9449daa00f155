#pragma once
// The demo's PIV step: a simulated experiment in the reactor (sim/piv_experiment.h)
// with an analytic flow, a Lamb-Oseen vortex centred on the sheet, recorded by
// the one camera of reactor.yaml; PIV (piv/piv_evaluate.h) on the glass-removed
// reference pair, on the distorted pair corrected onto the glass-removed camera
// grid, and on the distorted pair as recorded, each scored against the exact
// displacement; the sheet grid's masked area with one camera and with the five
// of reactor_5cams.yaml, and PIV on the sheet grid reconstructed from all five
// and from the centre one alone (apps/demo_piv_sheet.h); pictures, an HTML
// page and metrics.json.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "apps/demo_piv_sheet.h"
#include "calib/camera.h"
#include "sim/chain_sweep.h"

namespace glasspiv {

// {"rms_px", "max_px", "vectors"} (null where there is no figure).
nlohmann::json score_json(const PivScore& s);

struct DemoPivSummary {
  int width = 0, height = 0;  // the camera, binned
  int binning = 0;
  // The flow: a steady Lamb-Oseen vortex about the sheet normal through the sheet's origin.
  double core_radius_mm = 0, circulation_m2_per_s = 0, dt_s = 0;
  // The experiment.
  std::size_t tracers = 0;
  double density_ppp = 0, particle_px = 0, max_displacement_px = 0;
  int bit_depth = 0;
  std::vector<std::string> warnings;
  double simulate_seconds = 0;
  // PIV: windows (px, one per pass) and overlap; vectors of the final grid.
  std::vector<int> window_px;
  double overlap = 0;
  int grid_cols = 0, grid_rows = 0;
  double piv_seconds = 0;  // the reference and uncorrected evaluations (the corrected one: the sweep's first row)
  // Scored where the corrected frames are usable and the truth exists (no glass:
  // wherever the truth exists).
  PivScore no_glass, corrected, uncorrected;
  PivScore corrected_inner;  // windows with no masked pixel at all (what the mask's rim costs)
  // Corrected with the camera the demo recovered (own calibration and alignment) instead of the truth.
  bool own_model = false;
  PivScore corrected_own_model;
  double own_pose_error_mm = 0;             // its camera centre from the truth's
  double own_projection_difference_px = 0;  // its intrinsics against the truth's, RMS over the image at 1 m
  double own_projection_difference_rotated_px = 0;  // the same after the rotation it implies
  double own_model_seconds = 0;
  // Run time against error (sim/chain_sweep.h): glasspiv correct's defaults
  // and one knob changed per row, the Pareto front (indices into sweep) and its plot.
  std::vector<ChainRow> sweep;
  std::vector<std::size_t> sweep_front;
  std::string pareto_png;
  double sweep_seconds = 0;
  double masked_pixel_fraction = 0;  // of the camera grid, by the correction's mask
  // The rectified sheet grid: masked fraction of its fluid region (correct/cell_mask.h).
  double one_camera_sheet_masked = 0;  // reactor.yaml's camera, on its grid
  int five_binning = 0;
  double five_seconds = 0;
  SheetPivSummary sheet;  // reactor_5cams.yaml: PIV on the sheet grid, five cameras and the centre one alone
  std::string distorted_png, corrected_png, true_field_png, measured_field_png, error_corrected_png,
      error_uncorrected_png, vectors_txt, html,
      metrics_json;
  double seconds = 0;
};

// scenes_dir holds the embedded reactor.yaml and reactor_5cams.yaml (with
// their camera files where the scenes expect them); binning: the camera's
// read-out binning; five_cache_dir: where the five cameras' maps and
// operators are cached (the correction step's cache, validated on reading; ""
// for none), at twice that binning as the correction step uses. recovered
// (optional): the camera the demo calibrated and aligned itself (binned, with
// its pose); the frames are corrected with it too and scored against the same truth.
DemoPivSummary run_piv_demo(const std::string& folder, const std::string& scenes_dir, int binning,
                            const std::string& five_cache_dir, const Camera* recovered = nullptr);

}  // namespace glasspiv
