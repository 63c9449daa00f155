// Real photographs that are not ours: OpenCV's ArUco and ChArUco tutorial photos
// (data/fiducials/opencv_aruco, copied unchanged from Debian's opencv-doc
// 4.6.0; Apache-2.0 AND BSD-3-Clause, see its README.md). The markers are
// found by glasspiv's detectors (targets/marker_detect.h for the single markers,
// TargetDetector for the board); on those same detections the pose of
// calib/fit/extrinsic_fit.h fit_camera_pose is compared with OpenCV's
// cv::solvePnP(SOLVEPNP_SQPNP) + cv::solvePnPRefineLM (the independent
// reference), both with the intrinsics OpenCV's samples give for these photos
// (tutorial_camera_params.yml, tutorial_camera_charuco.yml).
//
// Both minimise the same sum of squared pixel residuals, so at their minima the
// reprojection RMS must agree to 1e-6 relative (the RMS is stationary at the
// minimum: a pose off by e changes it by O(e^2)). The poses agree to the
// stated tolerances below (rotation angle between them, camera-centre distance
// relative to the distance to the target). The outlier rounds are off
// (outlier_k = 0) so that both fit the same points; the sigma limits are wide,
// since a single marker of ~40 px only loosely determines its tilt, and that is
// not what is compared here.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "calib/fit/extrinsic_fit.h"
#include "targets/marker_detect.h"
#include "targets/photo_io.h"
#include "targets/target_detect.h"
#include "targets/target_spec.h"
#include "targets/target_yaml.h"

namespace glasspiv {
namespace {

std::string data_path(const std::string& file) {
  return std::string(GLASSPIV_SOURCE_DIR) + "/data/fiducials/opencv_aruco/" + file;
}

// OpenCV's FileStorage camera file of the samples (camera_matrix,
// distortion_coefficients; tutorial_camera_params.yml has no image size, so
// the photo's is used).
CameraModel read_sample_camera(const std::string& file, int width_px, int height_px) {
  cv::FileStorage fs(data_path(file), cv::FileStorage::READ);
  cv::Mat k, d;
  fs["camera_matrix"] >> k;
  fs["distortion_coefficients"] >> d;
  EXPECT_EQ(k.rows, 3);
  std::vector<double> distortion(d.begin<double>(), d.end<double>());
  return CameraModel(width_px, height_px, k.at<double>(0, 0), k.at<double>(1, 1), k.at<double>(0, 2),
                     k.at<double>(1, 2), distortion);
}

cv::Mat camera_matrix(const CameraModel& camera) {
  return (cv::Mat_<double>(3, 3) << camera.fx_px(), 0, camera.cx_px(), 0, camera.fy_px(), camera.cy_px(), 0, 0, 1);
}

struct OpenCVPose {
  RigidTransform camera_from_world;
  double rms_px = 0;
};

// The reference: SQPnP start, then solvePnPRefineLM iterated to convergence
// (OpenCV's default stops after 20 iterations or a step below FLT_EPSILON).
OpenCVPose opencv_pose(const CameraModel& camera, const std::vector<PointObservation>& points) {
  std::vector<cv::Point3d> world;
  std::vector<cv::Point2d> pixels;
  for (const PointObservation& p : points) {
    world.emplace_back(p.point_world_mm.x(), p.point_world_mm.y(), p.point_world_mm.z());
    pixels.emplace_back(p.pixel_px.x(), p.pixel_px.y());
  }
  const cv::Mat k = camera_matrix(camera);
  const std::vector<double> dist = camera.distortion();
  cv::Mat rvec, tvec;
  EXPECT_TRUE(cv::solvePnP(world, pixels, k, dist, rvec, tvec, false, cv::SOLVEPNP_SQPNP));
  cv::solvePnPRefineLM(world, pixels, k, dist, rvec, tvec,
                       cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 200, 1e-15));
  std::vector<cv::Point2d> projected;
  cv::projectPoints(world, rvec, tvec, k, dist, projected);
  double sum = 0;
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const cv::Point2d r = projected[i] - pixels[i];
    sum += r.dot(r);
  }
  OpenCVPose pose;
  pose.camera_from_world = RigidTransform::from_rvec_tvec(
      Eigen::Vector3d(rvec.at<double>(0), rvec.at<double>(1), rvec.at<double>(2)),
      Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2)));
  pose.rms_px = std::sqrt(sum / static_cast<double>(pixels.size()));
  return pose;
}

