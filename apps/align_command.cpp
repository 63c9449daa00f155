// glasspiv align: the model placed on the setup by its photographs.
//   align pose   SCENE PHOTO... --camera NAME: pose from the fiducials (through glass)
//   align check  SCENE PHOTO --camera NAME -o overlay.png: render vs photo, scored
//   align refine SCENE PHOTO --camera NAME: pose (and more) optimised on the picture
// Thin: parse, call align/, report. See docs/alignment.md.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

#include <fmt/format.h>
#include <Eigen/Eigenvalues>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "align/align_pose.h"
#include "align/align_refine.h"
#include "align/fiducial_detection.h"
#include "align/overlay_image.h"
#include "align/prepared_scene.h"
#include "align/scene_update.h"
#include "align/sensitivity.h"
#include "align/sensitivity_picture.h"
#include "align/setup_similarity.h"
#include "apps/cli_checks.h"
#include "render/scene_yaml.h"
#include "apps/cli_files.h"
#include "apps/commands.h"
#include "apps/png_file.h"
#include "render/setup_render.h"
#include "targets/photo_io.h"
#include "util/json_document.h"
#include "util/atomic_file.h"
#include "util/file_identity.h"
#include "util/image_file.h"
#include "util/input_error.h"
#include "util/input_file.h"
#include "util/progress_bar.h"

