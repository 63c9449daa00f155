// glasspiv render: the image a scene camera records of a textured light sheet
// (through the transport map, cached on request), or the setup itself.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

#include <fmt/format.h>

#include "apps/cli_checks.h"
#include "apps/cli_files.h"
#include "apps/commands.h"
#include "align/prepared_scene.h"
#include "render/forward_render.h"
#include "render/render_defaults.h"
#include "render/setup_render.h"
#include "render/sheet_pattern.h"
#include "render/scene_yaml.h"
#include "render/transport_map_cache.h"
#include "render/transport_map_file.h"
#include "util/image_file.h"
#include "util/input_error.h"
#include "util/progress_bar.h"
#include "util/stopwatch.h"

namespace glasspiv {
namespace {

struct RenderOptions {
  std::string scene, camera, output, sheet_texture, pattern, map, format;
  bool setup = false, no_reflections = false;
  double background = -1, texture_mm_per_px = 0, pattern_mm = 10, particle_density = 2, particle_diameter_mm = 0.2, gain = 1;
  double min_weight = TraceOptions{}.min_weight, min_weight_reflected = TraceOptions{}.min_weight_reflected;
  // The render's defaults interpolate ghosts, and whole samples, where the
  // anchors agree (render/render_defaults.h).
  int reflection_grid = render_trace_options().reflection_grid;
  double reflection_grid_tolerance = render_trace_options().reflection_grid_tolerance;
  bool whole_samples = render_trace_options().grid_whole_samples;
  int reflection_grid_levels = 0;  // 0: render_trace_options' for the reflections asked
  int max_depth = TraceOptions{}.max_depth, samples = 0, threads = 0, binning = 1;
  std::uint64_t seed = 1;
};

// The picture on the sheet: an image file, or a built-in pattern over the sheet's extent.
SheetTexture sheet_picture(const RenderOptions& o, const SheetPlane& sheet) {
  if (!o.sheet_texture.empty()) {
    const GrayImage img = read_gray_image(o.sheet_texture);
    // Default: as large as fits the sheet's extent, centred.
    const double mm = o.texture_mm_per_px > 0 ? o.texture_mm_per_px
                                              : std::max(sheet.extent_s_mm / img.width, sheet.extent_t_mm / img.height);
    return SheetTexture(img.values.data(), img.height, img.width, mm);
  }
  SheetPicture p;
  if (o.pattern == "checker") {
    p = checkerboard_picture(sheet.extent_s_mm, sheet.extent_t_mm, o.pattern_mm);
  } else if (o.pattern == "grid") {
    p = grid_picture(sheet.extent_s_mm, sheet.extent_t_mm, o.pattern_mm, o.pattern_mm / 10, o.pattern_mm / 20);
  } else {
    p = particle_picture(sheet.extent_s_mm, sheet.extent_t_mm, o.particle_density, o.particle_diameter_mm,
                         o.particle_diameter_mm / 4, o.seed);
  }
  return SheetTexture(p.values.data(), p.rows, p.cols, p.mm_per_texel);
}

// path with "_<name>" before its extension: out.tif -> out_cam0.tif.
std::string with_suffix(const std::string& path, const std::string& name) {
  const std::filesystem::path p(path);
  return (p.parent_path() / (p.stem().string() + "_" + name + p.extension().string())).string();
}

void render_camera(const RenderOptions& o, const std::string& camera_name, const std::string& output,
                   const std::string& map_path, PixelFormat format);

// The built-in picture's size and particle count, against their limits, before any tracing.
void check_sheet_picture(const RenderOptions& o, const Scene& scene) {
  if (o.pattern.empty() || !scene.sheet) return;
  const double es = scene.sheet->extent_mm[0], et = scene.sheet->extent_mm[1];
  const bool particles = o.pattern == "particles";
  const double texel = o.pattern == "checker" ? o.pattern_mm / 8 : o.pattern == "grid" ? o.pattern_mm / 20
                                                                                        : o.particle_diameter_mm / 4;
  const char* field = particles ? "--particle-diameter-mm" : "--pattern-mm";
  const double texels = std::ceil(es / texel) * std::ceil(et / texel);
  if (!(texels <= kMaxSheetPictureTexels))
    throw InputError("", field,
                     fmt::format("{} mm makes the {} picture of the {} x {} mm sheet {} texels ({} mm each); the limit is "
                                 "{} texels",
                                 number(particles ? o.particle_diameter_mm : o.pattern_mm), o.pattern, number(es),
                                 number(et), number(texels), number(texel), number(kMaxSheetPictureTexels)));
  if (particles && !(o.particle_density * es * et <= kMaxSheetParticles))
    throw InputError("", "--particle-density",
                     fmt::format("{} per mm^2 over the {} x {} mm sheet makes {} particles; the limit is {}",
                                 number(o.particle_density), number(es), number(et),
                                 number(o.particle_density * es * et), number(kMaxSheetParticles)));
}

void run_render(const RenderOptions& o) {
  const int sources = !o.sheet_texture.empty() + !o.pattern.empty() + o.setup;
  if (sources != 1)
    throw InputError("", "--sheet-texture", "give exactly one of --sheet-texture IMG, --sheet-pattern NAME, --setup");
  const std::string ext = lower_extension(o.output);
  if (ext != ".tif" && ext != ".tiff" && ext != ".png" && ext != ".exr")
    throw InputError(o.output, "-o", "must end in .tif, .tiff, .png or .exr");
  const PixelFormat format = !o.format.empty() ? pixel_format_from_name(o.format, "--format")
                                               : (ext == ".exr" ? PixelFormat::float32 : PixelFormat::uint16);
  // Refuse a format the file type cannot hold now, not after minutes of tracing.
  if (ext == ".png" && format == PixelFormat::float32)
    throw InputError(o.output, "--format", "PNG holds 8 or 16 bits, not float (use .tif or .exr)");
  if (ext == ".exr" && format != PixelFormat::float32)
    throw InputError(o.output, "--format", "EXR holds float only (use .tif or .png for 8 or 16 bits)");
  // Every camera's outputs, checked against every file the scene reads before any tracing.
  // --camera all: OUT and MAP get the camera's name before their extension.
  const Scene scene = read_scene(o.scene);
  struct Job {
    std::string camera, output, map;
  };
  std::vector<Job> jobs;
  if (o.camera != "all") {
    jobs.push_back({o.camera, o.output, o.map});
  } else {
    for (const SceneCamera& cam : scene.cameras)
      jobs.push_back({cam.name, with_suffix(o.output, cam.name), o.map.empty() ? "" : with_suffix(o.map, cam.name)});
  }
  std::vector<std::string> inputs = scene_input_files(scene);
  if (!o.sheet_texture.empty()) inputs.push_back(o.sheet_texture);
  std::vector<OutputFile> outputs;
  for (const Job& j : jobs) {
    outputs.push_back({j.output, "-o", OutputKind::image});
    if (!j.map.empty()) outputs.push_back({j.map, "--map", OutputKind::transport_map});
  }
  check_outputs(inputs, outputs);
  check_sheet_picture(o, scene);
  for (const Job& j : jobs) render_camera(o, j.camera, j.output, j.map, format);
}

void render_camera(const RenderOptions& o, const std::string& camera_name, const std::string& output,
                   const std::string& map_path, PixelFormat format) {
  const PreparedScene ps = prepare_scene(o.scene, camera_name, o.binning);
  TraceOptions options;
  options.min_weight = o.min_weight;
  options.min_weight_reflected = o.min_weight_reflected;
  options.reflection_grid = o.reflection_grid;
  options.reflection_grid_tolerance = o.reflection_grid_tolerance;
  options.grid_whole_samples = o.whole_samples;
  options.reflection_grid_levels = o.reflection_grid_levels > 0
                                       ? o.reflection_grid_levels
                                       : (o.whole_samples ? render_trace_options(!o.no_reflections).reflection_grid_levels : 1);
  options.max_depth = o.max_depth;
  options.reflections = !o.no_reflections;
  const Camera& camera = ps.camera();
  const RigidTransform& pose = *camera.camera_from_world;
  std::printf("scene %s: %s; camera '%s' %dx%d\n", o.scene.c_str(), count_of(ps.trace.solids.size(), "solid").c_str(),
              ps.camera_name().c_str(), camera.model.width_px(), camera.model.height_px());

  std::vector<float> image;
  const Stopwatch clock;
  if (o.setup) {
    const int samples = o.samples > 0 ? o.samples : 2;
    const std::vector<const SheetTexture*> textures = ps.textures_by_solid();
    SetupLook look;
    look.background_radiance = o.background >= 0 ? o.background : ps.scene.background.radiance;
    look.textures = textures;
    SetupRenderStats stats;
    {
      ProgressBar bar("render setup", static_cast<std::size_t>(camera.model.height_px()));
      image = render_setup(ps.trace, look, camera.model, pose, options, samples, o.threads, [&bar](int done, int) { bar.set_done(static_cast<std::size_t>(done)); }, &stats);
    }
    std::printf("traced the setup: %ld camera rays (%d x %d per pixel), %.1f branches per ray, %ld rays met no "
                "solid (closed form), %.2f s on %d threads\n",
                stats.camera_rays, samples, samples, double(stats.branches_traced) / std::max(1L, stats.camera_rays),
                stats.closed_form_rays, clock.seconds(), stats.threads);
  } else {
    const int samples = o.samples > 0 ? o.samples : 1;
    // The picture (an image file read, or a pattern drawn) before the trace: a bad one fails at once.
    const SheetTexture texture = sheet_picture(o, ps.trace.sheet);
    CachedTransportMap cached;
    {
      ProgressBar bar("trace map", static_cast<std::size_t>(camera.model.height_px()));
      cached = load_or_build_transport_map(ps.trace, camera.model, pose, options, samples, map_path, o.threads,
                                           [&bar](int done, int) { bar.set_done(static_cast<std::size_t>(done)); });
      if (!cached.reused) bar.finish();
    }
    const TransportMap& map = cached.map;
    if (cached.reused) {
      std::printf("reused the transport map %s (fingerprint %s): nothing re-traced\n", map_path.c_str(),
                  fingerprint_hex(cached.fingerprint).c_str());
    } else {
      if (!map_path.empty()) std::printf("traced a new transport map (cache %s: %s)\n", map_path.c_str(), cached.why_traced.c_str());
      const TransportStats& st = map.stats;
      std::printf("traced: %ld camera rays, %ld branches (%.1f per ray), %zu sheet crossings (%.2f per pixel), "
                  "%.2f s on %d threads\n",
                  st.camera_rays, st.branches_traced, double(st.branches_traced) / std::max(1L, st.camera_rays),
                  map.crossing_count(), double(map.crossing_count()) / map.pixel_count(), cached.seconds,
                  st.threads);
      std::printf("skipped: %ld rays met no solid (closed form), %ld branches below min_weight, %ld beyond max_depth, "
                  "%ld reflections not spawned; weight not followed %.3g of a pixel on average\n",
                  st.closed_form_rays, st.branches_cut_by_weight, st.branches_cut_by_depth, st.reflections_skipped,
                  st.cut_weight / map.pixel_count());
      if (reflection_grid_in_effect(options))
        std::printf("reflection grid %d: %ld reflected subtrees and %ld whole samples interpolated between anchors, "
                    "not traced\n",
                    options.reflection_grid, st.subtrees_interpolated, st.samples_interpolated);
      if (cached.written)
        std::printf("wrote the transport map %s (%.1f MiB, fingerprint %s)\n", map_path.c_str(),
                    map.memory_bytes() / 1048576.0, fingerprint_hex(cached.fingerprint).c_str());
    }
    if (map.crossing_count() == 0)
      throw InputError(o.scene, ps.camera_field(),
                       fmt::format("camera '{}' sees none of the sheet: check its pose and the sheet's extent",
                                   ps.camera_name()));
    image = forward_render_values(map, texture, o.background >= 0 ? o.background : ps.scene.background.radiance);
  }
  if (o.gain != 1)
    for (float& v : image) v = static_cast<float>(v * o.gain);
  write_gray_image(output, image.data(), camera.model.width_px(), camera.model.height_px(), format);
  std::printf("wrote %s (%dx%d, %s)\n", output.c_str(), camera.model.width_px(), camera.model.height_px(),
              pixel_format_name(format));
}

}  // namespace

void register_render_command(CLI::App& app) {
  auto o = std::make_shared<RenderOptions>();
  CLI::App* r = app.add_subcommand(
      "render", "Render what a scene camera records: a textured light sheet through the glass, or the setup itself");
  r->add_option("scene", o->scene, "Scene file (docs/scene.md)")->required()->check(CLI::ExistingFile);
  r->add_option("-o,--output", o->output, "Image to write: .tif, .png or .exr")->required();
  r->add_option("--camera", o->camera,
                "Camera name in the scene (default: the first); 'all': every camera, OUT (and --map) get "
                "'_<camera>' before the extension");
  r->add_option("--sheet-texture", o->sheet_texture, "Image laid on the sheet (TIFF, PNG, EXR, ...)")
      ->check(CLI::ExistingFile);
  r->add_option("--texture-mm-per-px", o->texture_mm_per_px,
                "Size of one texture pixel on the sheet (default: the image, centred, just covers the sheet's extent)")
      ->check(CLI::PositiveNumber);
  r->add_option("--sheet-pattern", o->pattern, "Built-in picture on the sheet instead of an image")
      ->check(CLI::IsMember({"checker", "grid", "particles"}));
  r->add_option("--pattern-mm", o->pattern_mm, "Checker square or grid pitch in mm")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  r->add_option("--particle-density", o->particle_density, "Particles per mm^2 of sheet")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  r->add_option("--particle-diameter-mm", o->particle_diameter_mm, "Particle image diameter at 1/e^2, mm")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  r->add_option("--seed", o->seed, "Seed of the particle field")->capture_default_str();
  r->add_flag("--setup", o->setup, "Render the setup itself (glass, opaque parts, targets, background)");
  r->add_option("--map", o->map,
                "Transport map cache: reused when it was made for this exact scene, camera and settings; "
                "otherwise traced and written there");
  r->add_option("--binning", o->binning,
                "Render with the camera read out K x K binned (a quick preview at 1/K^2 of the cost)")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  r->add_option("--samples", o->samples, "Samples per pixel axis (default 1; 2 with --setup)")
      ->check(CLI::Range(1, 16));
  r->add_option("--min-weight", o->min_weight, "Branches below this weight are not followed")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  r->add_option("--min-weight-reflected", o->min_weight_reflected,
                "Branches reflected at least once are cut below this instead, where it is higher than --min-weight "
                "(cheaper ghosts; bench/RESULTS.md tables the error)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  r->add_option("--reflection-grid", o->reflection_grid,
                "Trace reflected subtrees on every Nth sample of each axis only and interpolate those that agree "
                "between them (1: trace every sample whole; bench/RESULTS.md tables the error)")
      ->check(CLI::Range(1, 16))
      ->capture_default_str();
  r->add_option("--reflection-grid-tolerance", o->reflection_grid_tolerance,
                "How closely a subtree must agree to be interpolated: a fraction of a pixel's footprint on the sheet "
                "and of each weight")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  r->add_flag("--whole-samples,!--no-whole-samples", o->whole_samples,
              "With the reflection grid, interpolate a sample whole (its refracted chain too, no ray traced) where "
              "its four anchors agree on everything; --no-whole-samples traces every sample's refracted chain "
              "(default: on)");
  r->add_option("--reflection-grid-levels", o->reflection_grid_levels,
                "2: trace the grid's anchors themselves on a grid twice as coarse and interpolate an anchor whole "
                "where its coarse cell agrees on everything (1: trace every anchor; default 2 with reflections and whole "
                "samples, else 1; bench/RESULTS.md tables the error)")
      ->check(CLI::Range(1, 2));
  r->add_option("--max-depth", o->max_depth, "Most interface events on one path")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  r->add_flag("--no-reflections", o->no_reflections, "Follow refracted branches only (no ghost images)");
  r->add_option("--background", o->background,
                "Radiance of what lies beyond the scene (default: the scene's background.radiance; "
                "1 makes glass edges visible in --setup)")
      ->check(CLI::NonNegativeNumber);
  r->add_option("--gain", o->gain, "Multiply the radiance before writing (integer formats clip at 1)")
      ->capture_default_str();
  r->add_option("--format", o->format, "8, 16 or float (default 16; float for .exr)");
  r->add_option("--threads", o->threads, "Threads (default: all cores)")->check(CLI::NonNegativeNumber);
  r->callback([o]() { run_render(*o); });
}

}  // namespace glasspiv
