// A calibration session on real photographs: OpenCV's own left*.jpg chessboard
// set (data/calibration/opencv_left, 13 photos, 9 x 6 inner corners). glasspiv's
// detection and fit against cv::calibrateCamera on the same observations.
#include <filesystem>
#include <vector>

#include <gtest/gtest.h>

#include "calib/fit/intrinsic_fit.h"
#include "calib/lens_maps.h"
#include "targets/photo_io.h"
#include "targets/target_detect.h"
#include "opencv_peer.h"

namespace glasspiv {
namespace {
namespace fs = std::filesystem;

// The board has 10 x 7 squares (9 x 6 inner corners); its square size is not
// recorded with the photos, so it is 1 (the intrinsics do not depend on it).
TargetSpec opencv_left_board() {
  TargetSpec spec;
  spec.kind = TargetKind::chessboard;
  spec.squares_x = 10;
  spec.squares_y = 7;
  spec.square_size_mm = 1.0;
  return spec;
}

Observations detect_opencv_left() {
  const fs::path dir = fs::path(GLASSPIV_SOURCE_DIR) / "data" / "calibration" / "opencv_left";
  std::vector<std::string> photos;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".jpg") photos.push_back(e.path().string());
  std::sort(photos.begin(), photos.end());
  const TargetDetector detector(opencv_left_board());
  Observations obs;
  for (const std::string& p : photos) {
    const cv::Mat gray = read_photo_gray8(p);
    obs.image_width_px = gray.cols;
    obs.image_height_px = gray.rows;
    obs.views.push_back(detector.detect(gray, p).view);
  }
  return obs;
}

TEST(OpenCVLeftPhotos, DetectsTheBoardInEveryPhoto) {
  const Observations obs = detect_opencv_left();
  ASSERT_EQ(obs.views.size(), 13u);
  EXPECT_EQ(obs.image_width_px, 640);
  EXPECT_EQ(obs.image_height_px, 480);
  for (const ViewObservations& v : obs.views) EXPECT_EQ(v.corners.size(), 54u) << v.source;
}

// Same observations, same model (OpenCV5), no outlier rejection: glasspiv's fit
// and cv::calibrateCamera must find the same minimum. Agreement: the projection
// difference over the image below 0.05 px RMS (the bar; both minimise the
// same sum of squares, so only convergence tolerances separate them), and our RMS
// no worse than OpenCV's (to 1e-6 px).
TEST(OpenCVLeftPhotos, FitAgreesWithCalibrateCamera) {
  const Observations obs = detect_opencv_left();
  IntrinsicFitOptions options;
  options.lens_model = LensModel::OpenCV5;
  options.outlier_k = 0;
  const IntrinsicFit fit = fit_intrinsics(obs, options);

  CameraModel opencv(640, 480, 1, 1, 0, 0);
  const double opencv_rms = testing::opencv_calibrate(
      obs, LensModel::OpenCV5, &opencv, nullptr,
      cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 200, 1e-12));
  const GridValues diff = projection_difference(fit.camera, opencv, 1000.0, 8.0);
  std::printf("opencv_left: glasspiv RMS %.5f px, OpenCV RMS %.5f px; projection difference RMS %.5f px, max %.5f px\n",
              fit.rms_px, opencv_rms, diff.rms_px, diff.max_px);
  std::printf("  glasspiv fx %.4f fy %.4f cx %.4f cy %.4f; OpenCV fx %.4f fy %.4f cx %.4f cy %.4f\n", fit.camera.fx_px(),
              fit.camera.fy_px(), fit.camera.cx_px(), fit.camera.cy_px(), opencv.fx_px(), opencv.fy_px(),
              opencv.cx_px(), opencv.cy_px());
  EXPECT_LT(diff.rms_px, 0.05);
  EXPECT_LE(fit.rms_px, opencv_rms + 1e-6);
}

}  // namespace
}  // namespace glasspiv
