#pragma once
// OpenCV's own sample chessboard photographs, left*.jpg and right*.jpg (13 each,
// 640 x 480, one stereo pair of cameras; data/calibration/opencv_left and
// opencv_right), for the real-photo session tests.
#include <string>
#include <vector>

#include "calib/observations.h"
#include "targets/target_spec.h"

namespace glasspiv::testing {

// The board of both sets: 10 x 7 squares (9 x 6 inner corners); its square size
// is not recorded with the photos, so it is 1 (the intrinsics do not depend on it).
TargetSpec opencv_sample_board();

// The photos of data/calibration/opencv_<set> ("left" or "right"), sorted by name.
std::vector<std::string> opencv_sample_photos(const std::string& set);

// glasspiv's detection (default options) on every photo of the set: one view per
// photo, in photo order, with the image size.
Observations detect_opencv_sample_set(const std::string& set);

// glasspiv's fit and cv::calibrateCamera on the same observations, same model
// (OpenCV5), no outlier rejection; prints and checks that they find the same
// minimum: the projection difference over the image below 0.05 px RMS (both
// minimise the same sum of squares, so only convergence tolerances separate
// them), and glasspiv's RMS no worse than OpenCV's (to 1e-6 px).
void expect_fit_agrees_with_calibrate_camera(const Observations& obs, const std::string& name);

}  // namespace glasspiv::testing
