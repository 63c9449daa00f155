#include "opencv_peer.h"

#include <chrono>
#include <vector>

#include <opencv2/calib3d.hpp>

namespace glasspiv::testing {

double opencv_calibrate(const Observations& obs, LensModel model, CameraModel* out, double* seconds,
                        std::optional<cv::TermCriteria> criteria) {
  std::vector<std::vector<cv::Point3f>> object;
  std::vector<std::vector<cv::Point2f>> image;
  for (const ViewObservations& v : obs.views) {
    object.emplace_back();
    image.emplace_back();
    for (const CornerObservation& c : v.corners) {
      object.back().emplace_back(c.board_point_mm.x(), c.board_point_mm.y(), 0.f);
      image.back().emplace_back(c.pixel_px.x(), c.pixel_px.y());
    }
  }
  cv::Mat k, d;
  std::vector<cv::Mat> rvecs, tvecs;
  const int flags = model == LensModel::OpenCV8 ? cv::CALIB_RATIONAL_MODEL : 0;
  const cv::Size size(obs.image_width_px, obs.image_height_px);
  const auto start = std::chrono::steady_clock::now();
  const double rms = criteria ? cv::calibrateCamera(object, image, size, k, d, rvecs, tvecs, flags, *criteria)
                              : cv::calibrateCamera(object, image, size, k, d, rvecs, tvecs, flags);
  if (seconds) *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::vector<double> distortion(d.begin<double>(), d.end<double>());
  distortion.resize(static_cast<int>(model));
  *out = CameraModel(obs.image_width_px, obs.image_height_px, k.at<double>(0, 0), k.at<double>(1, 1),
                     k.at<double>(0, 2), k.at<double>(1, 2), distortion);
  return rms;
}

}  // namespace glasspiv::testing
