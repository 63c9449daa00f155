#pragma once
// mrcal .cameramodel (a Python-literal dict): LENSMODEL_PINHOLE and
// LENSMODEL_OPENCV4/5/8/12, imagersize and extrinsics (rt_cam_ref, our
// camera_from_world). Written at full precision (mrcal's own C writer rounds);
// read by our own parser so errors name the field.
#include <string>
#include <string_view>
#include <vector>

#include "calib/camera.h"

namespace glasspiv {

// Throws InputError naming `path` and the field for anything it cannot use.
std::vector<Camera> parse_mrcal_cameramodel(std::string_view contents, const std::string& path);
// Throws InputError naming `path` if the format cannot hold the cameras.
std::string format_mrcal_cameramodel(const std::vector<Camera>& cameras, const std::string& path);

}  // namespace glasspiv
