#pragma once
// The demo's five-camera PIV on the rectified sheet grid (issue 15, item 8:
// one camera against five). A simulated experiment recorded by every camera
// of a multi-camera scene through the glass (sim/piv_experiment.h); frames A
// and B reconstructed on the sheet grid (correct/reconstruct.h: back-projection,
// then least squares warm-started from it) from all cameras' distorted frames
// and from the centre camera's alone; PIV (piv/piv_evaluate.h) on each pair
// with the valid cells as the mask, scored against the experiment's sheet
// truth; the masked fraction of the sheet's fluid region for both, and
// pictures of the reconstructed frame A and of the error per vector.
//
// Sheet-grid pixels: the grid's pitch is the centre camera's median pixel
// footprint on the sheet with the glass removed (the correction's default),
// column along +s, row along -t (correct/sheet_grid.h). So a PIV vector
// (u_px, v_px) on the grid is (ds, -dt) / mm_per_px.
#include <cmath>
#include <string>
#include <vector>

#include "apps/correction_setup.h"
#include "calib/lens_maps.h"
#include "piv/piv_evaluate.h"
#include "sim/flows.h"
#include "sim/piv_experiment.h"
#include "sim/piv_score.h"

namespace glasspiv {

// One set of cameras (all, or the centre one alone) on the sheet grid.
struct SheetPivCase {
  std::vector<std::string> cameras;  // the scene's names
  double masked_fraction = 0;        // of the sheet's fluid region: cells not valid (correct/cell_mask.h)
  PivScore least_squares;       // PIV on the least-squares frames (the result)
  PivScore back_projection;     // PIV on the back-projected frames (the published method's)
  // Mean measured displacement over least_squares' scored vectors, grid px (+u: +s, +v: -t).
  double mean_u_px = NAN, mean_v_px = NAN;
  int lsq_iterations_a = 0, lsq_iterations_b = 0;
  std::string frame_a_png;  // least-squares frame A, masked cells dark
  std::string error_png;    // |measured - true| per vector (least squares), grey where not scored
};

struct SheetPivSummary {
  int binning = 0;                        // every camera's read-out binning
  std::string centre_camera;              // the grid's pitch and the density and particle size follow it
  int width = 0, height = 0;              // the centre camera, binned
  SheetGrid grid;                         // the rectified sheet grid
  // The experiment (particle_px and density_ppp in px of the centre camera's
  // glass-removed view, which is the grid's pitch).
  std::size_t tracers = 0;
  double density_ppp = 0, particle_px = 0;
  double max_displacement_px = 0;         // largest true |(ds, dt)| on the sheet, grid px
  std::vector<std::string> warnings;      // the experiment's design-rule warnings
  int piv_cols = 0, piv_rows = 0;         // vectors of the final pass on the grid
  SheetPivCase all, centre;               // all cameras; the centre camera alone
  // All cameras scored on the vectors the centre camera alone also scores: the
  // same region, so the accuracy comparison is like for like.
  PivScore all_on_centre_vectors;
  int operators_reused = 0;               // of the cameras' operators, loaded from the cache
  double simulate_seconds = 0, operator_seconds = 0, reconstruct_seconds = 0, piv_seconds = 0, seconds = 0;
};

// scene: a multi-camera scene (read_correction_scene; no camera need be
// prepared: cs.cameras is not used); centre_camera: the name of the camera
// whose glass-removed pixel sets the grid's pitch ("" = the first); flow in
// m/s, world frame. base: the experiment's settings (dt, density and particle
// size per px of the centre camera, sensor, seed, trace options, threads);
// the truth grids, the sheet truth's step and keep_maps are set here.
// binning: every camera read out binning x binning. cache_dir: the cameras'
// operators on the grid are read from there when valid and written there
// otherwise, under the names and fingerprints glasspiv correct and the
// demo's correction step use (correction_setup.h correction_cache_files); ""
// for no cache. piv: the evaluation on the grid. out_folder: the four PNGs
// (created if missing). Throws InputError for a camera that sees none of the
// sheet or a damaged cache file, std::invalid_argument for bad settings.
SheetPivSummary run_sheet_piv(const CorrectionScene& scene, const std::string& centre_camera, const Flow& flow,
                              const PivExperimentSettings& base, int binning, const std::string& cache_dir,
                              const PivOptions& piv, const std::string& out_folder);

}  // namespace glasspiv
