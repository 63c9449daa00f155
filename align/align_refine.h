#pragma once
// Alignment by the picture: the camera pose (and on request the focal length,
// the glass's refractive index and the position of the glass parts) optimised
// until the render of the setup (render/setup_render.h) agrees with the
// photograph. Coarse to fine: binned renders first, with the same blur in
// binned pixels, so a start off by a few mm and degrees is pulled in before
// full resolution fixes the last fraction of a pixel. See docs/alignment.md.
//
// The objective is the score of align/setup_similarity.h made least squares:
// the blurred gradient magnitudes of photo and render (blurred intensities on
// coarse levels), each normalised to zero mean and unit variance over the
// compared pixels (minimising it maximises gradient_ncc: edge agreement,
// insensitive to the lighting of the photo; smooth in the parameters), and,
// when fiducial corners are given, their detected pixels against their traced
// projections (align/refraction_pose.h). Both are weighted as measurements:
// a corner by 1 / corner_sigma_px; the picture as one measurement per blur
// footprint (pi (2 blur)^2 pixels) of its residual as measured at the start of
// each level (at least feature_sigma): a model that matches the photo less
// well counts for less. A picture of a narrow view
// cannot tell a small lateral shift from a small rotation (the gradient NCC of
// the two differs by 1e-4 for 0.07 mm at 500 mm); the corners can. Ceres (Levenberg-Marquardt) drives it; its Jacobian is by central
// differences of whole renders, with steps that move the picture by about a
// third of a (binned) pixel, far above the render's sampling noise.
// What stays the same between evaluations is made once per level: the binned
// photo, its normalised features, the trace index when only the camera moves.
// No I/O.
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "align/fiducial_detection.h"
#include "align/model_adjustment.h"
#include "align/setup_similarity.h"
#include "calib/camera_model.h"
#include "calib/rigid_transform.h"
#include "render/path_tracer.h"
#include "render/setup_render.h"

namespace glasspiv {

struct RefineParameters {
  bool focal = false;             // one scale on fx, fy
  bool refractive_index = false;  // one offset on the index of every glass solid
  bool glass_position = false;    // one translation of every glass solid (mm, world axes)
};

struct RefineOptions {
  std::vector<int> binning_levels = {8, 4, 2, 1};  // coarse to fine; each >= 1
  double blur_px = 1.5;           // Gaussian sigma in binned pixels, every level
  // Per pixel and axis in the renders; 0: min(binning, 4), so that a binned
  // pixel averages its area as the binned photo does (a point sample per
  // binned pixel aliases fine structure such as the images behind spheres).
  // On the marker-frame test auto took 0.048 -> 0.006 mm with corners (measured
  // before the refinement's steps came from the solids' depth), left
  // the picture alone at 0.07 mm, and cost 10x the time: 1 is the default.
  int samples_per_axis = 1;
  int max_iterations = 20;        // Levenberg-Marquardt steps per level
  // Levels binned this much or more compare the blurred intensities (a wide
  // basin of attraction for a far start), the finer ones the gradients.
  int intensity_from_binning = 4;
  TraceOptions trace{true, 1e-2, 32};
  int threads = 0;                // render threads; 0: all
  // Fiducial corners and how much one counts (px at full resolution), and the
  // residual of a normalised feature at a good alignment (its unit: the
  // features' standard deviation).
  double corner_sigma_px = 0.05;  // the marker detector's RMS at 20-60 px (targets/marker_detect.h)
  double feature_sigma = 0.15;
  // Called after each evaluation (level index, renders so far) for a progress bar.
  std::function<void(int, int)> progress;
};

// A fiducial corner for the objective: its world point on the opaque rectangle
// scene.solids[solid] and where the photo shows it (full-resolution px).
struct RefineCorner {
  Eigen::Vector3d world_mm = Eigen::Vector3d::Zero();
  int solid = 0;
  Eigen::Vector2d pixel_px = Eigen::Vector2d::Zero();
};

// The fiducial corners found in a photo as refinement corners: each on the
// solid of its fiducial's rectangle (rectangle_solids: TraceSceneBuildInfo's).
std::vector<RefineCorner> refine_corners(const std::vector<FiducialCorner>& corners,
                                         const std::vector<SceneFiducial>& fiducials,
                                         const std::vector<int>& rectangle_solids);

struct RefineLevel {
  int binning = 1;
  int width_px = 0, height_px = 0;
  double gradient_ncc_before = 0, gradient_ncc_after = 0;
  int iterations = 0, renders = 0;
  double seconds = 0;
  double corner_rms_px_after = 0;  // full-resolution px; 0 without corners
  // With corners: the normalised features' RMS difference at the level's start,
  // which (when above feature_sigma) sets the picture's weight for the level.
  double picture_rms_before = 0;
  int corners_lost = 0;            // corners without a traced image at the end of the level
};

// How a refinement ended. A result that is not `improved` must not be used as a
// pose: `no_step`, no level took a successful step or the score did not change
// (a camera looking away renders nothing: its steps move it through a flat
// objective); `worse`, the result is worse than the start at the finest level:
// its objective (one weighting for both) higher, more fiducial corners without
// an image (a lost corner is a miss of zero in the objective, so a start far
// off can drift to where none is seen), or, without corners, the score
// (gradient NCC against the photo) lower.
enum class RefineStatus { improved, no_step, worse };

struct RefineResult {
  RefineStatus status = RefineStatus::improved;
  // Gradient NCC at the last (finest) level's binning: at the start pose and
  // at the result (= levels.back().gradient_ncc_after).
  double score_start = 0, score_end = 0;
  // With corners, at the finest level: their RMS (full-resolution px) and how
  // many have no traced image, at the start and at the result.
  double corner_rms_start_px = 0, corner_rms_end_px = 0;
  int corners_lost_start = 0, corners_lost_end = 0;
  // The finest level's objective (1/2 sum of squared residuals) at the start and at the result.
  double objective_start = 0, objective_end = 0;
  int successful_steps = 0;  // over all levels
  RigidTransform camera_from_world;
  double focal_scale = 1;
  double refractive_index_offset = 0;
  Eigen::Vector3d glass_offset_mm = Eigen::Vector3d::Zero();
  std::vector<RefineLevel> levels;
  int renders = 0;
  double seconds = 0;
};

// `photo32f`: CV_32FC1 of the camera's size (values in any units: they are
// normalised). Throws std::invalid_argument for a photo of another size or an
// empty level list (commands check the user's input first). The result's
// status says whether it may be used (RefineStatus): the objective's minimum
// is not always the photo's pose (corners out of view count as misses of
// zero, a render of nothing has no edges to disagree with), so the score is
// measured at the start and at the result on the finest level.
RefineResult refine_alignment(const TraceScene& scene, const SetupLook& look, const CameraModel& camera,
                              const RigidTransform& start_camera_from_world, const cv::Mat& photo32f,
                              const RefineParameters& parameters = {}, const RefineOptions& options = {},
                              const std::vector<RefineCorner>& corners = {});

}  // namespace glasspiv
