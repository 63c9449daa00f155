#pragma once
// The demo's rendering step: the reference-like reactor (a bcc bed of 40 mm
// N-BK7 spheres, the sheet behind two layers) seen by its camera: the
// transport map traced once and cached, then a checkerboard and a particle
// field on the sheet rendered through it, and the setup itself.
#include <string>

namespace glasspiv {

struct DemoRenderSummary {
  int width = 0, height = 0;
  double trace_seconds = 0, reload_seconds = 0, render_seconds = 0, setup_seconds = 0;
  double crossings_per_pixel = 0, closed_form_fraction = 0;
  bool cache_reused = false;
  bool map_from_earlier_run = false;  // the first load found a valid map of an earlier demo run
  std::string checkerboard_png, particles_tif, setup_png, map_file;
};

// scene_path: the reactor scene as written by the demo (its camera file next
// to it as the scene expects); binning: the camera read out binned, for speed.
DemoRenderSummary run_render_demo(const std::string& folder, const std::string& scene_path, int binning);

}  // namespace glasspiv
