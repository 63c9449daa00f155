#pragma once
// The demo's calibration session: synthetic photos of a ChArUco board taken by
// a known camera, then the same detection, fit and report a user runs on real
// photos, and the recovered camera against the truth.
#include <optional>
#include <string>

#include "calib/camera.h"

namespace glasspiv {

// Where the board is photographed from: the distance range of its centre.
struct DemoCalibrationViews {
  double near_mm = 300, far_mm = 450;
};

struct DemoCalibrationSummary {
  double rms_px = 0;                  // fit residual
  double truth_difference_rms_px = 0; // projection difference to the true camera
  double truth_difference_rotated_rms_px = 0;  // the same after the implied rotation (as mrcal compares)
  double focal_error_rel = 0;         // |fx - fx_true| / fx_true
  double principal_point_error_px = 0;
  std::string report_html;
  std::optional<Camera> fitted;  // the fitted camera (no pose), as written to the folder
};

// Writes photos, observations, the fitted camera and its report under `folder`.
// The target and true camera are the embedded files written to `cameras_dir`
// and `targets_dir` by the demo.
DemoCalibrationSummary run_calibration_demo(const std::string& folder, const std::string& truth_camera_path,
                                            const std::string& target_path, const DemoCalibrationViews& views = {});

}  // namespace glasspiv
