#include "apps/demo_render.h"

#include <cstdio>
#include <filesystem>

#include "align/prepared_scene.h"
#include "render/forward_render.h"
#include "render/render_defaults.h"
#include "render/setup_render.h"
#include "render/sheet_pattern.h"
#include "render/transport_map_cache.h"
#include "util/image_file.h"
#include "util/progress_bar.h"
#include "util/stopwatch.h"

namespace glasspiv {

DemoRenderSummary run_render_demo(const std::string& folder, const std::string& scene_path, int binning) {
  namespace fs = std::filesystem;
  const fs::path out(folder);
  fs::create_directories(out);
  const PreparedScene ps = prepare_scene(scene_path, "", binning);
  const CameraModel& model = ps.camera().model;
  const RigidTransform& pose = *ps.camera().camera_from_world;
  const TraceOptions options = render_trace_options();  // as glasspiv render

  DemoRenderSummary s;
  s.width = model.width_px();
  s.height = model.height_px();
  s.map_file = (out / "reactor.tmap").string();
  auto traced = [&](const char* label) {
    ProgressBar bar(label, static_cast<std::size_t>(model.height_px()));
    CachedTransportMap c = load_or_build_transport_map(ps.trace, model, pose, options, 1, s.map_file, 0,
                                                       [&bar](int done, int) { bar.set_done(static_cast<std::size_t>(done)); });
    if (!c.reused) bar.finish();
    return c;
  };
  std::printf("   tracing the transport map (%dx%d px; reused if an earlier run left it)...\n", s.width, s.height);
  {
    const CachedTransportMap first = traced("trace map");
    s.trace_seconds = first.seconds;
    s.map_from_earlier_run = first.reused;
    s.crossings_per_pixel = double(first.map.crossing_count()) / first.map.pixel_count();
    s.closed_form_fraction =
        double(first.map.stats.closed_form_rays) / std::max(1L, first.map.stats.camera_rays);
  }
  // What every later image of a series does: load the cached map.
  const CachedTransportMap again = traced("load map");
  s.reload_seconds = again.seconds;
  s.cache_reused = again.reused;
  if (!again.reused) throw std::runtime_error("demo: the transport map just written does not load");
  const TransportMap* map = &again.map;
  Stopwatch clock;

  std::printf("   rendering a checkerboard and a particle field through the map...\n");
  const SheetPlane& sheet = ps.trace.sheet;
  const SheetPicture checker = checkerboard_picture(sheet.extent_s_mm, sheet.extent_t_mm, 5.0);
  const SheetPicture particles = particle_picture(sheet.extent_s_mm, sheet.extent_t_mm, 1.0, 0.3, 0.075, 1);
  const SheetTexture checker_texture(checker.values.data(), checker.rows, checker.cols, checker.mm_per_texel);
  const SheetTexture particle_texture(particles.values.data(), particles.rows, particles.cols, particles.mm_per_texel);
  clock.restart();
  const std::vector<float> checker_image = forward_render_values(*map, checker_texture);
  const std::vector<float> particle_image = forward_render_values(*map, particle_texture);
  s.render_seconds = clock.seconds() / 2;
  s.checkerboard_png = (out / "reactor_checkerboard.png").string();
  s.particles_tif = (out / "reactor_particles.tif").string();
  write_gray_image(s.checkerboard_png, checker_image.data(), s.width, s.height, PixelFormat::uint8);
  write_gray_image(s.particles_tif, particle_image.data(), s.width, s.height, PixelFormat::uint16);

  std::printf("   rendering the setup itself...\n");
  clock.restart();
  SetupLook look;
  look.background_radiance = 1;  // a lit backdrop shows the glass's edges
  look.textures = ps.textures_by_solid();
  std::vector<float> setup;
  {
    ProgressBar bar("render setup", static_cast<std::size_t>(model.height_px()));
    setup = render_setup(ps.trace, look, model, pose, options, 2, 0, [&bar](int done, int) { bar.set_done(static_cast<std::size_t>(done)); });
  }
  s.setup_seconds = clock.seconds();
  s.setup_png = (out / "reactor_setup.png").string();
  write_gray_image(s.setup_png, setup.data(), s.width, s.height, PixelFormat::uint8);
  return s;
}

}  // namespace glasspiv
