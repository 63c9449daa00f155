#pragma once
// Maps over the image that show what a lens model does: its distortion field
// and its projection difference to another model (as mrcal-show-projection-diff).
#include <optional>

#include "calib/camera_model.h"
#include "calib/pixel_grid.h"
#include "calib/rigid_transform.h"

namespace glasspiv {

// Per sample pixel: pixel - (the pixel the same ray would hit without distortion),
// i.e. how far the lens moves the image point. NaN where the pixel has no ray.
GridValues distortion_field(const CameraModel& model, double approx_step_px);

// Per sample pixel of `a`: the ray of `a` through it, taken to the point at
// `distance_mm` along the ray, moved into b's frame by `b_from_a` (identity:
// both cameras at the same place, the intrinsics-only comparison), and projected
// with `b`; the value is b's pixel minus a's projection of the same point. NaN
// where either model has no answer.
GridValues projection_difference(const CameraModel& a, const CameraModel& b, double distance_mm,
                                 double approx_step_px, const RigidTransform& b_from_a = RigidTransform{});

}  // namespace glasspiv
