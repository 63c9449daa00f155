#pragma once
// The transport-map settings a correction traces with unless told otherwise
// (glasspiv correct, the demo, the chain bench's default row).
//
// Branches lighter than 0.1 of the pixel's light are not followed: a single
// Fresnel reflection at near-normal incidence carries ~4 % (glass-air; ~0.4 %
// glass-water), so its faint ghost is left out, while total internal
// reflection and grazing reflections (> 10 %), the ghosts that show in PIV
// images, are kept. The mask's own floor is the same (MaskOptions::
// min_mean_weight: a view carrying under 0.1 of the light is not used), so a
// lighter branch could only add a ghost's smear to the accumulated image.
// Measured on the chain bench (bench/RESULTS.md, "The whole chain"): the same
// PIV error as 1e-2 and 1e-3 to under 1 %, for less map, operator and
// per-frame time. glasspiv render keeps TraceOptions' 1e-2: a render shows
// faint ghosts too.
#include "render/path_tracer.h"

namespace glasspiv {

inline TraceOptions correction_trace_options() {
  TraceOptions o;
  o.min_weight = 0.1;
  return o;
}

}  // namespace glasspiv
