#pragma once
// How far two models' pixel-to-sheet mappings differ: the judge of a model fit
// against the truth, and of the drawing against the fitted model. Every pixel
// of a grid is traced through both models (reflections off, the refracted
// chain's first sheet crossing, each in its own model's sheet frame: the
// sheet is where the plate is); the difference of the two sheet points in mm
// and, through the reference's footprint Jacobian, in px (how far the
// reference's image of the sheet point is from the pixel). Double precision.
// No I/O.
#include <vector>

#include <Eigen/Core>

#include "calib/camera_model.h"
#include "calib/rigid_transform.h"
#include "render/path_tracer.h"

namespace glasspiv {

struct MappingModel {
  const TraceScene* scene = nullptr;
  CameraModel camera;
  RigidTransform camera_from_world;
};

struct MappingPercentiles {
  int count = 0;
  double rms_px = 0, p95_px = 0, max_px = 0, rms_mm = 0;
};

struct MappingDifference {
  std::vector<Eigen::Vector2d> pixels;  // the grid pixels compared
  std::vector<float> error_px, error_mm;
  std::vector<unsigned char> through_glass;  // the reference's path met glass
  MappingPercentiles glass, direct;
  int other_path = 0;  // pixels whose paths met other surfaces in the two models (rims): not compared
};

// Pixels on a grid step_px apart (at step/2 + k step) whose sheet point lies
// within the plate (|s| <= extent_mm[0] / 2, |t| <= extent_mm[1] / 2 in the
// reference) in both models. threads <= 0: all.
MappingDifference compare_mappings(const MappingModel& reference, const MappingModel& other, int step_px,
                                   const Eigen::Vector2d& extent_mm, int threads = 0);

}  // namespace glasspiv
