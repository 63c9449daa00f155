#pragma once
// A camera's pose in the setup from the fiducials it sees: the corners found in
// its photos (align/fiducial_detection.h), each paired with its world position,
// fitted by calib/fit/extrinsic_fit.h. Two fits: the plain pinhole one (the
// start, and the figure to compare with), then, through_glass, the fit whose
// projection follows every corner's line of sight through the traced model
// (align/refraction_pose.h): a marker behind a window or the packing is seen
// where the glass puts it. Where no glass is in the way both projections agree.
// See docs/alignment.md. No I/O.
#include <string>
#include <vector>

#include "align/fiducial_detection.h"
#include "align/refraction_pose.h"
#include "align/scene_fiducials.h"
#include "calib/fit/extrinsic_fit.h"
#include "render/path_tracer.h"

namespace glasspiv {

struct AlignPoseOptions {
  bool through_glass = true;   // false: the pinhole fit is the result
  // One common scale on fx, fy free, in the pinhole fit; the traced fit holds it
  // there. A focal fitted through a window absorbs part of its magnification:
  // use it with corners that no glass displaces.
  bool refine_focal = false;
  double outlier_k = 4.0;      // calib/fit's outlier rounds; 0 disables
  double max_position_sigma_mm = 10.0;  // refuse an unconstrained pose (calib/fit/extrinsic_fit.h)
  double max_rotation_sigma_deg = 1.0;
  TracedProjectionOptions traced;
  int threads = 1;
};

struct FiducialFit {
  int fiducial = 0;
  std::string field;  // the fiducial's rectangle in the scene file
  int corners = 0, outliers = 0;
  double rms_px = 0, max_px = 0;  // over its inliers
};

struct AlignedPose {
  ExtrinsicFit fit;              // the result
  ExtrinsicFit pinhole;          // the plain-pinhole fit (equal to fit unless through_glass)
  bool through_glass = false;
  std::vector<FiducialFit> fiducials;  // one per fiducial with corners, scene order
  // The largest distance between a corner's traced and pinhole projections
  // under the result's pose: how much the glass displaces what the camera sees.
  double glass_displacement_px = 0;
};

// The scene's trace model (scene, index, rectangle_solids: the solid of each
// scene rectangle, TraceSceneBuildInfo), its fiducials, the camera and the
// corners found in its photos. Throws InputError (field "fiducials") when the
// corners cannot determine a pose (calib/fit/extrinsic_fit.h says why).
AlignedPose align_pose(const TraceScene& scene, const SceneIndex& index, const std::vector<int>& rectangle_solids,
                       const std::vector<SceneFiducial>& fiducials, const CameraModel& camera,
                       const std::vector<FiducialCorner>& corners, const AlignPoseOptions& options = {});

}  // namespace glasspiv
