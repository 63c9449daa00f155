#pragma once
// The simulated experiment that glasspiv demo (step 9), bench/chain_bench and
// the demo's tests share, so that their figures compare: a steady Lamb-Oseen
// vortex about the sheet's normal through the sheet's origin (core radius
// 30 mm, peak velocity 1 m/s, pulses 1 ms apart: about 3 px of the reactor
// camera's glass-removed view at binning 4, well within the one-quarter rule of
// a 32 px window), 0.04 tracers per px, 2.5 px particle images and a 12-bit
// sensor whose in-plane particle peaks near 2000 counts (the PIV design of
// sim_piv_experiment_test). No I/O.
#include "render/path_tracer.h"
#include "sim/flows.h"
#include "sim/piv_experiment.h"

namespace glasspiv {

struct VortexDesign {
  double core_radius_mm = 30;
  double peak_velocity_m_per_s = 1.0;
  double dt_s = 1e-3;
  // The Lamb-Oseen vortex peaks at r = 1.1209 rc with u = 0.63817 Gamma / (2 pi rc).
  double circulation_m2_per_s() const;
};

// The vortex about the sheet's normal through its origin.
LambOseenVortexFlow vortex_flow(const SheetPlane& sheet, const VortexDesign& design = {});

// The experiment's settings: dt from the design, the density, particle size,
// sensor and seed above; trace options, map samples, truth grids and threads
// left at their defaults for the caller.
PivExperimentSettings vortex_experiment_settings(const VortexDesign& design = {});

}  // namespace glasspiv
