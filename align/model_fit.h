#pragma once
// The model made to match the built setup: the glass parts, the glass's
// refractive index, the sheet (the plate) and the cameras fitted, part by
// part, to photographs of a known plate lying in the sheet plane, seen through
// the glass (docs/alignment.md, "Model fit"). No I/O.
//
// The prediction. A pixel (of the level's binned camera) is traced through the
// model with reflections off; its first sheet crossing on the refracted chain
// lands at (s, t) with weight w (Fresnel transmission) and footprint J =
// d(s, t)/d(pixel). The plate's picture (1 = paper, 0 = ink) averaged over
// the footprint is A(s, t; J), and the photo is predicted as
//   photo(x) = gain(x) (w A + ghosts) + offset(x),
// ghosts the same sum over the pixel's reflected crossings (options.trace),
// gain a quadratic and offset a linear polynomial of the pixel position
// (lighting and vignetting), fitted with the geometry. Pixels whose crossing
// footprint reaches past the plate's edge, or that cross no sheet, are not used.
//
// The Jacobian comes from the traced paths, never from whole renders per
// parameter: d(photo)/d(theta) = gain w grad A . d(s, t)/d(theta), with grad A
// the footprint-averaged picture's gradient and d(s, t)/d(theta)
//  - analytic for the camera's rotation and focal length (a central camera
//    rotated sees with pixel p what it saw with a nearby pixel p': d(s, t) =
//    J dp'), and for the sheet's pose (the crossing's last segment met by the
//    moved plane);
//  - by forward differences of re-traced pixels for the camera's centre, a
//    sphere's centre and diameter and the index, re-tracing only the pixels
//    whose paths meet the part moved (a sphere's parameters move only the
//    pixels that went through it). A pixel whose path changes its sequence of
//    surfaces under the step (a rim) gets no derivative for that parameter.
// A full Jacobian costs about (1 + 3 + 3 x the fraction of pixels through
// glass + 1) traces of the image.
//
// The solution. Robust (Huber) Gauss-Newton with Levenberg-Marquardt damping
// on the normal equations: the photo's residuals in units of their noise
// (1.4826 MAD at each level's start) plus a Gaussian prior per geometric
// parameter, centred on the drawing, with the drawing's tolerance as its
// sigma. The prior fixes the gauge (a rigid motion of everything changes no
// photo) and keeps what the photos cannot see at the drawing: a sphere no
// pixel looks through is not a parameter at all. Coarse to fine over binned
// levels: a start 0.2 mm and 0.1 degrees off moves the pictures behind the
// balls by many full-resolution pixels, a few binned ones. Small problem
// (tens to a few hundred parameters): dense normal equations, sparse columns.
// Covariance: the inverse of the final normal matrix (residuals of unit
// variance by construction).
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "calib/camera_model.h"
#include "calib/rigid_transform.h"
#include "render/path_tracer.h"
#include "render/sheet_texture.h"

