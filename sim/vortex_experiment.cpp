#include "sim/vortex_experiment.h"

#include <cmath>

namespace glasspiv {

double VortexDesign::circulation_m2_per_s() const {
  return peak_velocity_m_per_s * 2 * M_PI * (1e-3 * core_radius_mm) / 0.63817;
}

LambOseenVortexFlow vortex_flow(const SheetPlane& sheet, const VortexDesign& design) {
  return LambOseenVortexFlow(sheet.origin_mm, sheet.normal(), design.circulation_m2_per_s(), design.core_radius_mm);
}

PivExperimentSettings vortex_experiment_settings(const VortexDesign& design) {
  PivExperimentSettings s;
  s.dt_s = design.dt_s;
  s.density_ppp = 0.04;
  s.particle_px = 2.5;
  s.sensor.bit_depth = 12;
  s.sensor.electrons_per_radiance = 4000;
  s.seed = 8;
  return s;
}

}  // namespace glasspiv
