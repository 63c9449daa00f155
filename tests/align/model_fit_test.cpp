// The model fit (align/model_fit.h) against a build that is not its drawing.
// The truth is richer than the fit's own prediction: the photo is rendered with
// 3 x 3 samples per pixel, reflections (ghosts) on, vignetting and noise, while
// the fit predicts one footprint-averaged sample per pixel without ghosts. The
// judge is independent of the fit: every grid pixel traced through the true
// build and through the fitted model (align/mapping_comparison.h).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "align/mapping_comparison.h"
#include "align/model_fit.h"
#include "render/material.h"
#include "render/sheet_texture.h"
#include "sim/plate_experiment.h"
#include "tests/sanitized_build.h"

namespace glasspiv {
namespace {

// The rig: a 3 x 3 layer of 40 mm N-BK7 balls (touching), the sheet
// 30 mm behind them, a pinhole camera 600 mm in front of the layer.
struct Rig {
  TraceScene scene;
  CameraModel camera;
  RigidTransform camera_from_world;
};

Rig layer_rig(int width_px, int height_px) {
  // 160 mm across the image at the sheet.
  const double f = width_px * 650.0 / 160.0;
  Rig rig{{}, CameraModel(width_px, height_px, f, f, 0.5 * (width_px - 1), 0.5 * (height_px - 1), {}), {}};
  const double n_glass = material_from_name("N-BK7").refractive_index(532);
  rig.scene.fluid_index = standard_air_index(532);
  for (int i = -1; i <= 1; ++i)
    for (int j = -1; j <= 1; ++j)
      rig.scene.solids.push_back({Sphere{Eigen::Vector3d(40.0 * i, 40.0 * j, 0), 20}, TraceMaterial::glass(n_glass)});
  rig.scene.sheet.origin_mm = Eigen::Vector3d(0, 0, 50);
  rig.scene.sheet.s_axis = Eigen::Vector3d::UnitX();
  rig.scene.sheet.t_axis = -Eigen::Vector3d::UnitY();  // t up: the camera's y runs down
  rig.scene.sheet.extent_s_mm = rig.scene.sheet.extent_t_mm = 220;
  rig.camera_from_world.translation_mm = Eigen::Vector3d(0, 0, 600);
  return rig;
}

// A random-dot plate, 170 x 140 mm: discs of dot_mm on a jittered grid, ink
// covering about 40 %, rasterised with 4 x 4 samples per texel.
std::vector<float> speckle_raster(double dot_mm, double mm_per_texel, int cols, int rows, unsigned seed) {
  std::vector<float> paper(static_cast<std::size_t>(cols) * static_cast<std::size_t>(rows), 1.0f);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  const double pitch = dot_mm * std::sqrt(M_PI / 4 / 0.4);
  const double w = cols * mm_per_texel, h = rows * mm_per_texel;
  const double r = 0.5 * dot_mm, r_tex = r / mm_per_texel;
  for (double y = 0; y < h; y += pitch)
    for (double x = 0; x < w; x += pitch) {
      const double cx = (x + pitch * u(rng)) / mm_per_texel, cy = (y + pitch * u(rng)) / mm_per_texel;
      for (int j = std::max(0, static_cast<int>(cy - r_tex) - 1); j <= std::min(rows - 1, static_cast<int>(cy + r_tex) + 1); ++j)
        for (int i = std::max(0, static_cast<int>(cx - r_tex) - 1); i <= std::min(cols - 1, static_cast<int>(cx + r_tex) + 1); ++i) {
          int in = 0;
          for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b) {
              const double dx = i + (a + 0.5) / 4 - cx, dy = j + (b + 0.5) / 4 - cy;
              in += dx * dx + dy * dy <= r_tex * r_tex;
            }
          float& p = paper[static_cast<std::size_t>(j) * static_cast<std::size_t>(cols) + static_cast<std::size_t>(i)];
          p = std::min(p, 1.0f - in / 16.0f);
        }
    }
  return paper;
}

struct Plate {
  std::vector<float> raster;
  std::unique_ptr<SheetTexture> texture;
  PlatePicture picture;
};

Plate speckle_plate(double dot_mm, unsigned seed) {
  Plate p;
  const double mm_per_texel = 0.05;
  const int cols = 3400, rows = 2800;  // 170 x 140 mm
  p.raster = speckle_raster(dot_mm, mm_per_texel, cols, rows, seed);
  p.texture = std::make_unique<SheetTexture>(p.raster.data(), rows, cols, mm_per_texel);
  p.picture = {p.texture.get(), cols * mm_per_texel, rows * mm_per_texel};
  return p;
}

cv::Mat as_float(const cv::Mat& photo) {
  cv::Mat f;
  photo.convertTo(f, CV_32F);
  return f;
}

// A sphere's centre in its model's sheet frame (s, t, normal): where it sits
// relative to the plate, which the photos see. Its world coordinates also
// carry the gauge (a rigid motion of camera, glass and plate together changes
// no photo), which only the drawing's tolerances pin down.
Eigen::Vector3d in_sheet_frame(const TraceScene& scene, std::size_t solid) {
  const Eigen::Vector3d d = std::get<Sphere>(scene.solids[solid].shape).centre_mm - scene.sheet.origin_mm;
  return Eigen::Vector3d(d.dot(scene.sheet.s_axis), d.dot(scene.sheet.t_axis), d.dot(scene.sheet.normal()));
}

double centre_error_rms_um(const TraceScene& truth, const TraceScene& fitted, const std::vector<int>& unseen) {
  double sum = 0;
  int n = 0;
  for (std::size_t i = 0; i < truth.solids.size(); ++i) {
    if (std::find(unseen.begin(), unseen.end(), static_cast<int>(i)) != unseen.end()) continue;
    const Eigen::Vector3d d = in_sheet_frame(truth, i) - in_sheet_frame(fitted, i);
    sum += d.squaredNorm() / 3;
    ++n;
  }
  return 1e3 * std::sqrt(sum / n);
}

// A build off its drawing as hand-built rigs are (centres N(0, 30 um) per
// axis, index +4e-4, sheet 0.15 mm / 0.05 deg, camera 0.03 mm / 0.005 deg),
// one plate photo, 320 x 256 px (the 640 x 512 figures: bench/RESULTS.md).
// Measured: the mapping within 0.0005 px RMS of the truth through the glass
// (drawing: 0.43 px) and 0.0001 px in the direct view (drawing: 0.22 px); the
// centres, in the plate's frame, 6 um RMS (drawing: 80 um); the index 1.4e-4
// off (drawing: 4e-4). The bounds leave a factor of 2 to 20 above those for
// other platforms' round-off and the fit's stopping point. From one photo the
// index trades with the balls' distance to the plate (a ball lens's
// magnification depends on both): the mapping is exact, the index only to
// ~1e-4 (docs/alignment.md).
TEST(ModelFit, RecoversABuildOffItsDrawing) {
  if (kSanitizedBuild) GTEST_SKIP() << "minutes under the sanitizers";
  const Rig rig = layer_rig(320, 256);
  const Plate plate = speckle_plate(0.9, 7);
  BuildDeviation dev;
  dev.seed = 3;
  const AsBuilt truth = as_built(rig.scene, {rig.camera_from_world}, dev);
  const cv::Mat photo = as_float(plate_photo(truth.scene, rig.camera, truth.camera_from_world[0], *plate.texture));

  const ModelFitResult fit =
      fit_model(rig.scene, {{"cam0", rig.camera, rig.camera_from_world, photo}}, plate.picture);

  const Eigen::Vector2d extent(plate.picture.width_mm - 4, plate.picture.height_mm - 4);
  const MappingModel true_model{&truth.scene, rig.camera, truth.camera_from_world[0]};
  const MappingDifference before =
      compare_mappings(true_model, {&rig.scene, rig.camera, rig.camera_from_world}, 2, extent);
  const MappingDifference after =
      compare_mappings(true_model, {&fit.scene, rig.camera, fit.camera_from_world[0]}, 2, extent);
  const double index_error = fit.scene.solids[0].material.refractive_index - truth.scene.solids[0].material.refractive_index;
  std::printf("mapping error, px RMS (p95): drawing glass %.3f (%.3f) direct %.3f (%.3f); fitted glass %.4f (%.4f) direct %.4f (%.4f)\n",
              before.glass.rms_px, before.glass.p95_px, before.direct.rms_px, before.direct.p95_px,
              after.glass.rms_px, after.glass.p95_px, after.direct.rms_px, after.direct.p95_px);
  std::printf("centres RMS: drawing %.1f um, fitted %.2f um; index error: drawing %.1e, fitted %.1e; %.1f s\n",
              centre_error_rms_um(truth.scene, rig.scene, {}), centre_error_rms_um(truth.scene, fit.scene, fit.unseen_spheres),
              dev.index_offset, index_error, fit.seconds);
  for (const ModelFitLevel& l : fit.levels)
    std::printf("  level %d: %d px, rms %.3f -> %.3f, %d iterations, %ld rays, %.1f s\n", l.binning, l.pixels,
                l.rms_before, l.rms_after, l.iterations, l.traced_rays, l.seconds);
  EXPECT_LE(after.glass.rms_px, 0.01);
  EXPECT_LE(after.direct.rms_px, 0.01);
  EXPECT_LE(centre_error_rms_um(truth.scene, fit.scene, fit.unseen_spheres), 12.0);
  EXPECT_LE(std::abs(index_error), 3e-4);
  EXPECT_TRUE(fit.unseen_spheres.empty());
  EXPECT_GT(fit.explained_variance, 0.9);
  EXPECT_GT(before.glass.rms_px, 5 * after.glass.rms_px);  // the fit did something
}

}  // namespace
}  // namespace glasspiv
