#include "align/scene_update.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "util/atomic_file.h"
#include "util/input_error.h"

namespace glasspiv {

std::string scene_with_camera_poses(const std::string& scene_path, const std::vector<CameraPoseUpdate>& updates) {
  YAML::Node root = YAML::Load(read_file(scene_path));
  YAML::Node cameras = root["cameras"];
  for (const CameraPoseUpdate& u : updates) {
    if (!cameras || !cameras.IsSequence() || u.camera_index < 0 ||
        static_cast<std::size_t>(u.camera_index) >= cameras.size())
      throw InputError(scene_path, "cameras", fmt::format("has no camera {}", u.camera_index));
    {
      YAML::Node cam = cameras[static_cast<std::size_t>(u.camera_index)];
      const Eigen::Vector3d r = u.camera_from_world.rvec(), t = u.camera_from_world.translation_mm;
      YAML::Node pose;
      pose.SetStyle(YAML::EmitterStyle::Flow);
      for (int k = 0; k < 3; ++k) pose["rvec"].push_back(fmt::format("{:.17g}", r[k]));
      for (int k = 0; k < 3; ++k) pose["tvec_mm"].push_back(fmt::format("{:.17g}", t[k]));
      cam["pose"] = pose;
    }
  }
  YAML::Emitter out;
  out << root;
  return std::string("# written by glasspiv align (camera poses replaced; comments of the original dropped)\n") +
         out.c_str() + "\n";
}

}  // namespace glasspiv
