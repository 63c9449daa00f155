#include "align/prepared_scene.h"

#include <fmt/format.h>

#include "align/scene_fiducials.h"
#include "render/scene_yaml.h"
#include "targets/target_image.h"
#include "targets/target_yaml.h"
#include "util/image_file.h"
#include "util/input_error.h"

namespace glasspiv {

std::vector<const SheetTexture*> PreparedScene::textures_by_solid() const {
  std::vector<const SheetTexture*> out(trace.solids.size(), nullptr);
  for (std::size_t i = 0; i < rectangle_textures.size(); ++i)
    out[static_cast<std::size_t>(info.rectangle_solids[i])] = rectangle_textures[i].get();
  return out;
}

PreparedScene prepare_scene(const std::string& path, const std::string& camera_name, int binning, SceneUse use) {
  PreparedScene ps;
  ps.scene = read_scene(path);
  if (!ps.scene.sheet && use == SceneUse::sheet) throw InputError(path, "sheet", "the scene has no sheet to render");
  if (ps.scene.cameras.empty()) throw InputError(path, "cameras", "the scene has no camera");
  if (!camera_name.empty()) {
    ps.camera_index = -1;
    std::string names;
    for (std::size_t i = 0; i < ps.scene.cameras.size(); ++i) {
      if (ps.scene.cameras[i].name == camera_name) ps.camera_index = static_cast<int>(i);
      names += (i ? ", " : "") + ps.scene.cameras[i].name;
    }
    if (ps.camera_index < 0)
      throw InputError(path, "--camera", fmt::format("no camera '{}' in the scene (it has: {})", camera_name, names));
  }
  Camera& chosen = ps.scene.cameras[static_cast<std::size_t>(ps.camera_index)].camera;
  if (binning > 1) chosen.model = binned(chosen.model, binning);
  if (ps.scene.sheet) {
    ps.trace = build_trace_scene(ps.scene, &ps.info);
  } else {
    Scene traced = ps.scene;
    Sheet placeholder;
    placeholder.origin_mm = Eigen::Vector3d(0, 0, 0.9 * kMaxSceneCoordinate_mm);
    placeholder.extent_mm = {kMinSceneSize_mm, kMinSceneSize_mm};
    placeholder.thickness_mm = kMinSceneSize_mm;
    traced.sheet = placeholder;
    ps.trace = build_trace_scene(traced, &ps.info);
  }
  for (const RectangleSolid& r : ps.scene.rectangles) {
    if (r.texture.empty()) {
      ps.rectangle_textures.emplace_back();
      continue;
    }
    if (is_target_file(r.texture)) {
      const TargetRender board = rectangle_target_texture(read_target_yaml(r.texture));
      cv::Mat values;
      board.image.convertTo(values, CV_32F, 1.0 / 255);
      ps.rectangle_textures.push_back(
          std::make_unique<SheetTexture>(values.ptr<float>(0), values.rows, values.cols, 1.0 / board.px_per_mm));
      continue;
    }
    const GrayImage img = read_gray_image(r.texture);
    // The picture fills the rectangle's width and is centred (a different
    // aspect ratio leaves bands or is cut at the top and bottom).
    ps.rectangle_textures.push_back(
        std::make_unique<SheetTexture>(img.values.data(), img.height, img.width, r.size_mm[0] / img.width));
  }
  return ps;
}

}  // namespace glasspiv
