// glasspiv align fit: the model fitted part by part to photos of a plate in
// the sheet plane (align/model_fit.h). Thin: parse, call align/, report.
// See docs/alignment.md, "Model fit".
#include <cmath>
#include <cstdio>
#include <map>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "align/fitted_scene.h"
#include "align/model_fit.h"
#include "align/plate_picture.h"
#include "apps/cli_checks.h"
#include "apps/cli_files.h"
#include "apps/commands.h"
#include "render/scene_yaml.h"
#include "render/trace_scene_builder.h"
#include "targets/target_yaml.h"
#include "util/atomic_file.h"
#include "util/file_identity.h"
#include "util/image_file.h"
#include "util/input_error.h"
#include "util/progress_bar.h"

namespace glasspiv {
namespace {

struct FitOptions {
  std::string scene, plate, output, json, camera;
  std::vector<std::string> photos, camera_photos;
  std::vector<int> levels = {4, 2, 1};
  std::vector<double> offsets_mm;  // per PHOTO: the plate's position along the sheet's normal
  std::vector<std::string> fix;
  bool fit_diameters = false, fit_focal = false;
  ModelFitTolerances tol;
  double texel_mm = 0.05;
  double min_explained = 0.5;
  int iterations = ModelFitOptions{}.max_iterations;
  int threads = 0;
  int binning = 1;
};

int camera_index(const Scene& scene, const std::string& name, const std::string& field) {
  if (name.empty()) {
    if (scene.cameras.empty()) throw InputError(scene.source, "cameras", "the scene has no camera");
    return 0;
  }
  for (std::size_t i = 0; i < scene.cameras.size(); ++i)
    if (scene.cameras[i].name == name) return static_cast<int>(i);
  throw InputError(scene.source, field, fmt::format("no camera named '{}' in the scene", name));
}

cv::Mat read_photo(const std::string& path, const CameraModel& camera, const std::string& camera_name) {
  GrayImage img = read_gray_image(path);
  if (img.width != camera.width_px() || img.height != camera.height_px())
    throw InputError(path, "size", fmt::format("is {}x{} px, camera '{}' is {}x{} px", img.width, img.height,
                                               camera_name, camera.width_px(), camera.height_px()));
  return cv::Mat(img.height, img.width, CV_32F, img.values.data()).clone();
}

ModelFitFreedom freedom_of(const FitOptions& o) {
  ModelFitFreedom f;
  f.sphere_diameters = o.fit_diameters;
  f.camera_focal = o.fit_focal;
  for (const std::string& part : o.fix) {
    if (part == "camera") f.camera_pose = false;
    else if (part == "sheet") f.sheet_pose = false;
    else if (part == "spheres") f.sphere_centres = false;
    else if (part == "index") f.refractive_index = false;
    else throw InputError("", "--fix", fmt::format("unknown part '{}' (camera, sheet, spheres, index)", part));
  }
  return f;
}

// The photos and their cameras: PHOTO for --camera, CAM=FILE for the others;
// several photos of one camera only with the plate moved between them.
std::vector<std::pair<int, std::string>> plate_views(const FitOptions& o, const Scene& scene) {
  std::vector<std::pair<int, std::string>> views;
  if (!o.offsets_mm.empty() && o.offsets_mm.size() != o.photos.size())
    throw InputError("", "--plate-offsets-mm",
                     fmt::format("gives {} offsets for {} PHOTOs (one per photo, in order)", o.offsets_mm.size(),
                                 o.photos.size()));
  for (const std::string& p : o.photos) views.emplace_back(camera_index(scene, o.camera, "--camera"), p);
  for (const std::string& cp : o.camera_photos) {
    const std::size_t eq = cp.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == cp.size())
      throw InputError("", "--photo", fmt::format("expected CAMERA=FILE, got '{}'", cp));
    views.emplace_back(camera_index(scene, cp.substr(0, eq), "--photo"), cp.substr(eq + 1));
  }
  if (views.empty()) throw InputError("", "PHOTO", "give a plate photo (PHOTO or --photo CAMERA=FILE)");
  std::vector<std::string> paths;
  for (const auto& v : views) paths.push_back(v.second);
  check_distinct_inputs(paths, "PHOTO", "plate photo");  // one photo named twice is one view
  std::map<int, int> per_camera;
  for (const auto& v : views)
    if (++per_camera[v.first] > 1 && o.offsets_mm.empty())
      throw InputError(v.second, "PHOTO",
                       fmt::format("a second photo of camera '{}': give one plate photo per camera, or the plate's "
                                   "positions with --plate-offsets-mm",
                                   scene.cameras[static_cast<std::size_t>(v.first)].name));
  for (std::size_t i = 0; i < o.offsets_mm.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (o.offsets_mm[i] == o.offsets_mm[j])
        throw InputError("", "--plate-offsets-mm", fmt::format("offset {} mm given twice", o.offsets_mm[i]));
  return views;
}

void print_levels(const ModelFitResult& fit) {
  for (const ModelFitLevel& l : fit.levels)
    std::printf("level %d: %d px, residual %.4g -> %.4g (photo sd %.4g), %d steps, %ld rays, %.1f s\n", l.binning,
                l.pixels, l.rms_before, l.rms_after, l.photo_sd, l.iterations, l.traced_rays, l.seconds);
  std::printf("residual at full resolution: drawing %.4g, fitted %.4g; the model explains %.1f %% of the photo's "
              "variance\n",
              fit.residual_rms_start, fit.residual_rms_end, 100 * fit.explained_variance);
}

// The table of parameters, the spheres no pixel sees, what the photos cannot pin down.
void print_parameters(const ModelFitResult& fit, const std::vector<SphereSolid>& spheres) {
  std::printf("%-34s %14s %14s %12s %12s\n", "parameter", "drawing", "fitted", "1-sigma", "tolerance");
  for (const FittedParameter& p : fit.parameters)
    std::printf("%-34s %14.6f %14.6f %12.3g %12.3g%s\n", p.name.c_str(), p.drawing, p.fitted, p.sigma, p.prior_sigma,
                p.determined() ? "" : "  (not determined by the photos: held by the drawing's tolerance)");
  for (int s : fit.unseen_spheres)
    std::printf("no pixel looks through %s: left at the drawing\n",
                spheres[static_cast<std::size_t>(s)].field.c_str());
  for (const WeakCombination& w : fit.weak) {
    std::string parts;
    for (const auto& [name, weight] : w.parts) parts += fmt::format("{}{:+.2f} {}", parts.empty() ? "" : ", ", weight, name);
    std::printf("the photos cannot separate (%.0f %% of the drawing's information): %s\n", 100 * w.information,
                parts.c_str());
  }
}

nlohmann::json fit_json(const ModelFitResult& fit, const std::vector<SphereSolid>& spheres) {
  nlohmann::json j;
  j["residual_rms_drawing"] = fit.residual_rms_start;
  j["residual_rms_fitted"] = fit.residual_rms_end;
  j["explained_variance"] = fit.explained_variance;
  j["seconds"] = fit.seconds;
  for (const FittedParameter& p : fit.parameters)
    j["parameters"].push_back({{"name", p.name}, {"drawing", p.drawing}, {"fitted", p.fitted}, {"sigma", p.sigma},
                               {"tolerance", p.prior_sigma}, {"determined", p.determined()}});
  for (int s : fit.unseen_spheres) j["unseen_spheres"].push_back(spheres[static_cast<std::size_t>(s)].field);
  for (const WeakCombination& w : fit.weak) {
    nlohmann::json parts;
    for (const auto& [name, weight] : w.parts) parts.push_back({{"parameter", name}, {"weight", weight}});
    j["weak_combinations"].push_back({{"information", w.information}, {"parts", parts}});
  }
  for (const ModelFitLevel& l : fit.levels)
    j["levels"].push_back({{"binning", l.binning}, {"pixels", l.pixels}, {"residual_before", l.rms_before},
                           {"residual_after", l.rms_after}, {"photo_sd", l.photo_sd}, {"iterations", l.iterations},
                           {"rays", l.traced_rays}, {"seconds", l.seconds}});
  std::vector<std::vector<double>> cov(static_cast<std::size_t>(fit.covariance.rows()));
  for (Eigen::Index a = 0; a < fit.covariance.rows(); ++a)
    for (Eigen::Index b = 0; b < fit.covariance.cols(); ++b) cov[static_cast<std::size_t>(a)].push_back(fit.covariance(a, b));
  j["covariance"] = cov;
  return j;
}

// The scene of the fitted model: each camera's pose from its first photo. A
// fitted model the scene format refuses (two balls fitted into each other at
// a contact) is reported, not written as a file that cannot be read back.
Scene checked_fitted_scene(const Scene& scene, const ModelFitResult& fit,
                           const std::vector<std::pair<int, std::string>>& views, const std::string& output) {
  std::vector<FittedCamera> cams;
  std::map<int, bool> written;
  for (std::size_t i = 0; i < views.size(); ++i)
    if (!written[views[i].first]) {
      written[views[i].first] = true;
      cams.push_back({views[i].first, fit.camera_from_world[i], fit.focal_scale[i]});
    }
  Scene fitted = fitted_scene(scene, fit.scene, cams);
  try {
    validate(fitted);
  } catch (const InputError& e) {
    throw InputError(output, e.field(), "the fitted model is not a valid scene (" + e.problem() + "); nothing written");
  }
  return fitted;
}

void run_fit(const FitOptions& o) {
  const Scene scene = read_scene(o.scene);
  const std::vector<std::pair<int, std::string>> views = plate_views(o, scene);
  std::vector<std::string> inputs = scene_input_files(scene);
  inputs.push_back(o.plate);
  for (const auto& v : views) inputs.push_back(v.second);
  std::vector<OutputFile> outputs{{o.output, "-o"}};
  if (!o.json.empty()) outputs.push_back({o.json, "--json"});
  check_outputs(inputs, outputs);

  const TargetSpec spec = read_target_yaml(o.plate);
  const PlateTexture plate = naming_file(o.plate, [&] { return plate_texture(spec, o.texel_mm); });
  const TraceScene drawing = naming_file(o.scene, [&] { return build_trace_scene(scene); });
  std::vector<PlatePhoto> photos;
  for (std::size_t i = 0; i < views.size(); ++i) {
    const auto& [cam, path] = views[i];
    const SceneCamera& sc = scene.cameras[static_cast<std::size_t>(cam)];
    const CameraModel model = o.binning > 1 ? binned(sc.camera.model, o.binning) : sc.camera.model;
    const double offset = i < o.offsets_mm.size() ? o.offsets_mm[i] : 0.0;
    photos.push_back({sc.name, model, *sc.camera.camera_from_world, read_photo(path, model, sc.name), offset});
  }

  ModelFitOptions options;
  options.binning_levels = o.levels;
  options.max_iterations = o.iterations;
  options.threads = o.threads;
  const int steps = static_cast<int>(o.levels.size()) * o.iterations;
  ProgressBar bar("fit", static_cast<std::size_t>(steps));
  options.progress = [&](int level, int iteration, int) { bar.set_done(static_cast<std::size_t>(level * o.iterations + iteration + 1)); };
  const ModelFitResult fit = naming_file(o.scene, [&] {
    return fit_model(drawing, photos, plate.picture(), freedom_of(o), o.tol, options);
  });
  bar.finish();

  print_levels(fit);
  if (fit.explained_variance < o.min_explained)
    throw InputError(views.front().second, "PHOTO",
                     fmt::format("does not show this plate through this model: the fitted model explains {:.1f} % of "
                                 "its variance (at least {:.0f} % expected; residual {:.4g}, photo sd {:.4g}); "
                                 "nothing written",
                                 100 * fit.explained_variance, 100 * o.min_explained, fit.residual_rms_end,
                                 fit.levels.back().photo_sd));
  const std::vector<SphereSolid> spheres = scene.all_spheres();
  print_parameters(fit, spheres);

  const Scene fitted = checked_fitted_scene(scene, fit, views, o.output);
  write_scene(o.output, fitted);
  std::printf("wrote %s\n", o.output.c_str());
  if (!o.json.empty()) {
    write_file_atomically(o.json, fit_json(fit, spheres).dump(2) + "\n");
    std::printf("wrote %s\n", o.json.c_str());
  }
}

}  // namespace

void register_align_fit_command(CLI::App* align) {
  static FitOptions o;
  CLI::App* fit = align->add_subcommand(
      "fit", "fit the model to photos of a plate in the sheet plane: each glass sphere's centre, the glass index, the "
             "sheet's (plate's) pose and the camera poses, photometric, coarse to fine; writes the fitted scene");
  fit->add_option("SCENE", o.scene, "the drawing: scene file (docs/scene.md)")->required()->check(CLI::ExistingFile);
  fit->add_option("PHOTO", o.photos,
                  "the plate photo taken by --camera (8/16-bit TIFF, PNG, ...); several with --plate-offsets-mm")
      ->check(CLI::ExistingFile);
  fit->add_option("--plate-offsets-mm", o.offsets_mm,
                  "per PHOTO, in order: the plate moved this far along the sheet's normal (a traverse; 0 = in the "
                  "sheet); two positions tell the glass index from the balls' distance to the plate")
      ->delimiter(',')
      ->check(CLI::Range(-1000.0, 1000.0));
  fit->add_option("--camera", o.camera, "the scene's camera that took PHOTO (default: the first)");
  fit->add_option("--photo", o.camera_photos, "CAMERA=FILE: a plate photo of another camera (repeat for a rig)");
  fit->add_option("--plate", o.plate, "the plate's target spec (docs/targets.md), lying in the sheet plane")
      ->required()
      ->check(CLI::ExistingFile);
  fit->add_option("-o,--scene-out", o.output, "the fitted scene (YAML)")->required();
  fit->add_option("--json", o.json, "also write every parameter, its 1-sigma and the covariance as JSON");
  fit->add_option("--levels", o.levels, "binning factors, coarse to fine")->delimiter(',')->check(CLI::Range(1, 64));
  fit->add_option("--fix", o.fix, "parts held at the drawing: camera, sheet, spheres, index")->delimiter(',');
  fit->add_flag("--fit-diameters", o.fit_diameters, "also fit each sphere's diameter");
  fit->add_flag("--fit-focal", o.fit_focal, "also fit one scale on each camera's focal length");
  fit->add_option("--camera-mm", o.tol.camera_position_mm, "drawing tolerance (1-sigma) of a camera centre, mm")
      ->check(CLI::PositiveNumber);
  fit->add_option("--camera-deg", o.tol.camera_rotation_deg, "... of a camera's rotation, deg")->check(CLI::PositiveNumber);
  fit->add_option("--sheet-mm", o.tol.sheet_position_mm, "... of the sheet's (plate's) position, mm")
      ->check(CLI::PositiveNumber);
  fit->add_option("--sheet-deg", o.tol.sheet_rotation_deg, "... of the sheet's rotation, deg")->check(CLI::PositiveNumber);
  fit->add_option("--centre-mm", o.tol.sphere_centre_mm, "... of each sphere's centre, mm")->check(CLI::PositiveNumber);
  fit->add_option("--diameter-mm", o.tol.sphere_diameter_mm, "... of each sphere's diameter, mm")
      ->check(CLI::PositiveNumber);
  fit->add_option("--index", o.tol.refractive_index, "... of the glass index")->check(CLI::PositiveNumber);
  fit->add_option("--texel-mm", o.texel_mm, "the plate's picture resolution, mm per texel")->check(CLI::Range(1e-3, 10.0));
  fit->add_option("--iterations", o.iterations, "Gauss-Newton steps per level at most")->check(CLI::Range(1, 200));
  fit->add_option("--min-explained", o.min_explained,
                  "refuse a fit whose model explains less than this fraction of the photo's variance")
      ->check(CLI::Range(0.0, 1.0));
  fit->add_option("--threads", o.threads, "threads (0: all)");
  fit->add_option("--binning", o.binning, "the cameras read out K x K binned (photos of that size; quick runs)")
      ->check(CLI::Range(1, 64));
  fit->callback([] { run_fit(o); });
}

}  // namespace glasspiv
