#include "apps/correction_setup.h"

#include <cstdio>
#include <filesystem>

#include <fmt/format.h>

#include "correct/correction_operator_file.h"
#include "correct/operator_cache.h"
#include "render/scene_yaml.h"
#include "render/trace_scene_builder.h"
#include "render/transport_map_cache.h"
#include "render/transport_map_file.h"
#include "util/input_error.h"
#include "util/progress_bar.h"

namespace glasspiv {
namespace fs = std::filesystem;

CorrectionScene read_correction_scene(const std::string& path) {
  CorrectionScene cs;
  cs.scene = read_scene(path);
  if (!cs.scene.sheet) throw InputError(path, "sheet", "the scene has no sheet to correct onto");
  if (cs.scene.cameras.empty()) throw InputError(path, "cameras", "the scene has no camera");
  cs.trace = build_trace_scene(cs.scene);
  return cs;
}

int find_camera(const Scene& scene, const std::string& name, const std::string& field) {
  if (name.empty()) return 0;
  std::string names;
  for (std::size_t i = 0; i < scene.cameras.size(); ++i) {
    if (scene.cameras[i].name == name) return static_cast<int>(i);
    names += (i ? ", " : "") + scene.cameras[i].name;
  }
  throw InputError(scene.source, field, fmt::format("no camera '{}' in the scene (it has: {})", name, names));
}

namespace {
CameraModel camera_model(const CorrectionScene& cs, int index, const CorrectionSettings& s) {
  const CameraModel& m = cs.scene.cameras[static_cast<std::size_t>(index)].camera.model;
  return s.binning > 1 ? binned(m, s.binning) : m;
}
}  // namespace

GlassRemovedView glass_removed_view(const CorrectionScene& cs, int camera_index, const CorrectionSettings& s) {
  const SceneCamera& sc = cs.scene.cameras[static_cast<std::size_t>(camera_index)];
  GlassRemovedView v;
  v.map = glass_removed_map(cs.trace, camera_model(cs, camera_index, s), *sc.camera.camera_from_world, 1, s.threads);
  v.footprint_mm = median_footprint_mm(v.map);
  if (!(v.footprint_mm > 0))
    throw InputError(cs.scene.source, sc.field,
                     fmt::format("camera '{}' sees none of the sheet: check its pose and the sheet's extent", sc.name));
  return v;
}

void add_correction_camera(CorrectionScene& cs, int camera_index, const SheetGrid& grid, const CorrectionSettings& s) {
  const SceneCamera& sc = cs.scene.cameras[static_cast<std::size_t>(camera_index)];
  CorrectionCamera cam{sc.name, sc.field, camera_model(cs, camera_index, s), *sc.camera.camera_from_world, {}, 0};
  const CorrectionCacheFiles cache = correction_cache_files(cs.scene, camera_index, s, grid.cols, grid.rows);
  const std::string map_path = cache.map, op_path = cache.op;
  if (!s.cache_dir.empty()) {
    std::error_code ec;
    fs::create_directories(s.cache_dir, ec);
    if (ec) throw InputError(s.cache_dir, "--cache-dir", "cannot create the folder: " + ec.message());
  }
  const std::uint64_t map_fp = transport_map_fingerprint(cs.trace, cam.model, cam.pose, s.trace, s.samples);
  // A valid cached operator needs no map.
  if (!op_path.empty()) {
    std::string why;
    const std::uint64_t op_fp = correction_operator_fingerprint(map_fp, grid, s.op);
    if (auto op = load_cached_correction_operator(op_path, op_fp, &why)) {
      cam.op = std::move(*op);
      cam.op_fingerprint = op_fp;
      if (s.report)
        std::printf("camera '%s': reused the correction operator %s (%zu entries): nothing traced or built\n",
                    cam.name.c_str(), op_path.c_str(), cam.op.entry_count());
      cs.cameras.push_back(std::move(cam));
      return;
    }
    // A damaged cache file is not silently replaced: it may be something else the user keeps there.
    if (why.rfind("unreadable", 0) == 0)
      throw InputError(op_path, "", "cached correction operator is " + why + "; delete it to build a new one");
  }
  CachedTransportMap map;
  {
    ProgressBar bar("trace map " + cam.name, static_cast<std::size_t>(cam.model.height_px()));
    map = load_or_build_transport_map(cs.trace, cam.model, cam.pose, s.trace, s.samples, map_path, s.threads,
                                      [&bar](int done, int) { bar.set_done(static_cast<std::size_t>(done)); });
    if (!map.reused) bar.finish();
  }
  if (map.map.crossing_count() == 0)
    throw InputError(cs.scene.source, sc.field,
                     fmt::format("camera '{}' sees none of the sheet: check its pose and the sheet's extent", sc.name));
  if (s.report) {
    if (map.reused)
      std::printf("camera '%s': reused the transport map %s\n", cam.name.c_str(), map_path.c_str());
    else
      std::printf("camera '%s': traced its transport map %dx%d in %.2f s (%.2f crossings per pixel)%s\n",
                  cam.name.c_str(), map.map.width, map.map.height, map.seconds,
                  double(map.map.crossing_count()) / map.map.pixel_count(),
                  map.written ? (", cached in " + map_path).c_str() : "");
  }
  CachedCorrectionOperator op;
  {
    ProgressBar bar("operator " + cam.name, static_cast<std::size_t>(cam.model.height_px()));
    op = load_or_build_correction_operator(map.map, map.fingerprint, grid, s.op, op_path, s.threads,
                                           [&bar](int done, int) { bar.set_done(static_cast<std::size_t>(done)); });
    bar.finish();
  }
  if (s.report)
    std::printf("camera '%s': built its correction operator in %.2f s (%zu entries, %.1f MiB)%s\n", cam.name.c_str(),
                op.seconds, op.op.entry_count(), op.op.memory_bytes() / 1048576.0,
                op.written ? (", cached in " + op_path).c_str() : "");
  cam.op = std::move(op.op);
  cam.op_fingerprint = op.fingerprint;
  cs.cameras.push_back(std::move(cam));
}

CorrectionCacheFiles correction_cache_files(const Scene& scene, int camera_index, const CorrectionSettings& s, int cols,
                                            int rows) {
  if (s.cache_dir.empty()) return {};
  const SceneCamera& sc = scene.cameras[static_cast<std::size_t>(camera_index)];
  const std::string stem = s.binning > 1 ? fmt::format("{}_bin{}", sc.name, s.binning) : sc.name;
  CorrectionCacheFiles f;
  f.map = (fs::path(s.cache_dir) / (stem + ".tmap")).string();
  if (cols > 0) f.op = (fs::path(s.cache_dir) / fmt::format("{}_{}x{}.gop", stem, cols, rows)).string();
  return f;
}

std::vector<CameraOperator> camera_operators(const CorrectionScene& cs) {
  std::vector<CameraOperator> out;
  for (const CorrectionCamera& c : cs.cameras) out.push_back({&c.op, 1.0});
  return out;
}

}  // namespace glasspiv
