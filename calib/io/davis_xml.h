#pragma once
// DaVis Calibration.xml with PinholeOpenCV coordinate mappers (one camera per
// mapper): focal length in mm with the sensor's pixel size, principal point in
// pixels, k1 k2 p1 p2, and the pose as ZYX Euler angles plus a translation in mm.
#include <string>
#include <string_view>
#include <vector>

#include "calib/camera.h"

namespace glasspiv {

// Throws InputError naming `path` and the field for anything it cannot use.
std::vector<Camera> parse_davis_xml(std::string_view contents, const std::string& path);
// The CameraIdentifier of each mapper, in the order parse_davis_xml gives the
// cameras (so `--camera 1` finds a camera whatever its name).
std::vector<std::string> davis_camera_identifiers(std::string_view contents, const std::string& path);
// Throws InputError naming `path` if the format cannot hold the cameras.
std::string format_davis_xml(const std::vector<Camera>& cameras, const std::string& path);

}  // namespace glasspiv
