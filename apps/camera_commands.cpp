// glasspiv camera convert | show | compare
#include <cstdio>
#include <filesystem>

#include <fmt/format.h>

#include "apps/camera_text.h"
#include "apps/cli_checks.h"
#include "apps/cli_files.h"
#include "apps/commands.h"
#include "apps/plots.h"
#include "calib/io/camera_file.h"
#include "calib/lens_maps.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {

struct ConvertOptions {
  std::string input, output, to, camera, name;
  double pixel_pitch_um = 0;
};

struct ShowOptions {
  std::string input, camera, plot;
  double pixel_pitch_um = 0, step_px = 40;
};

struct CompareOptions {
  std::string a, b, camera_a, camera_b, plot;
  double distance_mm = 1000, step_px = 16;
  bool use_poses = false;
};

// --plot: a PNG, not the camera file or another input, refused before any work.
void check_plot(const std::vector<std::string>& inputs, const std::string& plot) {
  if (plot.empty()) return;
  if (lower_extension(plot) != ".png") throw InputError(plot, "--plot", "must end in .png (plots are PNG pictures)");
  check_outputs(inputs, {{plot, "--plot"}});
}

void run_convert(const ConvertOptions& o) {
  check_outputs({o.input}, {{o.output, "output", OutputKind::text}});
  Camera camera = read_camera(o.input, o.camera);
  if (o.pixel_pitch_um != 0) {
    if (!(o.pixel_pitch_um > 0)) throw InputError("", "--pixel-pitch-um", "must be positive");
    camera.pixel_pitch_um = o.pixel_pitch_um;
  }
  if (!o.name.empty()) camera.name = o.name;
  const CameraFileFormat format = o.to.empty() ? format_for_output_path(o.output) : format_from_name(o.to);
  write_cameras(o.output, {camera}, format);
  std::printf("wrote %s (%s format, camera '%s', %s)\n", o.output.c_str(), format_name(format).c_str(),
              camera.name.c_str(), lens_model_name(camera.model.lens_model()).c_str());
}

void run_show(const ShowOptions& o) {
  check_plot({o.input}, o.plot);
  Camera camera = read_camera(o.input, o.camera);
  check_sample_grid("--step-px", camera.model.width_px(), camera.model.height_px(), o.step_px);
  if (o.pixel_pitch_um > 0) camera.pixel_pitch_um = o.pixel_pitch_um;
  std::fputs(describe_camera(camera).c_str(), stdout);
  const GridValues field = distortion_field(camera.model, o.step_px);
  std::printf("  distortion: RMS %.4g px, max %.4g px over the image (%d of %d samples have a ray)\n", field.rms_px,
              field.max_px, field.valid_count, field.grid.size());
  if (!o.plot.empty()) {
    write_vector_field_png(field, camera.model.width_px(), camera.model.height_px(),
                           {fmt::format("distortion of '{}' ({}): distorted - pinhole pixel", camera.name,
                                        lens_model_name(camera.model.lens_model())),
                            "|distortion| px"},
                           o.plot);
    std::printf("  wrote %s\n", o.plot.c_str());
  }
}

void run_compare(const CompareOptions& o) {
  if (!(o.distance_mm > 0)) throw InputError("", "--distance-mm", "must be positive");
  check_plot({o.a, o.b}, o.plot);
  const Camera a = read_camera(o.a, o.camera_a);
  const Camera b = read_camera(o.b, o.camera_b);
  if (a.model.width_px() != b.model.width_px() || a.model.height_px() != b.model.height_px())
    throw InputError(o.b, "image size",
                     fmt::format("is {}x{} px but '{}' is {}x{} px; compare models of the same sensor",
                                 b.model.width_px(), b.model.height_px(), o.a, a.model.width_px(),
                                 a.model.height_px()));
  check_sample_grid("--step-px", a.model.width_px(), a.model.height_px(), o.step_px);
  RigidTransform b_from_a;
  if (o.use_poses) {
    if (!a.camera_from_world) throw InputError(o.a, "camera_from_world", "--use-poses needs a pose in both files");
    if (!b.camera_from_world) throw InputError(o.b, "camera_from_world", "--use-poses needs a pose in both files");
    b_from_a = *b.camera_from_world * a.camera_from_world->inverse();
  }
  const GridValues diff = projection_difference(a.model, b.model, o.distance_mm, o.step_px, b_from_a);
  std::printf("projection difference '%s' -> '%s' at %.6g mm, %s:\n", a.name.c_str(), b.name.c_str(), o.distance_mm,
              o.use_poses ? "through both poses" : "intrinsics only (same camera frame)");
  std::printf("  RMS %.6g px   max %.6g px   over %d of %d samples (grid %dx%d)\n", diff.rms_px, diff.max_px,
              diff.valid_count, diff.grid.size(), diff.grid.cols, diff.grid.rows);
  if (!o.plot.empty()) {
    write_magnitude_png(diff, a.model.width_px(), a.model.height_px(),
                        {fmt::format("projection difference {} -> {} at {:g} mm", a.name, b.name, o.distance_mm),
                         "|difference| px"},
                        o.plot);
    std::printf("  wrote %s\n", o.plot.c_str());
  }
}

}  // namespace

