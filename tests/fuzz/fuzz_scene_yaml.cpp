// Fuzz harness: the scene file reader (render/scene_yaml.h, parse_scene).
// The input is the scene's text; it is read as if it were a scene file in
// data/scenes/, so the seeds' camera files (../cameras/example.yaml) resolve
// and are read too.
#include "fuzz_common.h"
#include "render/scene_yaml.h"

#ifndef GLASSPIV_SOURCE_DIR
#error "GLASSPIV_SOURCE_DIR must name the source tree (tests/fuzz/CMakeLists.txt sets it)"
#endif

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = std::string(GLASSPIV_SOURCE_DIR) + "/data/scenes/fuzz_input.yaml";
  glasspiv_fuzz::returns_or_refuses("parse_scene", [&] { glasspiv::parse_scene(glasspiv_fuzz::as_text(data, size), path); });
  return 0;
}
