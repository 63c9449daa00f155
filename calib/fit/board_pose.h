#pragma once
// The start of a board pose from its corners, camera known: the homography of
// the board plane (which the intrinsic fit's closed-form focal length also
// uses) and camera_from_board by IPPE (Collins & Bartoli 2014, cv::solvePnP
// SOLVEPNP_IPPE). The board's points lie on its z = 0 plane.
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "calib/camera_model.h"
#include "calib/observations.h"
#include "calib/rigid_transform.h"

namespace glasspiv {

// camera_from_board as the fits parameterise it.
struct BoardPose {
  Eigen::Vector3d rvec = Eigen::Vector3d::Zero();  // angle-axis, rad
  Eigen::Vector3d translation_mm = Eigen::Vector3d::Zero();
  RigidTransform camera_from_board() const { return RigidTransform::from_rvec_tvec(rvec, translation_mm); }
};

// The homography board (x, y) mm -> pixel over all corners (cv::findHomography,
// least squares, no RANSAC); nullopt when the corners give none (fewer than 4,
// collinear or repeated points).
std::optional<Eigen::Matrix3d> board_homography(const std::vector<CornerObservation>& corners);

// camera_from_board through the camera's pinhole and distortion (the corners'
// board z ignored, taken as 0); nullopt when IPPE finds no finite pose with the
// board in front of the camera.
std::optional<BoardPose> board_pose_ippe(const CameraModel& camera, const std::vector<CornerObservation>& corners);

}  // namespace glasspiv
