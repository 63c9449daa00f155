#pragma once
// The demo's correction step: a particle field on the reactor's sheet rendered
// through the glass (the distorted PIV frame), then corrected, for one camera
// onto its own pixels with the glass removed, and for the five-camera scene
// onto the sheet grid by accumulation and by least squares, each scored
// against the known field.
#include <string>

namespace glasspiv {

struct DemoCorrectionSummary {
  // One camera.
  int width = 0, height = 0;
  double operator_seconds = 0, correct_ms = 0;
  double one_valid_fraction = 0, one_ncc = 0, one_lsq_ncc = 0;
  std::string side_by_side_png, corrected_tif, mask_tif;
  // Five cameras.
  double centre_valid_fraction = 0, five_valid_fraction = 0, five_seen_fraction = 0;
  double accumulation_rms = 0, lsq_rms = 0;
  int lsq_iterations = 0;
  std::string coverage_png, five_png;
};

// scenes_dir holds the embedded reactor.yaml and reactor_5cams.yaml (and their
// camera files as the scenes expect); binning: one camera's read-out binning
// (the five cameras use twice that).
DemoCorrectionSummary run_correction_demo(const std::string& folder, const std::string& scenes_dir, int binning);

}  // namespace glasspiv
