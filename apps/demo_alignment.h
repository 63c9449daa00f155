#pragma once
// The demo's alignment step: a synthetic photograph of the reactor with
// fiducials (data/scenes/reactor_markers.yaml) rendered through the glass from
// the scene's pose (the truth), then the pose from the markers (traced and
// plain pinhole), the refinement on the picture from a start off by 2 mm and
// 1 degree, overlays before and after, a sensitivity map of what the remaining
// uncertainty moves, and an HTML page of it all. Every figure against the truth.
#include <string>
#include <vector>

#include <Eigen/Core>

#include "align/align_refine.h"
#include "calib/camera.h"

namespace glasspiv {

struct DemoPoseError {
  double position_mm = 0, rotation_deg = 0;  // camera centre distance, rotation angle
};

struct DemoSensitivityRow {
  std::string name;
  double sigma = 0;  // in the unit its name implies (align/sensitivity.h)
  double median_px = 0, p95_px = 0, median_mm = 0, p95_mm = 0;
};

struct DemoAlignmentSummary {
  int width = 0, height = 0;
  double photo_seconds = 0;
  // What the photo shows of the fiducials.
  int markers = 0, markers_found = 0;        // single markers of the scene, and those with corners
  int board_corners = 0, board_corner_ids = 0;  // rear board corners found, of its corner ids
  // Pose from the fiducials: traced through the glass, and the plain pinhole's.
  int pose_inliers = 0, pose_outliers = 0, board_inliers = 0;
  double pose_rms_px = 0, pinhole_rms_px = 0, glass_displacement_px = 0;
  DemoPoseError pose_error, pinhole_error;
  Eigen::Vector3d position_sigma_mm = Eigen::Vector3d::Zero();
  double rotation_sigma_deg = 0, pose_seconds = 0;
  // Refinement on the picture from the perturbed start.
  DemoPoseError start_error, refined_error;
  std::vector<RefineLevel> levels;  // binning relative to the demo's camera
  int renders = 0;
  double refine_seconds = 0;
  // Full-resolution scores of the start's and the refined render against the photo.
  double gradient_ncc_before = 0, gradient_ncc_after = 0, edge_distance_before_px = 0, edge_distance_after_px = 0;
  double gradient_ncc_truth = 0;  // the truth's render: what a perfect alignment scores
  // Sensitivity (first order) with the marker pose's covariance as its pose tolerance.
  int sensitivity_step_px = 0, sensitivity_valid_points = 0;
  std::vector<DemoSensitivityRow> sensitivity;  // per parameter, then "all together"
  double sensitivity_seconds = 0;
  std::string photo_png, overlay_before_png, overlay_before_edges_png, overlay_after_png, overlay_after_edges_png,
      sensitivity_png, html;
  double seconds = 0;
  // The camera the step recovered: the intrinsics it was given (the scene's
  // own, or a calibration's) and the refined pose.
  bool calibrated_intrinsics = false;
  std::optional<Camera> recovered;
};

// scene_path: reactor_markers.yaml as the demo writes it (its camera and marker
// specs where the scene expects them); binning: the camera's read-out binning.
// calibrated (optional): the binned camera's intrinsics as a calibration found
// them; the photograph is still taken by the scene's (true) camera, and the
// pose, the refinement and the sensitivity use these, as a user's would.
DemoAlignmentSummary run_alignment_demo(const std::string& folder, const std::string& scene_path, int binning,
                                        const CameraModel* calibrated = nullptr);

}  // namespace glasspiv
