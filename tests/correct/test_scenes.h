#pragma once
// The example scenes' first camera, read out binned, for the correction tests.
#include <string>

#include "render/scene_yaml.h"
#include "render/trace_scene_builder.h"

namespace glasspiv {

struct SceneCameraSetup {
  Scene scene;
  TraceScene trace;
  CameraModel camera;
  RigidTransform pose;
};

inline SceneCameraSetup load_scene_camera(const std::string& name, int binning, int camera_index = 0) {
  Scene scene = read_scene(std::string(GLASSPIV_SOURCE_DIR) + "/data/scenes/" + name);
  TraceScene trace = build_trace_scene(scene);
  const Camera cam = scene.cameras[static_cast<std::size_t>(camera_index)].camera;
  return {std::move(scene), std::move(trace), binned(cam.model, binning), *cam.camera_from_world};
}

}  // namespace glasspiv
