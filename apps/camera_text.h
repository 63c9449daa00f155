#pragma once
// A camera in words: both presentations (OpenCV and DaVis-style), field of view,
// pose and the invertibility of the lens model over the image.
#include <string>

#include "calib/camera.h"

namespace glasspiv {

std::string describe_camera(const Camera& camera);

}  // namespace glasspiv