namespace glasspiv {
namespace {
namespace fs = std::filesystem;

struct AlignOptions {
  std::string scene, camera, output, json, scene_out;
  std::vector<std::string> photos, camera_photos;
  bool pinhole = false, refine_focal = false, no_reflections = false;
  bool refine_index = false, refine_glass = false, no_fiducials = false;
  std::vector<int> levels = {8, 4, 2, 1};
  double tol_camera_mm = ModelTolerances{}.camera_position_mm, tol_camera_deg = ModelTolerances{}.camera_rotation_deg;
  double tol_glass_mm = ModelTolerances{}.glass_position_mm, tol_diameter_mm = ModelTolerances{}.sphere_diameter_mm;
  double tol_index = ModelTolerances{}.refractive_index;
  int step_px = 8, mc_samples = 0;
  std::string pose_json;
  unsigned seed = 1;
  int samples = 2, threads = 0, binning = 1;
  double blur_px = 1.5;
};

// The photo's values in [0, 1] (16-bit keeps its levels), checked against the camera.
cv::Mat read_photo_values(const std::string& path, const CameraModel& camera, const std::string& camera_name) {
  GrayImage img = read_gray_image(path);
  if (img.width != camera.width_px() || img.height != camera.height_px())
    throw InputError(path, "size",
                     fmt::format("is {}x{} px, camera '{}' is {}x{} px", img.width, img.height, camera_name,
                                 camera.width_px(), camera.height_px()));
  return cv::Mat(img.height, img.width, CV_32F, img.values.data()).clone();
}

SetupLook look_of(const PreparedScene& ps) {
  SetupLook look;
  look.background_radiance = ps.scene.background.radiance;
  look.textures = ps.textures_by_solid();
  return look;
}

TraceOptions trace_options(const AlignOptions& o) {
  TraceOptions t;
  t.reflections = !o.no_reflections;
  return t;
}

std::string describe_pose(const RigidTransform& camera_from_world) {
  const Eigen::Vector3d c = camera_from_world.inverse().translation_mm, r = camera_from_world.rvec();
  return fmt::format("position [{:.4f}, {:.4f}, {:.4f}] mm, rvec [{:.7f}, {:.7f}, {:.7f}] rad", c.x(), c.y(), c.z(),
                     r.x(), r.y(), r.z());
}

// The change from `a` to `b`: camera centre distance (mm) and rotation angle (deg).
std::pair<double, double> pose_change(const RigidTransform& a, const RigidTransform& b) {
  const Eigen::AngleAxisd d(b.rotation * a.rotation.transpose());
  return {(b.inverse().translation_mm - a.inverse().translation_mm).norm(), std::abs(d.angle()) * 180 / M_PI};
}

nlohmann::json pose_json(const RigidTransform& t) {
  const Eigen::Vector3d c = t.inverse().translation_mm, r = t.rvec(), v = t.translation_mm;
  return {{"rvec", {r.x(), r.y(), r.z()}}, {"tvec_mm", {v.x(), v.y(), v.z()}}, {"position_mm", {c.x(), c.y(), c.z()}}};
}

void write_json(const std::string& path, const nlohmann::json& j) {
  if (!path.empty()) write_file_atomically(path, json_text(j));
}

// -o scene.yaml: the scene with the camera's pose replaced, in the scene's folder.
void check_scene_out(const AlignOptions& o) {
  if (o.scene_out.empty()) return;
  std::error_code ec;
  const fs::path in = fs::absolute(o.scene, ec).parent_path(), out = fs::absolute(o.scene_out, ec).parent_path();
  const fs::path in_canonical = fs::weakly_canonical(in, ec), out_canonical = fs::weakly_canonical(out, ec);
  if (ec || in_canonical != out_canonical)
    throw InputError(o.scene_out, "--scene-out",
                     "must lie in the scene's own folder (its relative paths to cameras and textures stay valid)");
}

void write_scene_out(const AlignOptions& o, const PreparedScene& ps, const RigidTransform& camera_from_world) {
  if (o.scene_out.empty()) return;
  write_file_atomically(o.scene_out, scene_with_camera_poses(o.scene, {{ps.camera_index, camera_from_world}}));
  std::printf("wrote %s (camera '%s' with the new pose)\n", o.scene_out.c_str(), ps.camera_name().c_str());
}

std::string sibling(const std::string& path, const std::string& suffix) {
  const fs::path p(path);
  return (p.parent_path() / (p.stem().string() + suffix + p.extension().string())).string();
}

// Every file the command writes, the names derived from -o (`_edges`, `_checker`,
// `_px`) included, each with its kind: all checked together against every input.
std::vector<OutputFile> outputs_of(const AlignOptions& o, const std::vector<std::string>& derived_suffixes = {}) {
  std::vector<OutputFile> out;
  if (!o.output.empty()) {
    out.push_back({o.output, "-o", OutputKind::image});
    for (const std::string& suffix : derived_suffixes) out.push_back({sibling(o.output, suffix), "-o", OutputKind::image});
  }
  if (!o.json.empty()) out.push_back({o.json, "--json", OutputKind::json});
  if (!o.scene_out.empty()) out.push_back({o.scene_out, "--scene-out", OutputKind::text});
  return out;
}

// The overlays -o writes besides itself.
const std::vector<std::string> kOverlaySuffixes = {"_edges", "_checker"};

void check_files(const AlignOptions& o, const Scene& scene, const std::vector<std::string>& derived_suffixes) {
  std::vector<std::string> inputs = scene_input_files(scene);
  inputs.insert(inputs.end(), o.photos.begin(), o.photos.end());
  if (!o.pose_json.empty()) inputs.push_back(o.pose_json);
  check_outputs(inputs, outputs_of(o, derived_suffixes));
  check_scene_out(o);
}

// --- align pose -----------------------------------------------------------------
// One camera's pose from its photos: detection, fit, report; its JSON object.
nlohmann::json pose_one_camera(const AlignOptions& o, const std::string& camera, const std::vector<std::string>& photos,
                               std::vector<CameraPoseUpdate>* updates) {
  const PreparedScene ps = prepare_scene(o.scene, camera, o.binning, SceneUse::setup_only);
  const std::vector<SceneFiducial> fiducials = scene_fiducials(ps.scene);
  if (fiducials.empty())
    throw InputError(o.scene, "solids",
                     "the scene has no fiducials (rectangles whose texture is a target spec with corners; a speckle "
                     "plate has none)");
  const CameraModel& model = ps.camera().model;
  std::vector<FiducialCorner> corners;
  for (const std::string& photo : photos) {
    cv::Mat gray = read_photo_gray8(photo);
    if (gray.cols != model.width_px() || gray.rows != model.height_px())
      throw InputError(photo, "size", fmt::format("is {}x{} px, camera '{}' is {}x{} px", gray.cols, gray.rows,
                                                  ps.camera_name(), model.width_px(), model.height_px()));
    const FiducialsInPhoto found = detect_fiducials(gray, fiducials, photo);
    int seen = 0;
    for (int n : found.corners_per_fiducial) seen += n > 0;
    std::printf("%s: %d of %zu fiducials, %zu corners\n", photo.c_str(), seen, fiducials.size(), found.corners.size());
    for (const std::string& s : found.duplicated_markers) std::printf("  %s seen more than once: not used\n", s.c_str());
    for (const std::string& s : found.unknown_markers) std::printf("  %s is not in the scene: ignored\n", s.c_str());
    corners.insert(corners.end(), found.corners.begin(), found.corners.end());
  }
  if (corners.empty())
    throw InputError(photos.front(), "fiducials", "none of the scene's fiducials was found in the photos");
  const std::unique_ptr<SceneIndex> index = make_scene_index(ps.trace);
  AlignPoseOptions options;
  options.through_glass = !o.pinhole;
  options.refine_focal = o.refine_focal;
  options.threads = 1;
  const AlignedPose pose = align_pose(ps.trace, *index, ps.info.rectangle_solids, fiducials, model, corners, options);
  const ExtrinsicFit& fit = pose.fit;
  std::printf("pose of camera '%s' from %d corners (%d outliers): RMS %.3f px\n", ps.camera_name().c_str(),
              fit.inlier_count + fit.outlier_count, fit.outlier_count, fit.rms_px);
  std::printf("  %s\n", describe_pose(fit.camera_from_world).c_str());
  std::printf("  1-sigma: position [%.4f, %.4f, %.4f] mm, rotation %.5f deg; reciprocal condition %.2g\n",
              fit.position_sigma_mm.x(), fit.position_sigma_mm.y(), fit.position_sigma_mm.z(), fit.rotation_sigma_deg,
              fit.reciprocal_condition);
  if (o.refine_focal) std::printf("  focal scale %.6f (fx %.3f px)\n", fit.focal_scale, fit.camera.fx_px());
  if (pose.through_glass) {
    const auto [mm, deg] = pose_change(pose.pinhole.camera_from_world, fit.camera_from_world);
    std::printf("  through the glass: corners displaced by up to %.3f px; the plain pinhole fit (RMS %.3f px) is off "
                "by %.4f mm, %.5f deg\n",
                pose.glass_displacement_px, pose.pinhole.rms_px, mm, deg);
  }
  for (const FiducialFit& f : pose.fiducials)
    std::printf("  %-14s %3d corners  RMS %.3f px  max %.3f px%s\n", f.field.c_str(), f.corners, f.rms_px, f.max_px,
                f.outliers ? fmt::format("  ({} outliers)", f.outliers).c_str() : "");
  if (ps.camera().camera_from_world) {
    const auto [mm, deg] = pose_change(*ps.camera().camera_from_world, fit.camera_from_world);
    std::printf("  change from the scene's pose: %.4f mm, %.5f deg\n", mm, deg);
  }
  nlohmann::json j = {{"camera", ps.camera_name()},
                      {"pose", pose_json(fit.camera_from_world)},
                      {"pinhole_pose", pose_json(pose.pinhole.camera_from_world)},
                      {"rms_px", fit.rms_px},
                      {"inliers", fit.inlier_count},
                      {"outliers", fit.outlier_count},
                      {"position_sigma_mm", {fit.position_sigma_mm.x(), fit.position_sigma_mm.y(), fit.position_sigma_mm.z()}},
                      {"rotation_sigma_deg", fit.rotation_sigma_deg},
                      {"glass_displacement_px", pose.glass_displacement_px},
                      {"focal_scale", fit.focal_scale}};
  // The pose's covariance (rvec rad, tvec mm of camera_from_world), for `align sensitivity --pose-json`.
  for (int r = 0; r < 6; ++r) {
    nlohmann::json row = nlohmann::json::array();
    for (int c = 0; c < 6; ++c) row.push_back(fit.covariance(r, c));
    j["covariance"].push_back(row);
  }
  for (const FiducialFit& f : pose.fiducials)
    j["fiducials"].push_back({{"field", f.field}, {"corners", f.corners}, {"rms_px", f.rms_px}, {"max_px", f.max_px}});
  updates->push_back({ps.camera_index, fit.camera_from_world});
  return j;
}

// PHOTO... belong to --camera; each --photo CAM=FILE to its camera (several
// cameras in one run, each posed from its own photos, all written into one scene).
void run_pose(const AlignOptions& o) {
  std::vector<std::pair<std::string, std::vector<std::string>>> per_camera;
  if (!o.photos.empty()) per_camera.push_back({o.camera, o.photos});
  for (const std::string& spec : o.camera_photos) {
    const std::size_t eq = spec.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == spec.size())
      throw InputError("", "--photo", fmt::format("'{}' is not CAMERA=FILE", spec));
    const std::string name = spec.substr(0, eq), file = spec.substr(eq + 1);
    check_input_file(file, "--photo");  // a regular file: a fifo is refused, never opened
    auto it = std::find_if(per_camera.begin(), per_camera.end(), [&](const auto& p) { return p.first == name; });
    if (it == per_camera.end()) it = per_camera.insert(per_camera.end(), {name, {}});
    it->second.push_back(file);
  }
  if (per_camera.empty()) throw InputError("", "PHOTO", "give the photos (PHOTO... with --camera, or --photo CAMERA=FILE)");
  // Each photo is one view: the same file (or a copy) twice would count its
  // corners twice and shrink the reported uncertainty.
  std::vector<std::string> all_photos;
  for (const auto& [name, files] : per_camera) all_photos.insert(all_photos.end(), files.begin(), files.end());
  check_distinct_inputs(all_photos, "PHOTO", "photo");
  // Every output against the scene's files and every photo, before any work.
  const Scene scene = read_scene(o.scene);
  std::vector<std::string> inputs = scene_input_files(scene);
  for (const auto& [name, files] : per_camera) inputs.insert(inputs.end(), files.begin(), files.end());
  check_outputs(inputs, outputs_of(o));
  check_scene_out(o);
  std::vector<CameraPoseUpdate> updates;
  nlohmann::json j;
  for (const auto& [name, files] : per_camera) j["cameras"].push_back(pose_one_camera(o, name, files, &updates));
  // One camera: its object at the top level (what `align sensitivity --pose-json` reads).
  if (per_camera.size() == 1) j = j["cameras"][0];
  write_json(o.json, j);
  if (!o.scene_out.empty()) {
    write_file_atomically(o.scene_out, scene_with_camera_poses(o.scene, updates));
    std::printf("wrote %s (%zu camera poses replaced)\n", o.scene_out.c_str(), updates.size());
  }
}

// --- align check ----------------------------------------------------------------

std::vector<float> render_view(const PreparedScene& ps, const CameraModel& model, const RigidTransform& pose,
                               const AlignOptions& o, const char* label) {
  ProgressBar bar(label, static_cast<std::size_t>(model.height_px()));
  std::vector<float> r = render_setup(ps.trace, look_of(ps), model, pose, trace_options(o), o.samples, o.threads,
                                      [&](int done, int) { bar.set_done(static_cast<std::size_t>(done)); });
  bar.finish();
  return r;
}

void write_overlays(const std::string& output, const cv::Mat& render, const cv::Mat& photo) {
  write_png(output, overlay_blend(render, photo));
  write_png(sibling(output, "_edges"), overlay_edges(render, photo));
  write_png(sibling(output, "_checker"), overlay_checker(render, photo, std::max(16, photo.cols / 16)));
  std::printf("wrote %s (photo green, render magenta), %s (rendered edges magenta, photo edges green), %s\n",
              output.c_str(), sibling(output, "_edges").c_str(), sibling(output, "_checker").c_str());
}

void print_similarity(const char* what, const Similarity& s) {
  std::printf("%s: NCC %.4f, gradient NCC %.4f, edge distance %.3f px (render to photo %.3f, photo to render %.3f)\n",
              what, s.ncc, s.gradient_ncc, s.chamfer_px, s.chamfer_render_to_photo_px, s.chamfer_photo_to_render_px);
}

nlohmann::json similarity_json(const Similarity& s) {
  return {{"ncc", s.ncc},
          {"gradient_ncc", s.gradient_ncc},
          {"edge_distance_px", s.chamfer_px},
          {"edge_distance_render_to_photo_px", s.chamfer_render_to_photo_px},
          {"edge_distance_photo_to_render_px", s.chamfer_photo_to_render_px}};
}

// Marker corners: detected in the photo vs projected through the model.
struct CornerDistances {
  int corners = 0;
  double rms_px = 0, max_px = 0;
};

CornerDistances corner_distances(const PreparedScene& ps, const std::vector<SceneFiducial>& fiducials,
                                 const SceneIndex& index, const CameraModel& model, const RigidTransform& pose,
                                 const std::string& photo) {
  CornerDistances d;
  if (fiducials.empty()) return d;
  const FiducialsInPhoto found = detect_fiducials(read_photo_gray8(photo), fiducials, photo);
  double sum2 = 0;
  for (const FiducialCorner& c : found.corners) {
    const int solid = ps.info.rectangle_solids[static_cast<std::size_t>(fiducials[static_cast<std::size_t>(c.fiducial)].rectangle)];
    const auto start = model.project(pose.apply(c.world_mm));
    if (!start) continue;
    const TracedProjection t = project_through_scene(ps.trace, index, model, pose, c.world_mm, solid, *start);
    if (!t.ok()) continue;
    const double e = (t.pixel_px - c.pixel_px).norm();
    sum2 += e * e;
    d.max_px = std::max(d.max_px, e);
    ++d.corners;
  }
  if (d.corners) d.rms_px = std::sqrt(sum2 / d.corners);
  return d;
}

void run_check(const AlignOptions& o) {
  if (lower_extension(o.output) != ".png") throw InputError(o.output, "-o", "must end in .png");
  const PreparedScene ps = prepare_scene(o.scene, o.camera, o.binning, SceneUse::setup_only);
  check_files(o, ps.scene, kOverlaySuffixes);
  const CameraModel& model = ps.camera().model;
  const cv::Mat photo = read_photo_values(o.photos.front(), model, ps.camera_name());
  const RigidTransform pose = *ps.camera().camera_from_world;
  std::vector<float> radiance = render_view(ps, model, pose, o, "render");
  const cv::Mat render(model.height_px(), model.width_px(), CV_32F, radiance.data());
  const Similarity s = compare_render_to_photo(render, photo);
  print_similarity("score", s);
  const std::unique_ptr<SceneIndex> index = make_scene_index(ps.trace);
  const CornerDistances d = corner_distances(ps, scene_fiducials(ps.scene), *index, model, pose, o.photos.front());
  if (d.corners)
    std::printf("fiducial corners: %d found, detected vs modelled RMS %.3f px, max %.3f px\n", d.corners, d.rms_px,
                d.max_px);
  write_overlays(o.output, render, photo);
  nlohmann::json j = similarity_json(s);
  j["camera"] = ps.camera_name();
  j["fiducial_corners"] = {{"count", d.corners}, {"rms_px", d.rms_px}, {"max_px", d.max_px}};
  write_json(o.json, j);
}

// --- align refine ---------------------------------------------------------------
void run_refine(const AlignOptions& o) {
  if (!o.output.empty() && lower_extension(o.output) != ".png") throw InputError(o.output, "-o", "must end in .png");
  for (int b : o.levels)
    if (b < 1 || b > 64) throw InputError("", "--levels", fmt::format("binning {} is not in 1..64", b));
  const PreparedScene ps = prepare_scene(o.scene, o.camera, o.binning, SceneUse::setup_only);
  check_files(o, ps.scene, kOverlaySuffixes);
  const CameraModel& model = ps.camera().model;
  const cv::Mat photo = read_photo_values(o.photos.front(), model, ps.camera_name());
  const RigidTransform start = *ps.camera().camera_from_world;
  RefineParameters parameters;
  parameters.focal = o.refine_focal;
  parameters.refractive_index = o.refine_index;
  parameters.glass_position = o.refine_glass;
  RefineOptions options;
  options.binning_levels = o.levels;
  options.blur_px = o.blur_px;
  options.trace = trace_options(o);
  options.threads = o.threads;
  options.samples_per_axis = 1;
  // The fiducial corners join the objective (they pin the pose down where the
  // picture of a narrow view cannot).
  std::vector<RefineCorner> corners;
  if (!o.no_fiducials) {
    const std::vector<SceneFiducial> fiducials = scene_fiducials(ps.scene);
    if (!fiducials.empty())
      corners = refine_corners(detect_fiducials(read_photo_gray8(o.photos.front()), fiducials, o.photos.front()).corners,
                               fiducials, ps.info.rectangle_solids);
  }
  std::printf("refining camera '%s' on %s with %zu fiducial corners: levels", ps.camera_name().c_str(),
              o.photos.front().c_str(), corners.size());
  for (int b : o.levels) std::printf(" %d", b);
  std::printf(" (binning)\n");
  const RefineResult r = refine_alignment(ps.trace, look_of(ps), model, start, photo, parameters, options, corners);
  for (const RefineLevel& l : r.levels)
    std::printf("  binning %2d (%dx%d): gradient NCC %.4f -> %.4f in %d steps, %d renders, %.1f s%s\n", l.binning,
                l.width_px, l.height_px, l.gradient_ncc_before, l.gradient_ncc_after, l.iterations, l.renders,
                l.seconds,
                corners.empty() ? ""
                                : fmt::format("; corners RMS {:.3f} px{}", l.corner_rms_px_after,
                                              l.corners_lost ? fmt::format(" ({} without an image)", l.corners_lost) : "")
                                      .c_str());
  const auto [mm, deg] = pose_change(start, r.camera_from_world);
  // A refinement that took no step or lowered the score is no pose: nothing is written.
  if (r.status == RefineStatus::no_step)
    throw InputError(o.scene, "", fmt::format("camera '{}': the refinement took no step from the start (gradient NCC "
                                              "{:.4f} at binning {}): the start shows too little of the setup; "
                                              "nothing written",
                                              ps.camera_name(), r.score_start, r.levels.back().binning));
  if (r.status == RefineStatus::worse)
    throw InputError(
        o.scene, "",
        fmt::format("camera '{}': the refinement ended worse than it started ({} at binning {}; {:.1f} mm and {:.2f} "
                    "deg from the start): the start is too far off; nothing written",
                    ps.camera_name(),
                    corners.empty() ? fmt::format("gradient NCC {:.4f} -> {:.4f}", r.score_start, r.score_end)
                                    : fmt::format("corners RMS {:.3f} -> {:.3f} px, {} -> {} without an image",
                                                  r.corner_rms_start_px, r.corner_rms_end_px, r.corners_lost_start,
                                                  r.corners_lost_end),
                    r.levels.back().binning, mm, deg));
  std::printf("refined pose: %s\n  moved %.4f mm, %.5f deg from the start; %d renders in %.1f s\n",
              describe_pose(r.camera_from_world).c_str(), mm, deg, r.renders, r.seconds);
  if (o.refine_focal) std::printf("  focal scale %.6f\n", r.focal_scale);
  if (o.refine_index) std::printf("  refractive index offset %+.5f\n", r.refractive_index_offset);
  if (o.refine_glass)
    std::printf("  glass offset [%.4f, %.4f, %.4f] mm\n", r.glass_offset_mm.x(), r.glass_offset_mm.y(),
                r.glass_offset_mm.z());
  nlohmann::json j = {{"camera", ps.camera_name()}, {"start", pose_json(start)}, {"pose", pose_json(r.camera_from_world)},
                      {"focal_scale", r.focal_scale}, {"refractive_index_offset", r.refractive_index_offset},
                      {"glass_offset_mm", {r.glass_offset_mm.x(), r.glass_offset_mm.y(), r.glass_offset_mm.z()}},
                      {"renders", r.renders}, {"seconds", r.seconds}};
  for (const RefineLevel& l : r.levels)
    j["levels"].push_back({{"binning", l.binning}, {"gradient_ncc_before", l.gradient_ncc_before},
                           {"gradient_ncc_after", l.gradient_ncc_after}, {"renders", l.renders}, {"seconds", l.seconds}});
  if (!o.output.empty()) {
    const CameraModel refined_model = scaled_focal(model, r.focal_scale);
    const TraceScene refined_scene = adjusted_glass(ps.trace, r.refractive_index_offset, r.glass_offset_mm);
    ProgressBar bar("render", static_cast<std::size_t>(model.height_px()));
    std::vector<float> radiance = render_setup(refined_scene, look_of(ps), refined_model, r.camera_from_world,
                                               trace_options(o), o.samples, o.threads,
                                               [&](int done, int) { bar.set_done(static_cast<std::size_t>(done)); });
    bar.finish();
    const cv::Mat render(model.height_px(), model.width_px(), CV_32F, radiance.data());
    const Similarity after = compare_render_to_photo(render, photo);
    print_similarity("score after", after);
    j["after"] = similarity_json(after);
    write_overlays(o.output, render, photo);
  }
  write_json(o.json, j);
  write_scene_out(o, ps, r.camera_from_world);
}

// The 6 x 6 covariance `align pose --json` wrote.
Eigen::Matrix<double, 6, 6> pose_covariance_from_json(const std::string& path) {
  // Malformed text, NaN and the like: one line naming the file and field (util/json_document.h).
  const nlohmann::json j = read_json_document(path);
  if (!j.is_object()) throw InputError(path, "", "must be a JSON object (write it with `glasspiv align pose --json`)");
  const nlohmann::json rows = j.contains("covariance") ? j.at("covariance") : nlohmann::json();
  if (!rows.is_array() || rows.size() != 6)
    throw InputError(path, "covariance", "needs 6 rows of 6 numbers (write it with `glasspiv align pose --json`)");
  Eigen::Matrix<double, 6, 6> c;
  for (int r = 0; r < 6; ++r) {
    if (!rows[r].is_array() || rows[r].size() != 6) throw InputError(path, "covariance", "needs 6 rows of 6 numbers");
    for (int k = 0; k < 6; ++k) {
      if (!rows[r][k].is_number() || !std::isfinite(rows[r][k].get<double>()))
        throw InputError(path, fmt::format("covariance[{}][{}]", r, k), "must be a finite number");
      c(r, k) = rows[r][k].get<double>();
    }
  }
  if ((c - c.transpose()).norm() > 1e-9 * std::max(1.0, c.norm()))
    throw InputError(path, "covariance", "is not symmetric");
  if (Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>>(c).eigenvalues().minCoeff() < -1e-12 * c.norm())
    throw InputError(path, "covariance", "is not positive semi-definite");
  return c;
}

void run_sensitivity(const AlignOptions& o) {
  if (lower_extension(o.output) != ".png") throw InputError(o.output, "-o", "must end in .png");
  if (o.step_px < 1) throw InputError("", "--step-px", "must be 1 or more");
  if (o.mc_samples == 1) throw InputError("", "--monte-carlo", "needs 2 samples or more");
  const PreparedScene ps = prepare_scene(o.scene, o.camera, o.binning);
  check_files(o, ps.scene, {"_px"});
  ModelTolerances tol;
  tol.camera_position_mm = o.tol_camera_mm;
  tol.camera_rotation_deg = o.tol_camera_deg;
  tol.glass_position_mm = o.tol_glass_mm;
  tol.sphere_diameter_mm = o.tol_diameter_mm;
  tol.refractive_index = o.tol_index;
  if (!o.pose_json.empty()) tol.pose_covariance = pose_covariance_from_json(o.pose_json);
  SensitivityOptions options;
  options.grid_step_px = o.step_px;
  options.threads = o.threads;
  if (o.mc_samples > 1) options.method = SensitivityMethod::monte_carlo;
  SensitivityMap m;
  try {
    m = model_sensitivity(ps.trace, ps.camera().model, *ps.camera().camera_from_world, tol, std::max(o.mc_samples, 2),
                          o.seed, options);
  } catch (const SensitivityError& e) {
    // The option that set the tolerance at fault; the scene's camera otherwise.
    const std::string& t = e.tolerance();
    if (t == "pose_covariance") throw InputError(o.pose_json, "covariance", e.what());
    const char* option = t == "camera_position_mm"    ? "--camera-mm"
                         : t == "camera_rotation_deg" ? "--camera-deg"
                         : t == "glass_position_mm"   ? "--glass-mm"
                         : t == "sphere_diameter_mm"  ? "--diameter-mm"
                         : t == "refractive_index"    ? "--index"
                                                      : nullptr;
    if (option) throw InputError("", option, e.what());
    throw InputError(o.scene, "", fmt::format("camera '{}': {}", ps.camera_name(), e.what()));
  }
  std::printf("sensitivity of camera '%s' (%s, %dx%d samples every %d px, %d see the sheet directly)\n",
              ps.camera_name().c_str(), o.mc_samples > 1 ? "Monte Carlo" : "first order", m.width, m.height,
              m.grid_step_px, m.valid_points);
  std::printf("  %-22s %12s %12s %12s %12s\n", "parameter (1-sigma)", "median px", "95% px", "median mm", "95% mm");
  nlohmann::json j = {{"camera", ps.camera_name()}, {"valid_points", m.valid_points}};
  for (const SensitivityParameter& p : m.parameters) {
    std::printf("  %-22s %12.4g %12.4g %12.4g %12.4g\n", fmt::format("{} ({:g})", p.name, p.sigma).c_str(),
                p.median_px, p.p95_px, p.median_mm, p.p95_mm);
    j["parameters"].push_back({{"name", p.name}, {"sigma", p.sigma}, {"median_px", p.median_px}, {"p95_px", p.p95_px},
                               {"median_mm", p.median_mm}, {"p95_mm", p.p95_mm}});
  }
  std::printf("  %-22s %12.4g %12.4g %12.4g %12.4g\n", "all together", m.median_px, m.p95_px, m.median_mm, m.p95_mm);
  j["total"] = {{"median_px", m.median_px}, {"p95_px", m.p95_px}, {"median_mm", m.median_mm}, {"p95_mm", m.p95_mm}};
  if (m.skipped_glass_meshes) std::printf("  (%d glass meshes kept in place)\n", m.skipped_glass_meshes);
  write_png(o.output, sensitivity_heat_map(m, m.displacement_mm, m.p95_mm));
  write_png(sibling(o.output, "_px"), sensitivity_heat_map(m, m.displacement_px, m.p95_px));
  std::printf("wrote %s (sheet point seen by each pixel, mm; yellow = %.3g mm and more) and %s (its image, px; "
              "yellow = %.3g px), grey where no direct view of the sheet\n",
              o.output.c_str(), m.p95_mm, sibling(o.output, "_px").c_str(), m.p95_px);
  write_json(o.json, j);
}

void add_binning(CLI::App* c, AlignOptions& o) {
  c->add_option("--binning", o.binning, "the camera read out K x K binned (photos of that size; quick runs)")
      ->check(CLI::Range(1, 64));
}

void add_common(CLI::App* c, AlignOptions& o, bool many_photos) {
  c->add_option("SCENE", o.scene, "scene file (docs/scene.md)")->required()->check(CLI::ExistingFile);
  if (many_photos)
    c->add_option("PHOTO", o.photos, "photos of the setup taken by the camera (8/16-bit TIFF, PNG, ...)")
        ->required()
        ->check(CLI::ExistingFile);
  else
    c->add_option("PHOTO", o.photos, "a photo of the setup taken by the camera")
        ->required()
        ->expected(1)
        ->check(CLI::ExistingFile);
  c->add_option("--camera", o.camera, "the scene's camera that took the photos (default: the first)");
  c->add_option("--json", o.json, "also write the figures as JSON");
  add_binning(c, o);
}

}  // namespace