void register_camera_commands(CLI::App& app) {
  CLI::App* camera = app.add_subcommand("camera", "Camera models: convert between formats, show, compare");
  camera->require_subcommand(1);
  const std::string formats = "glasspiv (.yaml), opencv (.yaml), mrcal (.cameramodel), davis (.xml)";

  auto convert = std::make_shared<ConvertOptions>();
  CLI::App* c = camera->add_subcommand("convert", "Convert a camera file between " + formats);
  c->add_option("input", convert->input, "Camera file to read (format detected from its contents)")
      ->required()
      ->check(CLI::ExistingFile);
  c->add_option("output", convert->output, "File to write (format from the extension unless --to)")->required();
  c->add_option("--to", convert->to, "Output format: glasspiv, opencv, mrcal or davis")
      ->check(CLI::IsMember({"glasspiv", "opencv", "mrcal", "davis"}));
  c->add_option("--camera", convert->camera, "Which camera of a multi-camera file (e.g. a DaVis identifier)");
  c->add_option("--pixel-pitch-um", convert->pixel_pitch_um, "Sensor pixel size in um (DaVis needs it)");
  c->add_option("--name", convert->name, "Rename the camera");
  c->callback([convert] { run_convert(*convert); });

  auto show = std::make_shared<ShowOptions>();
  CLI::App* s = camera->add_subcommand("show", "Print a camera in both presentations and plot its distortion");
  s->add_option("camera_file", show->input, "Camera file")->required()->check(CLI::ExistingFile);
  s->add_option("--camera", show->camera, "Which camera of a multi-camera file");
  s->add_option("--pixel-pitch-um", show->pixel_pitch_um, "Sensor pixel size in um, if the file lacks it");
  s->add_option("--plot", show->plot, "Write the distortion field as a PNG (.png)");
  s->add_option("--step-px", show->step_px,
                fmt::format("Spacing of the plotted samples in px (at most {:g} samples over the image)", kMaxGridSamples))
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  s->callback([show] { run_show(*show); });

  auto compare = std::make_shared<CompareOptions>();
  CLI::App* p = camera->add_subcommand(
      "compare", "Projection difference of two models over the image (as mrcal-show-projection-diff)");
  p->add_option("a", compare->a, "First camera file (the grid is over its image)")->required()->check(CLI::ExistingFile);
  p->add_option("b", compare->b, "Second camera file")->required()->check(CLI::ExistingFile);
  p->add_option("--camera-a", compare->camera_a, "Which camera of A");
  p->add_option("--camera-b", compare->camera_b, "Which camera of B");
  p->add_option("--distance-mm", compare->distance_mm, "Distance of the compared points along the rays, mm")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  p->add_flag("--use-poses", compare->use_poses, "Compare through both files' poses instead of intrinsics only");
  p->add_option("--plot", compare->plot, "Write the difference heat map as a PNG (.png)");
  p->add_option("--step-px", compare->step_px,
                fmt::format("Spacing of the samples in px (at most {:g} samples over the image)", kMaxGridSamples))
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  p->callback([compare] { run_compare(*compare); });
}

}  // namespace glasspiv
