// model_fit_bench: the model fit (align/model_fit.h) on the rig at full
// size, 3 x 3 balls, 640 x 512 px: accuracy against the truth (drawing and
// fitted side by side), the fit's time and rays against one transport-map build
// of the same camera in the same run, and the verdict on a photo of another
// plate. Results in bench/RESULTS.md.
//   ./build/bench/model_fit_bench [width_px height_px]
#include <cstdio>
#include <cstdlib>

#include "align/mapping_comparison.h"
#include "align/model_fit.h"
#include "align/plate_picture.h"
#include "render/transport_map.h"
#include "sim/plate_experiment.h"
#include "util/stopwatch.h"

using namespace glasspiv;

namespace {

PlateTexture speckle(double dot_mm, std::uint64_t seed) { return plate_texture(speckle_spec(170, 140, dot_mm, seed), 0.05); }

cv::Mat as_float(const cv::Mat& m) {
  cv::Mat f;
  m.convertTo(f, CV_32F);
  return f;
}

}  // namespace

int main(int argc, char** argv) {
  const int w = argc > 2 ? std::atoi(argv[1]) : 640, h = argc > 2 ? std::atoi(argv[2]) : 512;
  const PlateRig rig = ball_layer_rig(w, h);
  const double dot_mm = 0.5 * 640.0 / w;  // about 2 px in the direct view
  const PlateTexture plate = speckle(dot_mm, 1);
  BuildDeviation dev;
  dev.seed = 3;
  const AsBuilt truth = as_built(rig.drawing, {rig.camera_from_world}, dev);
  const cv::Mat photo = as_float(plate_photo(truth.scene, rig.camera, truth.camera_from_world[0], *plate.texture));

  Stopwatch map_clock;
  const TransportMap map = build_transport_map(rig.drawing, rig.camera, rig.camera_from_world, TraceOptions{});
  const double map_s = map_clock.seconds();

  const ModelFitResult fit = fit_model(rig.drawing, {{"cam0", rig.camera, rig.camera_from_world, photo}}, plate.picture());
  long rays = 0;
  for (const ModelFitLevel& l : fit.levels) rays += l.traced_rays;

  const Eigen::Vector2d extent(plate.width_mm - 4, plate.height_mm - 4);
  const MappingModel true_model{&truth.scene, rig.camera, truth.camera_from_world[0]};
  const MappingDifference before = compare_mappings(true_model, {&rig.drawing, rig.camera, rig.camera_from_world}, 2, extent);
  const MappingDifference after = compare_mappings(true_model, {&fit.scene, rig.camera, fit.camera_from_world[0]}, 2, extent);

  std::printf("model_fit_bench: 3 x 3 balls, %d x %d px, speckle dots %.2f mm, build seed %llu\n", w, h, dot_mm,
              static_cast<unsigned long long>(dev.seed));
  std::printf("| | drawing | fitted |\n|---|---|---|\n");
  std::printf("| mapping through the glass, px RMS (p95) | %.3f (%.3f) | %.4f (%.4f) |\n", before.glass.rms_px,
              before.glass.p95_px, after.glass.rms_px, after.glass.p95_px);
  std::printf("| mapping in the direct view, px RMS (p95) | %.3f (%.3f) | %.4f (%.4f) |\n", before.direct.rms_px,
              before.direct.p95_px, after.direct.rms_px, after.direct.p95_px);
  std::printf("| glass index error | %.1e | %.1e |\n", dev.index_offset,
              fit.scene.solids[0].material.refractive_index - truth.scene.solids[0].material.refractive_index);
  std::printf("fit: %.1f s, %ld rays (%.1f map builds' worth of camera rays); one map build (default options): %.2f s; "
              "fit / map build time %.1fx\n",
              fit.seconds, rays, static_cast<double>(rays) / static_cast<double>(map.stats.camera_rays), map_s,
              fit.seconds / map_s);
  for (const ModelFitLevel& l : fit.levels)
    std::printf("  level %d: %d px, residual %.1f -> %.1f, %d steps, %ld rays, %.1f s\n", l.binning, l.pixels,
                l.rms_before, l.rms_after, l.iterations, l.traced_rays, l.seconds);
  std::printf("explained variance: %.3f\n", fit.explained_variance);

  // A photo of another plate (another seed): the verdict the command gives.
  const PlateTexture other = speckle(dot_mm, 2);
  const cv::Mat wrong = as_float(plate_photo(truth.scene, rig.camera, truth.camera_from_world[0], *other.texture));
  ModelFitOptions quick;
  quick.binning_levels = {4, 2};
  const ModelFitResult refused =
      fit_model(rig.drawing, {{"cam0", rig.camera, rig.camera_from_world, wrong}}, plate.picture(), {}, {}, quick);
  std::printf("photo of another plate (seed 2) against plate seed 1: explained variance %.3f (the command refuses "
              "below 0.5)\n",
              refused.explained_variance);
  return 0;
}
