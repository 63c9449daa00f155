#pragma once
// The reference cameras of the fit tests and fit_bench (fixtures: their
// synthetic views come from sim/calibration_views.h): 2048 x 1536, fx ~ 2400,
// a mild OpenCV5 lens; and a strong rational (OpenCV8) lens at 2560 x 1600.
#include "calib/camera_model.h"

namespace glasspiv::testing {

inline CameraModel truth_opencv5() {
  return CameraModel(2048, 1536, 2400, 2401.5, 1030.25, 760.75, {-0.2, 0.1, 1e-4, -1.2e-4, -0.02});
}
inline CameraModel truth_opencv8() {
  return CameraModel(2560, 1600, 1500, 1501, 1275.5, 805.25, {-0.25, 0.08, 3e-4, -2e-4, -0.01, 0.15, -0.02, 0.005});
}

}  // namespace glasspiv::testing
