// glasspiv calib detect: find a target's corners in photos, write the observations.
#include <cstdio>
#include <filesystem>
#include <memory>

#include <fmt/format.h>

#include "apps/cli_files.h"
#include "apps/commands.h"
#include "apps/photo_detection.h"
#include "targets/observations_io.h"
#include "targets/target_yaml.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {
namespace fs = std::filesystem;

struct DetectCommandOptions {
  std::vector<std::string> images;
  std::string target, output, vnl;
  PhotoDetectionOptions detection;
};

void run_detect(const DetectCommandOptions& o) {
  const TargetSpec spec = read_target_yaml(o.target);
  require_target_corners(spec, o.target, "calib detect");
  // Refuse what cannot be written before the work.
  observations_format_for_path(o.output);
  int grid_w = 0, grid_h = 0;
  double spacing = 0;
  if (!o.vnl.empty() && !corner_grid(spec, grid_w, grid_h, spacing))
    throw InputError(o.vnl, "--vnl",
                     fmt::format("mrcal's corners.vnl holds a regular grid of corners; a {}'s are not one",
                                 target_kind_name(spec.kind)));
  const std::vector<std::string> photos = expand_photo_inputs(o.images);
  // No output may replace an input (a photo or the target spec): before any detection.
  std::vector<std::string> inputs = photos;
  inputs.push_back(o.target);
  std::vector<CalibOutput> outputs = {{o.output, "-o"}, {o.vnl, "--vnl"}, {o.detection.overlay_dir, "--overlay-dir", OutputKind::folder}};
  for (const std::string& path : overlay_paths(photos, o.detection.overlay_dir)) outputs.push_back({path, "--overlay-dir"});
  check_calib_outputs(inputs, outputs);
  const Observations observations = detect_in_photos(photos, spec, o.target, o.detection);
  write_observations(o.output, observations);
  std::size_t views = 0;
  for (const ViewObservations& v : observations.views) views += v.corners.empty() ? 0 : 1;
  std::printf("wrote %s: %zu corners in %zu of %zu images (%d x %d px)\n", o.output.c_str(),
              observations.corner_count(), views, observations.views.size(), observations.image_width_px,
              observations.image_height_px);
  if (!o.vnl.empty()) {
    write_mrcal_corners_vnl(o.vnl, observations, spec);
    std::printf("wrote %s (mrcal: --object-width-n %d --object-height-n %d --object-spacing %g)\n", o.vnl.c_str(),
                grid_w, grid_h, spacing);
  }
  if (!o.detection.overlay_dir.empty())
    std::printf("wrote %zu overlays to %s\n", photos.size(), folder_shown(o.detection.overlay_dir).c_str());
}

}  // namespace

void register_calib_detect_command(CLI::App& calib) {
  auto o = std::make_shared<DetectCommandOptions>();
  CLI::App* d = calib.add_subcommand("detect", "Find a target's corners in photos and write them as observations");
  d->add_option("images", o->images,
                "Photos of the target, or folders of them (any format OpenCV reads; 16-bit is scaled by its maximum)")
      ->required();
  d->add_option("--target", o->target, "Target spec YAML (docs/targets.md)")->required()->check(CLI::ExistingFile);
  d->add_option("-o,--output", o->output, "Observations to write: .yaml/.yml or .json")->required();
  d->add_option("--vnl", o->vnl, "Also write mrcal's corners.vnl (chessboard and charuco targets)");
  d->add_option("--overlay-dir", o->detection.overlay_dir,
                "Write each photo with its detected corners and ids as PNG here");
  d->add_flag("--accept-unconfirmed-layout", o->detection.lenient_layout,
              "ChArUco boards with an even number of rows: keep views that do not show which layout the board has "
              "(their ids are off by a column if the spec's layout is wrong)");
  d->callback([o] { run_detect(*o); });
}

}  // namespace glasspiv
