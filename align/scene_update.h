#pragma once
// A scene file with some of its cameras' poses replaced: what `glasspiv align`
// writes after a pose or a refinement. The rest of the file is kept as YAML
// (values, order; comments are lost). Relative paths in it stay relative to the
// scene's folder, so the new file must go into the same folder (the command
// checks that).
#include <string>
#include <vector>

#include "calib/rigid_transform.h"

namespace glasspiv {

struct CameraPoseUpdate {
  int camera_index = 0;  // into the scene's `cameras` list (Scene::cameras order)
  RigidTransform camera_from_world;
};

// The text of `scene_path` with `pose: {rvec, tvec_mm}` of each camera
// replaced (rvec in radians, 17 significant digits). Throws InputError naming
// the scene for a camera index it does not have.
std::string scene_with_camera_poses(const std::string& scene_path, const std::vector<CameraPoseUpdate>& updates);

}  // namespace glasspiv