ExtrinsicFitOptions comparison_options() {
  ExtrinsicFitOptions options;
  options.outlier_k = 0;
  options.max_position_sigma_mm = 1e6;
  options.max_rotation_sigma_deg = 180;
  // A single marker of 25-45 px: its mirrored pose fits almost as well, and
  // OpenCV returns one of the two regardless; so does the fit here, to compare.
  options.refuse_planar_ambiguity = false;
  return options;
}

// Rotation angle between two poses (deg) and their camera centres' distance (mm).
// The angle by atan2(|axis part|, cos part) of the relative rotation: acos of
// the trace alone cannot resolve angles below ~1e-8 rad.
void pose_difference(const RigidTransform& a, const RigidTransform& b, double* angle_deg, double* centre_mm) {
  const Eigen::Matrix3d r = a.rotation * b.rotation.transpose();
  const Eigen::Vector3d axis(r(2, 1) - r(1, 2), r(0, 2) - r(2, 0), r(1, 0) - r(0, 1));  // 2 sin(angle) * unit axis
  *angle_deg = std::atan2(0.5 * axis.norm(), 0.5 * (r.trace() - 1)) * 180 / M_PI;
  *centre_mm = (a.inverse().translation_mm - b.inverse().translation_mm).norm();
}

// Tolerances. Measured (printed by the tests): RMS equal to 2e-13 relative and
// below; poses within 2.2e-7 deg and 3.6e-9 of the distance (marker 40 with
// glasspiv's corners: 4 points leave a flat minimum), the others far below.
constexpr double kRmsRelative = 1e-6;
constexpr double kAngleDeg = 1e-5;
constexpr double kCentreRelative = 1e-7;  // of the distance to the target

void expect_agree(const CameraModel& camera, const std::vector<PointObservation>& points, const std::string& what) {
  const ExtrinsicFit fit = fit_camera_pose(camera, points, comparison_options());
  const OpenCVPose cv_pose = opencv_pose(camera, points);
  double angle_deg = 0, centre_mm = 0;
  pose_difference(fit.camera_from_world, cv_pose.camera_from_world, &angle_deg, &centre_mm);
  const double distance_mm = fit.camera_from_world.translation_mm.norm();
  const double rms_relative = std::abs(fit.rms_px - cv_pose.rms_px) / cv_pose.rms_px;
  std::printf(
      "%s: %zu points, glasspiv RMS %.9f px, OpenCV RMS %.9f px (relative %.1e); rotation %.1e deg, centre %.1e mm "
      "(%.1e of %.0f mm)\n",
      what.c_str(), points.size(), fit.rms_px, cv_pose.rms_px, rms_relative, angle_deg, centre_mm,
      centre_mm / distance_mm, distance_mm);
  EXPECT_LE(rms_relative, kRmsRelative) << what;
  EXPECT_LE(angle_deg, kAngleDeg) << what;
  EXPECT_LE(centre_mm, kCentreRelative * distance_mm) << what;
}

// A marker's 4 corners (top-left, top-right, bottom-right, bottom-left, as
// detectMarkers and glasspiv order them) with the marker as the world.
std::vector<PointObservation> marker_points(const std::vector<BoardCorner>& corners, int id,
                                            const std::array<Eigen::Vector2d, 4>& pixels) {
  std::vector<PointObservation> points;
  for (std::size_t c = 0; c < 4; ++c) {
    PointObservation p;
    p.point_world_mm = corners[c].point_mm;
    p.pixel_px = pixels[c];
    p.label = "marker " + std::to_string(id) + " corner " + std::to_string(c);
    points.push_back(p);
  }
  return points;
}

