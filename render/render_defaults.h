#pragma once
// The transport-map settings glasspiv render (and the demo's render) traces
// with unless told otherwise; bench/RESULTS.md ("The reflection grid", "Whole
// samples") has the tables they were chosen from.
//
// TraceOptions' min_weight 1e-2 (a render shows faint ghosts), the reflection
// grid 2 at tolerance 0.1 with whole samples: on the reactor's 2160 x 2160
// view 15.56 -> 9.16 segments per sample, the image within 1.2e-4 RMS of the
// one traced whole and unchanged to the digit against a converged render.
// With reflections the grid's coarse level (reflection_grid_levels 2,
// bench/RESULTS.md "The grid's coarse level"): on the whole camera 42.9 ->
// 36.7 M segments, at 2160 x 2160 the image within 1.9e-4 RMS of the one
// traced whole, and at 400 x 400 unchanged to the digit against a converged
// render. Without reflections the refracted chain alone decides whether a
// coarse cell agrees, and at 2160 x 2160 a 4-sample cell missed a change of it
// on a few pixels (largest difference a full checker step): level 1 there.
// The library's TraceOptions stay exact (grid 1): a caller opts in.
#include "render/path_tracer.h"

namespace glasspiv {

inline TraceOptions render_trace_options(bool reflections = true) {
  TraceOptions o;
  o.reflections = reflections;
  o.reflection_grid = 2;
  o.grid_whole_samples = true;
  o.reflection_grid_levels = reflections ? 2 : 1;
  return o;
}

}  // namespace glasspiv
