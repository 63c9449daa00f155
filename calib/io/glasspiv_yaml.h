#pragma once
// glasspiv YAML (docs/formats.md): one camera per file, any pinhole + OpenCV model,
// the pose and the pixel pitch. Doubles are written in their shortest round-trip
// form, so parse(format(x)) gives x bit for bit (the pose's rotation, kept as an
// rvec, to ~1e-16).
#include <string>
#include <string_view>
#include <vector>

#include "calib/camera.h"

namespace glasspiv {

// Throws InputError naming `path` and the field for anything it cannot use.
std::vector<Camera> parse_glasspiv_yaml(std::string_view contents, const std::string& path);
// Throws InputError naming `path` if the format cannot hold the cameras.
std::string format_glasspiv_yaml(const std::vector<Camera>& cameras, const std::string& path);

}  // namespace glasspiv
