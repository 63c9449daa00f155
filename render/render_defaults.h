#pragma once
// The transport-map settings glasspiv render (and the demo's render) traces
// with unless told otherwise; bench/RESULTS.md ("The reflection grid", "Whole
// samples") has the tables they were chosen from.
//
// TraceOptions' min_weight 1e-2 (a render shows faint ghosts), the reflection
// grid 2 at tolerance 0.1 with whole samples: on the reactor's 2160 x 2160
// view 15.56 -> 9.16 segments per sample, the image within 1.2e-4 RMS of the
// one traced whole and unchanged to the digit against a converged render.
// The library's TraceOptions stay exact (grid 1): a caller opts in.
#include "render/path_tracer.h"

namespace glasspiv {

inline TraceOptions render_trace_options() {
  TraceOptions o;
  o.reflection_grid = 2;
  o.grid_whole_samples = true;
  return o;
}

}  // namespace glasspiv
