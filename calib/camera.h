#pragma once
// A camera as users keep it in files: a name, the intrinsic CameraModel, an
// optional pose in the setup, and the sensor's pixel pitch (needed only for the
// DaVis-style presentation in mm).
#include <optional>
#include <string>

#include "calib/camera_model.h"
#include "calib/rigid_transform.h"

namespace glasspiv {

struct Camera {
  std::string name;
  CameraModel model;
  std::optional<RigidTransform> camera_from_world;
  std::optional<double> pixel_pitch_um;  // sensor pixel size; square pixels
};

// DaVis presents a pinhole as a focal length in mm with the sensor's pixel size,
// and the principal point in pixels. fx_px = focal_length_x_mm / pixel_pitch_mm.
struct DavisStyleIntrinsics {
  double focal_length_x_mm = 0, focal_length_y_mm = 0;
  double pixel_pitch_um = 0;
  double principal_point_x_px = 0, principal_point_y_px = 0;
};

// Throws InputError naming `pixel_pitch_um` if it is not positive and finite.
DavisStyleIntrinsics to_davis_style(const CameraModel& model, double pixel_pitch_um);
// OpenCV's fx, fy, cx, cy from the DaVis presentation (validated like the above).
void from_davis_style(const DavisStyleIntrinsics& davis, double* fx_px, double* fy_px, double* cx_px, double* cy_px);

}  // namespace glasspiv
