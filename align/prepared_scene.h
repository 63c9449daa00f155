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

// What a caller needs of the scene: the sheet (renders of it, the transport
// map, the sensitivity of sheet points), or only the setup (alignment: glass,
// opaque parts and fiducials; a scene without a sheet is fine).
enum class SceneUse { sheet, setup_only };

// camera_name "" = the first camera; binning > 1 reads the chosen camera out
// binned (calib/camera_model.h: binned). A scene without cameras, an unknown
// camera name, or (SceneUse::sheet) a scene without a sheet is an InputError.
// A setup-only scene without a sheet is traced with a 1 um sheet far outside
// the scene that no ray crosses in practice (the tracer needs a plane; the
// setup render ignores crossings).
PreparedScene prepare_scene(const std::string& path, const std::string& camera_name, int binning = 1,
                            SceneUse use = SceneUse::sheet);

}  // namespace glasspiv
