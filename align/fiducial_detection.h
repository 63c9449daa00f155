#pragma once
// The scene's fiducials found in a photo: every detected corner paired with its
// world position. Boards (chessboard, ChArUco, AprilGrid) are found by their
// own detector (targets/target_detect.h); single markers (ArUco, AprilTag) by
// one detection per dictionary for all markers sharing it
// (targets/marker_detect.h), matched to the scene by id. Ids seen twice in a
// photo and ids the scene does not have are reported, never used.
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "align/scene_fiducials.h"

namespace glasspiv {

struct FiducialCorner {
  int fiducial = 0;   // index into the scene_fiducials() list
  int corner_id = 0;  // board_corners() id
  Eigen::Vector3d world_mm = Eigen::Vector3d::Zero();
  Eigen::Vector2d pixel_px = Eigen::Vector2d::Zero();
};

struct FiducialsInPhoto {
  std::string source;
  std::vector<FiducialCorner> corners;  // by fiducial, then corner id
  std::vector<int> corners_per_fiducial;  // one count per scene fiducial (0: not found)
  // Single markers: decoded ids no fiducial of the scene carries ("DICT_4X4_50 id 17"),
  // and ids decoded more than once (ambiguous: dropped).
  std::vector<std::string> unknown_markers, duplicated_markers;
  std::vector<std::string> notes;  // per board: why corners were dropped, from the detector
};

// `gray8`: CV_8UC1. Throws InputError(source, "image", ...) for an empty image.
FiducialsInPhoto detect_fiducials(const cv::Mat& gray8, const std::vector<SceneFiducial>& fiducials,
                                  const std::string& source);

}  // namespace glasspiv