// Six DICT_6X6_250 markers on a sheet, 25 to 45 px across, seen at a slant.
// OpenCV's detectMarkers finds all six (ids 23, 40, 62, 98, 124, 203), and
// so does glasspiv's MarkerDetector: its edge fit (targets/marker_detect.cpp
// refine_corners) refines 40, 62 and 124; on the three smallest, whose cells
// are 3 to 4 px, it gives up and cornerSubPix in a small window takes over
// (DetectedMarker::edge_fit false). Each marker is its own pose problem.
TEST(RealPhotos, SingleArucoMarkersPoseAgreesWithOpenCV) {
  const cv::Mat gray = read_photo_gray8(data_path("singlemarkersoriginal.jpg"));
  const CameraModel camera = read_sample_camera("tutorial_camera_params.yml", gray.cols, gray.rows);
  const TargetSpec spec = read_target_yaml(data_path("marker_50mm.yaml"));
  const std::vector<BoardCorner> corners = board_corners(spec);
  ASSERT_EQ(corners.size(), 4u);

  const MarkerDetection detection = detect_markers(gray, spec.dictionary, "singlemarkersoriginal.jpg");
  std::vector<int> ids;
  for (const DetectedMarker& m : detection.markers) ids.push_back(m.id);
  EXPECT_EQ(ids, (std::vector<int>{23, 40, 62, 98, 124, 203}));
  for (const DetectedMarker& m : detection.markers)
    EXPECT_EQ(m.edge_fit, m.id == 40 || m.id == 62 || m.id == 124) << "marker " << m.id;
  EXPECT_TRUE(detection.duplicated_ids.empty());
  for (const DetectedMarker& m : detection.markers)
    expect_agree(camera, marker_points(corners, m.id, m.corners_px),
                 "singlemarkersoriginal.jpg marker " + std::to_string(m.id));
}

// The same comparison on OpenCV's own detections of all six markers
// (detectMarkers with its defaults: whole-pixel corners, no refinement), so that
// the markers glasspiv's detector drops are compared too.
TEST(RealPhotos, SingleArucoMarkersOnOpenCVDetectionsAgree) {
  const cv::Mat gray = read_photo_gray8(data_path("singlemarkersoriginal.jpg"));
  const CameraModel camera = read_sample_camera("tutorial_camera_params.yml", gray.cols, gray.rows);
  const std::vector<BoardCorner> corners = board_corners(read_target_yaml(data_path("marker_50mm.yaml")));
  std::vector<std::vector<cv::Point2f>> detected;
  std::vector<int> ids;
  cv::aruco::detectMarkers(gray, cv::aruco::getPredefinedDictionary(cv::aruco::DICT_6X6_250), detected, ids);
  std::vector<int> sorted = ids;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(sorted, (std::vector<int>{23, 40, 62, 98, 124, 203}));
  for (std::size_t i = 0; i < ids.size(); ++i) {
    std::array<Eigen::Vector2d, 4> pixels;
    for (std::size_t c = 0; c < 4; ++c) pixels[c] = Eigen::Vector2d(detected[i][c].x, detected[i][c].y);
    expect_agree(camera, marker_points(corners, ids[i], pixels),
                 "singlemarkersoriginal.jpg marker " + std::to_string(ids[i]) + " (OpenCV's corners)");
  }
}

TEST(RealPhotos, CharucoBoardPoseAgreesWithOpenCV) {
  const cv::Mat gray = read_photo_gray8(data_path("choriginal.jpg"));
  const CameraModel camera = read_sample_camera("tutorial_camera_charuco.yml", gray.cols, gray.rows);
  const TargetSpec spec = read_target_yaml(data_path("charuco_5x7.yaml"));
  const TargetDetector detector(spec);
  const DetectionResult result = detector.detect(gray, "choriginal.jpg");
  std::printf("choriginal.jpg: %d markers decoded, %zu corners; note \"%s\"\n", result.markers_found,
              result.view.corners.size(), result.note.c_str());
  EXPECT_EQ(result.markers_found, 17);
  EXPECT_EQ(result.view.corners.size(), 24u);  // every inner corner of the 5 x 7 board

  std::vector<PointObservation> points;
  for (const CornerObservation& c : result.view.corners) {
    PointObservation p;
    p.point_world_mm = c.board_point_mm;
    p.pixel_px = c.pixel_px;
    p.label = "corner " + std::to_string(c.id);
    points.push_back(p);
  }
  expect_agree(camera, points, "choriginal.jpg board");
}

}  // namespace
}  // namespace glasspiv
