// The second camera of OpenCV's stereo sample: its right*.jpg chessboard set
// (data/calibration/opencv_right, 13 photos, 9 x 6 inner corners), as the left
// set in opencv_left_test.cpp. That glasspiv finds all 13 boards (right09.jpg's
// too, which OpenCV's sector-based finder loses with glasspiv's first flags) is
// checked in opencv_detection_test.cpp.
#include <gtest/gtest.h>

#include "opencv_photos.h"

namespace glasspiv {
namespace {

TEST(OpenCVRightPhotos, FitAgreesWithCalibrateCamera) {
  testing::expect_fit_agrees_with_calibrate_camera(testing::detect_opencv_sample_set("right"), "opencv_right");
}

}  // namespace
}  // namespace glasspiv
