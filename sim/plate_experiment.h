#pragma once
// A plate experiment with known truth, for the model fit (align/model_fit.h):
// the setup "as built", off its drawing the way hand-built rigs are, and a
// photograph of a plate in its sheet plane taken through it. The truth of the
// fit's tests, benchmarks and the demo. No I/O.
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "calib/camera_model.h"
#include "calib/rigid_transform.h"
#include "render/path_tracer.h"
#include "render/sheet_texture.h"
#include "sim/setup_photo.h"
#include "targets/target_spec.h"

namespace glasspiv {

// The model fit's reference rig (data/scenes/ball_layer.yaml): a 3 x 3 layer of
// 40 mm N-BK7 balls 0.5 mm apart in air, the sheet 30 mm behind the layer
// (t up, s to the right as the camera sees it), a pinhole camera of
// width_px x height_px 600 mm in front of the layer seeing 160 mm across at
// the sheet.
struct PlateRig {
  TraceScene drawing;
  CameraModel camera;
  RigidTransform camera_from_world;
};
PlateRig ball_layer_rig(int width_px, int height_px);

// A speckle plate (targets/speckle_plate.h) of width x height mm, dots of
// dot_mm covering 40 % of it, placed by the seed.
TargetSpec speckle_spec(double width_mm, double height_mm, double dot_mm, std::uint64_t seed);

// How the build differs from the drawing. Each glass sphere's centre moves by
// N(0, sphere_centre_sigma_mm) per world axis; every glass solid's index by
// index_offset; the sheet and each camera move by a fixed distance along a
// random direction and turn by a fixed angle about a random axis (the camera
// about its centre, the sheet about its origin).
struct BuildDeviation {
  double sphere_centre_sigma_mm = 0.03;
  double index_offset = 4e-4;
  double sheet_shift_mm = 0.15;
  double sheet_turn_deg = 0.05;
  double camera_shift_mm = 0.03;
  double camera_turn_deg = 0.005;
  std::uint64_t seed = 1;
};

struct AsBuilt {
  TraceScene scene;
  std::vector<RigidTransform> camera_from_world;
};

AsBuilt as_built(const TraceScene& drawing, const std::vector<RigidTransform>& cameras_from_world,
                 const BuildDeviation& deviation);

struct PlatePhotoOptions {
  int samples_per_axis = 3;  // k x k stratified samples per pixel
  // Reflections on, followed down to 1e-4 of a pixel's light: the ghosts a
  // real photo shows, more of them than a fit's prediction follows.
  TraceOptions trace{true, 1e-4, 32};
  PhotoLook look{0.0, 0.2, 12, 235, 0.5, 1, true};  // no blur, 20 % vignette, 16-bit, noise
  int threads = 0;
};

// The photo (CV_16UC1 or CV_8UC1 as look says) of the plate picture lying on
// the scene's sheet, through the scene, footprint-filtered per sample.
cv::Mat plate_photo(const TraceScene& scene, const CameraModel& camera, const RigidTransform& camera_from_world,
                    const SheetTexture& plate, const PlatePhotoOptions& options = {});

}  // namespace glasspiv
