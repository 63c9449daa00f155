#include "calib/fit/board_pose.h"

#include <cmath>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

namespace glasspiv {

std::optional<Eigen::Matrix3d> board_homography(const std::vector<CornerObservation>& corners) {
  if (corners.size() < 4) return std::nullopt;
  std::vector<cv::Point2d> board, pixels;
  for (const CornerObservation& c : corners) {
    board.emplace_back(c.board_point_mm.x(), c.board_point_mm.y());
    pixels.emplace_back(c.pixel_px.x(), c.pixel_px.y());
  }
  const cv::Mat h = cv::findHomography(board, pixels, 0);
  if (h.empty() || !cv::checkRange(h) || std::abs(cv::determinant(h)) < 1e-300) return std::nullopt;
  Eigen::Matrix3d out;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out(r, c) = h.at<double>(r, c);
  return out;
}

std::optional<BoardPose> board_pose_ippe(const CameraModel& camera, const std::vector<CornerObservation>& corners) {
  const cv::Matx33d k(camera.fx_px(), 0, camera.cx_px(), 0, camera.fy_px(), camera.cy_px(), 0, 0, 1);
  const std::vector<double> distortion = camera.distortion();
  std::vector<cv::Point3d> board;
  std::vector<cv::Point2d> pixels;
  for (const CornerObservation& c : corners) {
    board.emplace_back(c.board_point_mm.x(), c.board_point_mm.y(), 0.0);
    pixels.emplace_back(c.pixel_px.x(), c.pixel_px.y());
  }
  cv::Vec3d rvec, tvec;
  bool ok = false;
  try {
    ok = cv::solvePnP(board, pixels, k, distortion, rvec, tvec, false, cv::SOLVEPNP_IPPE);
  } catch (const cv::Exception&) {
    ok = false;  // too few or degenerate points
  }
  if (!ok || !cv::checkRange(rvec) || !cv::checkRange(tvec) || !(tvec[2] > 0)) return std::nullopt;
  BoardPose pose;
  for (int i = 0; i < 3; ++i) {
    pose.rvec(i) = rvec[i];
    pose.translation_mm(i) = tvec[i];
  }
  return pose;
}

}  // namespace glasspiv