void register_align_commands(CLI::App& app) {
  CLI::App* align = app.add_subcommand("align", "place the model on the setup from photographs of it");
  align->require_subcommand(1);
  static AlignOptions o;

  CLI::App* pose = align->add_subcommand(
      "pose", "the camera's pose from the scene's fiducials (ArUco, AprilTag, boards) found in its photos; corners "
              "seen through glass are projected through the traced model");
  pose->add_option("SCENE", o.scene, "scene file (docs/scene.md)")->required()->check(CLI::ExistingFile);
  pose->add_option("PHOTO", o.photos, "photos taken by --camera (8/16-bit TIFF, PNG, ...)")->check(CLI::ExistingFile);
  pose->add_option("--camera", o.camera, "the scene's camera that took PHOTO... (default: the first)");
  pose->add_option("--photo", o.camera_photos, "CAMERA=FILE: a photo of another camera (repeat for a rig)");
  pose->add_option("--json", o.json, "also write the figures as JSON");
  add_binning(pose, o);
  pose->add_option("-o,--scene-out", o.scene_out, "write the scene with the new pose (in the scene's folder)");
  pose->add_flag("--pinhole", o.pinhole, "plain pinhole projection only (ignore the glass between camera and markers)");
  pose->add_flag("--refine-focal", o.refine_focal, "also fit one scale on the focal length");
  pose->callback([] { run_pose(o); });

  CLI::App* check = align->add_subcommand(
      "check", "render the setup from the camera's pose in the scene, overlay it on the photo and score the overlay");
  add_common(check, o, false);
  check->add_option("-o", o.output, "overlay PNG (also <stem>_edges.png and <stem>_checker.png)")->required();
  check->add_option("--samples", o.samples, "samples per pixel and axis of the render")->check(CLI::Range(1, 16));
  check->add_flag("--no-reflections", o.no_reflections, "no reflected branches in the render");
  check->add_option("--threads", o.threads, "threads (0: all)");
  check->callback([] { run_check(o); });

  CLI::App* refine = align->add_subcommand(
      "refine", "optimise the camera's pose (and on request focal length, glass index and position) until the render "
                "of the setup agrees with the photo, coarse to fine");
  add_common(refine, o, false);
  refine->add_option("-o", o.output, "overlay PNG after the refinement (also _edges, _checker)");
  refine->add_option("--scene-out", o.scene_out, "write the scene with the refined pose (in the scene's folder)");
  refine->add_option("--levels", o.levels, "binning factors, coarse to fine")->delimiter(',');
  refine->add_option("--blur-px", o.blur_px, "Gaussian blur of the compared gradients, binned px")
      ->check(CLI::Range(0.0, 20.0));
  refine->add_flag("--no-fiducials", o.no_fiducials, "the picture alone (ignore the fiducial corners in the photo)");
  refine->add_flag("--refine-focal", o.refine_focal, "also optimise one scale on the focal length");
  refine->add_flag("--refine-index", o.refine_index, "also optimise an offset on every glass solid's index");
  refine->add_flag("--refine-glass", o.refine_glass, "also optimise one translation of all glass solids");
  refine->add_option("--samples", o.samples, "samples per pixel and axis of the final overlay render")
      ->check(CLI::Range(1, 16));
  refine->add_flag("--no-reflections", o.no_reflections, "no reflected branches in the renders");
  refine->add_option("--threads", o.threads, "threads (0: all)");
  refine->callback([] { run_refine(o); });

  CLI::App* sens = align->add_subcommand(
      "sensitivity", "how far sheet points move (mm on the sheet, px in the image) when the model's pose, glass "
                     "position, sphere diameters and refractive index vary within their tolerances (1-sigma)");
  sens->add_option("SCENE", o.scene, "scene file (docs/scene.md)")->required()->check(CLI::ExistingFile);
  sens->add_option("--camera", o.camera, "the scene's camera (default: the first)");
  sens->add_option("-o", o.output, "heat map PNG of the mm displacement (also <stem>_px.png)")->required();
  sens->add_option("--json", o.json, "also write the table as JSON");
  add_binning(sens, o);
  sens->add_option("--camera-mm", o.tol_camera_mm, "camera position 1-sigma per axis, mm")->check(CLI::NonNegativeNumber);
  sens->add_option("--camera-deg", o.tol_camera_deg, "camera rotation 1-sigma per axis, deg")->check(CLI::NonNegativeNumber);
  sens->add_option("--glass-mm", o.tol_glass_mm, "glass position 1-sigma per axis, mm")->check(CLI::NonNegativeNumber);
  sens->add_option("--diameter-mm", o.tol_diameter_mm, "sphere diameter 1-sigma, mm")->check(CLI::NonNegativeNumber);
  sens->add_option("--index", o.tol_index, "refractive index 1-sigma")->check(CLI::NonNegativeNumber);
  sens->add_option("--pose-json", o.pose_json,
                   "the pose covariance from `align pose --json` in place of --camera-mm and --camera-deg")
      ->check(CLI::ExistingFile);
  sens->add_option("--step-px", o.step_px, "one sample per block of this many pixels")->check(CLI::Range(1, 4096));
  sens->add_option("--monte-carlo", o.mc_samples, "Monte Carlo with this many samples instead of first order")
      ->check(CLI::Range(0, 100000));
  sens->add_option("--seed", o.seed, "Monte Carlo seed");
  sens->add_option("--threads", o.threads, "threads (0: all)");
  sens->callback([] { run_sensitivity(o); });

  register_align_fit_command(align);
}

}  // namespace glasspiv
