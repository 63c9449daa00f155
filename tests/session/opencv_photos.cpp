#include "opencv_photos.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include <gtest/gtest.h>

#include "calib/fit/intrinsic_fit.h"
#include "calib/lens_maps.h"
#include "opencv_peer.h"

#include "targets/photo_io.h"
#include "targets/target_detect.h"

namespace glasspiv::testing {

TargetSpec opencv_sample_board() {
  TargetSpec spec;
  spec.kind = TargetKind::chessboard;
  spec.squares_x = 10;
  spec.squares_y = 7;
  spec.square_size_mm = 1.0;
  return spec;
}

std::vector<std::string> opencv_sample_photos(const std::string& set) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(GLASSPIV_SOURCE_DIR) / "data" / "calibration" / ("opencv_" + set);
  std::vector<std::string> photos;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".jpg") photos.push_back(e.path().string());
  std::sort(photos.begin(), photos.end());
  return photos;
}

Observations detect_opencv_sample_set(const std::string& set) {
  const TargetDetector detector(opencv_sample_board());
  Observations obs;
  for (const std::string& p : opencv_sample_photos(set)) {
    const cv::Mat gray = read_photo_gray8(p);
    obs.image_width_px = gray.cols;
    obs.image_height_px = gray.rows;
    obs.views.push_back(detector.detect(gray, p).view);
  }
  return obs;
}

void expect_fit_agrees_with_calibrate_camera(const Observations& obs, const std::string& name) {
  IntrinsicFitOptions options;
  options.lens_model = LensModel::OpenCV5;
  options.outlier_k = 0;
  const IntrinsicFit fit = fit_intrinsics(obs, options);

  CameraModel opencv(obs.image_width_px, obs.image_height_px, 1, 1, 0, 0);
  const double opencv_rms =
      opencv_calibrate(obs, LensModel::OpenCV5, &opencv, nullptr,
                       cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 200, 1e-12));
  const GridValues diff = projection_difference(fit.camera, opencv, 1000.0, 8.0);
  std::printf("%s: glasspiv RMS %.5f px, OpenCV RMS %.5f px; projection difference RMS %.5f px, max %.5f px\n",
              name.c_str(), fit.rms_px, opencv_rms, diff.rms_px, diff.max_px);
  std::printf("  glasspiv fx %.4f fy %.4f cx %.4f cy %.4f; OpenCV fx %.4f fy %.4f cx %.4f cy %.4f\n",
              fit.camera.fx_px(), fit.camera.fy_px(), fit.camera.cx_px(), fit.camera.cy_px(), opencv.fx_px(),
              opencv.fy_px(), opencv.cx_px(), opencv.cy_px());
  EXPECT_LT(diff.rms_px, 0.05) << name;
  EXPECT_LE(fit.rms_px, opencv_rms + 1e-6) << name;
}

}  // namespace glasspiv::testing
