// A calibration session on real photographs: OpenCV's own left*.jpg chessboard
// set (data/calibration/opencv_left, 13 photos, 9 x 6 inner corners). glasspiv's
// detection and fit against cv::calibrateCamera on the same observations.
#include <gtest/gtest.h>

#include "opencv_photos.h"

namespace glasspiv {
namespace {

TEST(OpenCVLeftPhotos, DetectsTheBoardInEveryPhoto) {
  const Observations obs = testing::detect_opencv_sample_set("left");
  ASSERT_EQ(obs.views.size(), 13u);
  EXPECT_EQ(obs.image_width_px, 640);
  EXPECT_EQ(obs.image_height_px, 480);
  for (const ViewObservations& v : obs.views) EXPECT_EQ(v.corners.size(), 54u) << v.source;
}

// Same observations, same model (OpenCV5), no outlier rejection: glasspiv's fit
// and cv::calibrateCamera must find the same minimum (the bar: 0.05 px
// RMS projection difference over the image; see opencv_photos.h).
TEST(OpenCVLeftPhotos, FitAgreesWithCalibrateCamera) {
  testing::expect_fit_agrees_with_calibrate_camera(testing::detect_opencv_sample_set("left"), "opencv_left");
}

}  // namespace
}  // namespace glasspiv
