#pragma once
// Runs tests/calib/fit/mrcal_fit.py (python3 with mrcal) on Observations of a
// SyntheticBoard: mrcal's own fit of the same corners, for comparisons.
#include <optional>
#include <string>
#include <vector>

#include "calib/camera_model.h"
#include "calib/observations.h"
#include "sim/calibration_views.h"
#include "tests/python_mrcal.h"

namespace glasspiv::testing {

struct MrcalFit {
  CameraModel camera;
  double rms_px = 0;            // sqrt(mean |r|^2) over the corners
  double optimize_seconds = 0;  // time inside mrcal.optimize, measured in python
};

// nullopt (with `error` set) if python/mrcal is missing or the script fails.
// `work_dir` receives the JSON and the result file. `source_dir` is the
// repository root (the script's location).
std::optional<MrcalFit> run_mrcal_fit(const Observations& observations, const SyntheticBoard& board,
                                      LensModel lens_model, double focal_estimate_px, const std::string& work_dir,
                                      const std::string& source_dir, std::string* error);

}  // namespace glasspiv::testing
