#pragma once
// Reading a scene file (docs/scene.md, schema docs/scene.schema.json) into a
// validated Scene. Errors are InputErrors naming the file, the field path
// ("solids[3].diameter_mm") and, where the field is in the file, its line.
#include <string>
#include <string_view>
#include <vector>

#include "render/scene.h"

namespace glasspiv {

constexpr int kSceneFormatVersion = 1;

// Reads, resolves (camera files and textures relative to the scene file's folder;
// camera files are read) and validates the scene at `path`.
Scene read_scene(const std::string& path);

// The same from text; `path` names the source in errors and is the base that
// relative file names are resolved against.
Scene parse_scene(std::string_view contents, const std::string& path);

// The scene as a scene file that read_scene turns back into the same Scene:
// packings stay packings, slabs stay slabs, box rotations become rvec_deg,
// camera files are named relative to `path`'s folder (inline cameras are written
// inline), poses as camera_from_world {rvec, tvec_mm}.
std::string format_scene(const Scene& scene, const std::string& path);
// format_scene written atomically to `path`.
void write_scene(const std::string& path, const Scene& scene);

// The top-level keys the reader accepts (docs/scene.schema.json lists the same).
std::vector<std::string> scene_top_level_keys();

}  // namespace glasspiv
