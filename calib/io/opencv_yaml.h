#pragma once
// OpenCV FileStorage YAML as calibrateCamera users save it: camera_matrix,
// distortion_coefficients, image_width, image_height; optionally camera_name,
// pixel_pitch_um and rvec/tvec (camera_from_world, tvec in mm). Other keys (the
// calibration sample's avg_reprojection_error, ...) are ignored on reading.
#include <string>
#include <string_view>
#include <vector>

#include "calib/camera.h"

namespace glasspiv {

// Throws InputError naming `path` and the field for anything it cannot use.
std::vector<Camera> parse_opencv_yaml(std::string_view contents, const std::string& path);
// Throws InputError naming `path` if the format cannot hold the cameras.
std::string format_opencv_yaml(const std::vector<Camera>& cameras, const std::string& path);

}  // namespace glasspiv
