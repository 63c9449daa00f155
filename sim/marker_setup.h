#pragma once
// A setup with fiducial markers for alignment tests, benchmarks and the demo: a
// frame of single ArUco markers (DICT_4X4_50) at two depths around a field of
// view, optionally behind a flat glass window, seen by one camera. Written as
// a scene file and one target spec per marker, so that it goes through the same
// readers as a user's setup. Reproducible: no randomness.
#include <string>

namespace glasspiv {

struct MarkerSetupOptions {
  int markers = 20;              // on the frame: half at z = 0, half at z = depth_mm
  double marker_size_mm = 8;     // 20 to 60 px at the default camera (f = 2500 px, 500 mm away)
  double depth_mm = 60;          // the second ring of markers lies this far behind the first
  double window_thickness_mm = 0;  // > 0: an N-BK7 window at z = -100 mm covering the whole view
  int width_px = 1280, height_px = 1024;
  double focal_px = 2500;
  double camera_distance_mm = 500;  // the camera at z = -distance, looking at the frame's centre
};

// Writes `folder`/scene.yaml and `folder`/marker_NN.yaml; returns the scene's path.
// The camera is named "cam"; its pose looks at the origin from slightly off axis.
std::string write_marker_setup(const std::string& folder, const MarkerSetupOptions& options = {});

}  // namespace glasspiv