namespace glasspiv {

// Which parts move.
struct ModelFitFreedom {
  bool camera_pose = true;
  bool camera_focal = false;  // one scale on fx, fy per camera
  bool sheet_pose = true;     // the plate's pose, which is the sheet's
  bool sphere_centres = true;
  bool sphere_diameters = false;
  bool refractive_index = true;  // one offset on every glass solid's index
};

// The drawing's 1-sigma tolerances: the prior of each geometric parameter.
struct ModelFitTolerances {
  double camera_position_mm = 0.1;     // camera centre, each world axis
  double camera_rotation_deg = 0.02;   // about each camera axis, around the centre
  double camera_focal_relative = 2e-3;
  double sheet_position_mm = 0.5;      // along the sheet's s, t and normal
  double sheet_rotation_deg = 0.2;     // about s, t and the normal
  double sphere_centre_mm = 0.05;      // each sphere, each world axis
  double sphere_diameter_mm = 0.02;
  double refractive_index = 1e-3;
};

// One photo of the plate: the camera that took it, its pose from the drawing
// (or from markers: the start), the photo (CV_32FC1, the camera's size; any
// units, saturated or dead pixels as NaN).
// Photos with the same name were taken by one camera (one pose, one focal
// length), e.g. of the plate at several known positions along the sheet's
// normal (plate_offset_mm: a traverse): with one position a ball lens's
// magnification trades the glass index against the ball's distance to the
// plate; two positions tell them apart.
struct PlatePhoto {
  std::string name;  // the camera's name ("cam0")
  CameraModel camera;
  RigidTransform camera_from_world;
  cv::Mat photo;
  double plate_offset_mm = 0;  // the plate moved this far along the sheet's normal (s x t) for this photo
};

// The plate on the sheet: its picture (1 paper, 0 ink) laid on the sheet as
// render/sheet_texture.h says (centred on the sheet origin, columns along s,
// rows along -t), and its size (mm), beyond which the sheet shows no plate.
struct PlatePicture {
  const SheetTexture* texture = nullptr;
  double width_mm = 0, height_mm = 0;
};

struct ModelFitOptions {
  std::vector<int> binning_levels = {4, 2, 1};  // coarse to fine
  int max_iterations = 12;                      // Gauss-Newton steps per level
  // Subsamples per pixel and axis of the prediction where the pixel's ray
  // meets glass, each with its own footprint (J / k); a pixel that sees the
  // plate through air only is one footprint-averaged sample (exact: the
  // mapping is linear there). Through a ball the mapping is far from linear
  // over a pixel: on the 3 x 3 layer one sample per pixel missed the photo by
  // ~8 % of its contrast, and against a photo rendered with 5 x 5 samples the
  // fitted index came out 3e-4 off with 2 x 2 and within 1e-5 with 3 x 3.
  int samples_per_axis = 3;
  // Pixels over which the mapping departs from linear by more than this (px,
  // between the centre's footprint and the subsamples' landings) are left out.
  double max_bend_px = 0.1;
  double huber_k = 2.0;                         // in noise sigmas
  // Step sizes of the re-traced forward differences: far above the tracer's
  // round-off (1e-12 mm), far below the tolerances.
  double step_mm = 1e-4;
  double step_index = 1e-6;
  // The prediction's tracing: with reflections, the ghosts of the plate a photo
  // shows join the prediction (their derivatives are left out: the Jacobian
  // follows the refracted chain, traced without reflections). On the 3 x 3
  // layer, leaving the ghosts out biased the index by -1.1e-3.
  TraceOptions trace{true, 1e-3, 32};
  int threads = 0;                      // <= 0: all
  // Called with (level, iteration, level count) after each iteration.
  std::function<void(int, int, int)> progress;
};

// One fitted parameter, in the unit its name says.
struct FittedParameter {
  std::string name;        // "cam0.position_x_mm", "sphere[4].centre_y_mm", "glass.index_offset", ...
  double drawing = 0;      // the start (the drawing's value)
  double fitted = 0;
  double sigma = 0;        // 1-sigma from the fit's covariance
  double prior_sigma = 0;  // the tolerance it was held to
  // The photos determine it: its sigma is below half its tolerance.
  bool determined() const { return sigma < 0.5 * prior_sigma; }
};

struct ModelFitLevel {
  int binning = 1;
  int pixels = 0;  // pixels used (all photos)
  double noise = 0;  // the residual noise sigma at the start (photo units)
  double rms_before = 0, rms_after = 0;  // photo units
  double photo_sd = 0;                   // the photo's own standard deviation over those pixels
  int iterations = 0;
  long traced_rays = 0;
  double seconds = 0;
};

struct WeakCombination {
  double information = 0;
  std::vector<std::pair<std::string, double>> parts;  // parameter name, weight in the unit vector
};

struct ModelFitResult {
  TraceScene scene;                           // the fitted model (sheet and solids)
  std::vector<RigidTransform> camera_from_world;  // per photo
  std::vector<double> focal_scale;            // per photo
  std::vector<FittedParameter> parameters;    // the free geometric parameters, in order
  Eigen::MatrixXd covariance;                 // of `parameters`, in their units
  std::vector<int> unseen_spheres;            // solid indices of glass spheres no pixel looks through
  // What the photos cannot pin down: combinations of parameters (unit vectors
  // over the tolerance-whitened parameters, the largest parts named) along
  // which the photos give less information than the drawing's tolerances,
  // after leaving out the gauge (a rigid motion of camera, glass and plate
  // together changes no photo; the tolerances alone fix it). Along them the
  // fit stays near the drawing. information: the photos' share, 1 = as much as
  // the tolerance; 0 = none.
  std::vector<WeakCombination> weak;
  std::vector<ModelFitLevel> levels;
  double residual_rms_start = 0;  // finest level, at the drawing (photo units)
  double residual_rms_end = 0;
  // 1 - (residual / photo's standard deviation)^2 at the finest level: how much
  // of the photo's contrast the model explains. A photo of another plate or
  // rig explains almost none (the gain goes to zero).
  double explained_variance = 0;
  double seconds = 0;
};

// Fits the model `drawing` (its glass spheres are the solids with a Sphere
// shape and a glass material; other solids are held where they are) to the
// photos. Throws InputError(field "photo") for a photo of the wrong size or one
// in which no pixel sees the plate, std::invalid_argument for an empty level
// list or a null texture.
ModelFitResult fit_model(const TraceScene& drawing, const std::vector<PlatePhoto>& photos, const PlatePicture& plate,
                         const ModelFitFreedom& freedom = {}, const ModelFitTolerances& tolerances = {},
                         const ModelFitOptions& options = {});

}  // namespace glasspiv
