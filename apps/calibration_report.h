#pragma once
// The calibration report: an HTML page with the pictures (residual field,
// coverage, projection uncertainty, distortion, cross-validation) and the numbers
// (parameters with their 1-sigma, RMS, outliers, per-view residuals), plus a
// metrics JSON. Written into one folder, every file atomically. No figure is
// ever printed as "nan": a pixel without one is named with the reason
// (the fitted model has no ray there), and counted on the maps.
#include <optional>
#include <string>
#include <vector>

#include "calib/camera.h"
#include "calib/fit/calibration_diagnostics.h"
#include "calib/fit/intrinsic_fit.h"
#include "calib/observations.h"

namespace glasspiv {

struct CalibrationReportInputs {
  const Observations& observations;
  const IntrinsicFitOptions& options;
  const IntrinsicFit& fit;
  const CrossValidation* cross_validation = nullptr;  // absent when too few views
  std::string camera_name;
  std::optional<double> pixel_pitch_um;
  std::optional<Camera> truth;  // synthetic sessions: the camera the photos were made with
  double uncertainty_distance_mm = 1000;  // kAtInfinity for a point at infinity
  UncertaintyMethod uncertainty_method = UncertaintyMethod::board_frames;
};

struct CalibrationReportFiles {
  std::string html, metrics_json;
};

CalibrationReportFiles write_calibration_report(const std::string& folder, const CalibrationReportInputs& in);

// Every file write_calibration_report may write into `folder` (for the
// commands' output checks, before any work).
std::vector<std::string> calibration_report_file_paths(const std::string& folder);

}  // namespace glasspiv
