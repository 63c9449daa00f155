#pragma once
// A scene file made ready for rendering the setup and aligning it: read and
// validated, one of its cameras chosen, converted for the tracer, the
// rectangles' textures loaded (a target spec as the board printed at true scale,
// align/scene_fiducials.h places its corners). Errors are InputErrors naming
// the scene file and field.
#include <memory>
#include <string>
#include <vector>

#include "render/path_tracer.h"
#include "render/scene.h"
#include "render/sheet_texture.h"
#include "render/trace_scene_builder.h"

namespace glasspiv {

struct PreparedScene {
  Scene scene;
  TraceScene trace;
  TraceSceneBuildInfo info;
  int camera_index = 0;
  std::vector<std::unique_ptr<SheetTexture>> rectangle_textures;  // per scene.rectangles entry (null: none)

  const Camera& camera() const { return scene.cameras[static_cast<std::size_t>(camera_index)].camera; }
  const std::string& camera_name() const { return scene.cameras[static_cast<std::size_t>(camera_index)].name; }
  std::string camera_field() const { return scene.cameras[static_cast<std::size_t>(camera_index)].field; }
  // Texture per solid index (null where none), for SetupLook.
  std::vector<const SheetTexture*> textures_by_solid() const;
};

// camera_name "" = the first camera; binning > 1 reads the chosen camera out
// binned (calib/camera_model.h: binned). A scene without a sheet or without
// cameras, or an unknown camera name, is an InputError.
PreparedScene prepare_scene(const std::string& path, const std::string& camera_name, int binning = 1);

}  // namespace glasspiv
