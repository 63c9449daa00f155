#pragma once
// cv::calibrateCamera on the same corners as glasspiv's fit: the OpenCV peer the
// fit tests, the real-photo session test and bench/fit_bench compare against.
#include <optional>

#include <opencv2/core.hpp>

#include "calib/camera_model.h"
#include "calib/observations.h"

namespace glasspiv::testing {

// Fits `model` (CALIB_RATIONAL_MODEL for opencv8; opencv4/5 otherwise) and
// returns OpenCV's RMS; `seconds` receives the calibrateCamera call's wall time.
// `criteria` replaces OpenCV's default stopping rule when given.
double opencv_calibrate(const Observations& obs, LensModel model, CameraModel* out, double* seconds = nullptr,
                        std::optional<cv::TermCriteria> criteria = std::nullopt);

}  // namespace glasspiv::testing
