#include "apps/demo_alignment.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "align/align_pose.h"
#include "align/fiducial_detection.h"
#include "align/overlay_image.h"
#include "align/prepared_scene.h"
#include "align/scene_fiducials.h"
#include "align/sensitivity.h"
#include "align/sensitivity_picture.h"
#include "align/setup_similarity.h"
#include "apps/html_text.h"
#include "apps/png_file.h"
#include "render/setup_render.h"
#include "sim/setup_photo.h"
#include "util/atomic_file.h"
#include "util/input_error.h"
#include "util/stopwatch.h"

namespace glasspiv {
namespace {
namespace fs = std::filesystem;

// The photo is rendered with 3 x 3 samples per pixel, the refinement's renders
// with 1: the truth is not the optimiser's own picture. (2 x 2 aliases the
// marker edges enough to double the marker pose's error.)
constexpr int kPhotoSamplesPerAxis = 3;
// Coarse levels only, relative to the demo's binned camera (80 x 67 and
// 160 x 135 px, intensities: the wide basin); with the corners they end
// 0.067 mm from the truth. A binning 2 level (gradients) would double this
// step's run time.
const std::vector<int> kRefineLevels = {8, 4};
constexpr int kSensitivityStepPx = 8;

DemoPoseError pose_error(const RigidTransform& fitted, const RigidTransform& truth) {
  const Eigen::AngleAxisd d(fitted.rotation * truth.rotation.transpose());
  return {(fitted.inverse().translation_mm - truth.inverse().translation_mm).norm(),
          std::abs(d.angle()) * 180 / M_PI};
}

std::string file_name(const std::string& path) { return fs::path(path).filename().string(); }

std::string write_page(const fs::path& out, const DemoAlignmentSummary& s, double sensitivity_top_mm) {
  std::string page;
  page += "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n";
  page += "<title>glasspiv demo: alignment</title>\n";
  page += "<style>body{font-family:sans-serif;max-width:1000px;margin:2em auto;color:#222}"
          "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}"
          "th{background:#f4f4f4}td:first-child,th:first-child{text-align:left}img{max-width:100%;border:1px solid #ddd}"
          "figure{margin:1.5em 0}.pair{display:flex;gap:1em}.pair figure{flex:1;margin:0.5em 0}</style>\n";
  page += "</head><body>\n<h1>Alignment of the reactor model on a photograph</h1>\n";
  page += fmt::format(
      "<p>A synthetic photograph ({}&times;{} px) of the reference reactor with 14 ArUco markers on its front frame "
      "and a ChArUco board behind the packing, rendered through the glass from the scene's pose (the truth), "
      "blurred, vignetted, with 0.5 grey levels of noise. Every error below is against that truth. {}</p>\n",
      s.width, s.height,
      s.calibrated_intrinsics
          ? "The camera's intrinsics are the demo's own calibration of it (20 synthetic ChArUco photos), not the "
            "truth: their small errors are absorbed by the pose, as in a real session."
          : "The camera's intrinsics are the true ones.");
  page += fmt::format("<figure><img src=\"{}\" alt=\"photo\"><figcaption>The photograph.</figcaption></figure>\n",
                      file_name(s.photo_png));

  page += "<h2>Pose from the fiducials</h2>\n<table>\n<tr><th></th><th>position error</th><th>rotation error</th>"
          "<th>RMS</th></tr>\n";
  page += fmt::format("<tr><td>traced through the glass</td><td>{:.4f} mm</td><td>{:.5f}&deg;</td><td>{:.3f} px</td></tr>\n",
                      s.pose_error.position_mm, s.pose_error.rotation_deg, s.pose_rms_px);
  page += fmt::format("<tr><td>plain pinhole</td><td>{:.4f} mm</td><td>{:.5f}&deg;</td><td>{:.3f} px</td></tr>\n",
                      s.pinhole_error.position_mm, s.pinhole_error.rotation_deg, s.pinhole_rms_px);
  page += "</table>\n";
  page += fmt::format(
      "<p>{} of {} markers found. {} corners used, {} dropped as outliers. 1&sigma;: position [{:.4f}, {:.4f}, "
      "{:.4f}] mm, rotation {:.5f}&deg;.</p>\n",
      s.markers_found, s.markers, s.pose_inliers, s.pose_outliers, s.position_sigma_mm.x(), s.position_sigma_mm.y(),
      s.position_sigma_mm.z(), s.rotation_sigma_deg);
  if (s.board_corners == 0)
    page += "<p>None of the rear board's corners was found: it is seen only through the spheres, magnified, "
            "inverted and in pieces, and takes part in the refinement through the picture alone. Every corner used "
            "is seen directly, so the pinhole fit is the traced one.</p>\n";
  else
    page += fmt::format("<p>{} corners of the rear board found, {} used; the glass displaces corners by up to {:.1f} "
                        "px.</p>\n",
                        s.board_corners, s.board_inliers, s.glass_displacement_px);

  page += "<h2>Refinement on the picture</h2>\n";
  page += fmt::format(
      "<p>The camera pose optimised until render and photo agree (blurred intensities on these coarse levels) and "
      "the fiducial corners meet their traced projections, from a start off by {:.3f} mm and {:.3f}&deg;, to "
      "{:.4f} mm and {:.5f}&deg; from the truth; {} renders in {:.1f} s. At {}&times;{} px: gradient NCC {:.4f} "
      "&rarr; {:.4f} (the truth's render: {:.4f}), edge distance {:.2f} px &rarr; {:.3f} px.</p>\n",
      s.start_error.position_mm, s.start_error.rotation_deg, s.refined_error.position_mm,
      s.refined_error.rotation_deg, s.renders, s.refine_seconds, s.width, s.height, s.gradient_ncc_before,
      s.gradient_ncc_after, s.gradient_ncc_truth, s.edge_distance_before_px, s.edge_distance_after_px);
  page += "<p>The markers alone give the pose better: a picture of this narrow view trades a lateral shift against "
          "a rotation. The refinement is what checks the model against the whole picture, and what can fit the "
          "glass's position and index, which markers cannot.</p>\n";
  page += "<table>\n<tr><th>binning (of the demo camera)</th><th>size</th><th>gradient NCC before</th><th>after</th>"
          "<th>corner RMS after</th><th>steps</th><th>renders</th><th>s</th></tr>\n";
  for (const RefineLevel& l : s.levels)
    page += fmt::format("<tr><td>{}</td><td>{}&times;{}</td><td>{:.4f}</td><td>{:.4f}</td><td>{:.3f} px</td><td>{}</td>"
                        "<td>{}</td><td>{:.1f}</td></tr>\n",
                        l.binning, l.width_px, l.height_px, l.gradient_ncc_before, l.gradient_ncc_after,
                        l.corner_rms_px_after, l.iterations, l.renders, l.seconds);
  page += "</table>\n";
  page += "<p>Overlays: photo green, render magenta (grey where they agree); edges: rendered magenta, photo green, "
          "yellow where both.</p>\n";
  page += fmt::format(
      "<div class=\"pair\"><figure><img src=\"{}\" alt=\"before\"><figcaption>Before (the perturbed start)."
      "</figcaption></figure><figure><img src=\"{}\" alt=\"after\"><figcaption>After the refinement.</figcaption>"
      "</figure></div>\n",
      file_name(s.overlay_before_png), file_name(s.overlay_after_png));
  page += fmt::format(
      "<div class=\"pair\"><figure><img src=\"{}\" alt=\"edges before\"><figcaption>Edges before.</figcaption>"
      "</figure><figure><img src=\"{}\" alt=\"edges after\"><figcaption>Edges after.</figcaption></figure></div>\n",
      file_name(s.overlay_before_edges_png), file_name(s.overlay_after_edges_png));

  page += "<h2>Sensitivity</h2>\n";
  page += fmt::format(
      "<p>How far the sheet point each pixel sees moves (mm) and the image of a sheet point moves (px) under the "
      "model's remaining uncertainty: the marker pose's covariance, glass position, sphere diameter and refractive "
      "index at their default tolerances; first order, one sample every {} px ({} with a direct view of the sheet). "
      "Yellow = {:.3g} mm and more, grey = no direct view.</p>\n",
      s.sensitivity_step_px, s.sensitivity_valid_points, sensitivity_top_mm);
  page += fmt::format("<figure><img src=\"{}\" alt=\"sensitivity\"><figcaption>Displacement of the seen sheet point, "
                      "mm.</figcaption></figure>\n",
                      file_name(s.sensitivity_png));
  page += "<table>\n<tr><th>parameter (1&sigma;)</th><th>median px</th><th>95% px</th><th>median mm</th>"
          "<th>95% mm</th></tr>\n";
  for (const DemoSensitivityRow& r : s.sensitivity)
    page += fmt::format("<tr><td>{}</td><td>{:.4g}</td><td>{:.4g}</td><td>{:.4g}</td><td>{:.4g}</td></tr>\n",
                        html_escape(r.sigma > 0 ? fmt::format("{} ({:g})", r.name, r.sigma) : r.name), r.median_px,
                        r.p95_px, r.median_mm, r.p95_mm);
  page += "</table>\n</body></html>\n";
  const std::string path = (out / "alignment.html").string();
  write_file_atomically(path, page);
  return path;
}

}  // namespace

DemoAlignmentSummary run_alignment_demo(const std::string& folder, const std::string& scene_path, int binning,
                                        const CameraModel* calibrated) {
  const Stopwatch total;
  const fs::path out(folder);
  fs::create_directories(out);
  DemoAlignmentSummary s;
  const PreparedScene ps = prepare_scene(scene_path, "", binning);
  const CameraModel& true_model = ps.camera().model;
  if (calibrated && (calibrated->width_px() != true_model.width_px() || calibrated->height_px() != true_model.height_px()))
    throw std::invalid_argument("run_alignment_demo: the calibrated camera's image size differs from the scene's");
  const CameraModel& model = calibrated ? *calibrated : true_model;  // the user's camera
  const RigidTransform truth = *ps.camera().camera_from_world;
  s.calibrated_intrinsics = calibrated != nullptr;
  s.width = model.width_px();
  s.height = model.height_px();
  SetupLook look;
  look.background_radiance = ps.scene.background.radiance;
  look.textures = ps.textures_by_solid();
  const std::unique_ptr<SceneIndex> index = make_scene_index(ps.trace);
  const auto render_with = [&](const CameraModel& camera, const RigidTransform& pose, int samples) {
    return render_setup(ps.trace, *index, look, camera, pose, TraceOptions{}, samples, 0);
  };
  const auto render = [&](const RigidTransform& pose, int samples) { return render_with(model, pose, samples); };
  const auto as_mat = [&](std::vector<float>& v) { return cv::Mat(s.height, s.width, CV_32F, v.data()); };

  // The photograph: the truth's render, made to look like a camera's.
  std::printf("   rendering the photograph through the glass...\n");
  Stopwatch clock;
  const cv::Mat photo8 =
      photo_from_radiance(render_with(true_model, truth, kPhotoSamplesPerAxis), s.width, s.height, PhotoLook{});
  s.photo_seconds = clock.seconds();
  s.photo_png = (out / "photo.png").string();
  write_png(s.photo_png, photo8);
  cv::Mat photo;
  photo8.convertTo(photo, CV_32F, 1.0 / 255);

  // Pose from the fiducials.
  std::printf("   the pose from the fiducials...\n");
  clock.restart();
  const std::vector<SceneFiducial> fiducials = scene_fiducials(ps.scene);
  const FiducialsInPhoto found = detect_fiducials(photo8, fiducials, s.photo_png);
  std::vector<bool> is_board(fiducials.size());
  for (std::size_t f = 0; f < fiducials.size(); ++f) {
    const TargetKind kind = fiducials[f].spec.kind;
    is_board[f] = kind != TargetKind::aruco_marker && kind != TargetKind::apriltag;
    if (is_board[f]) {
      s.board_corners += found.corners_per_fiducial[f];
      s.board_corner_ids += static_cast<int>(fiducials[f].corners_board.size());
    } else {
      ++s.markers;
      s.markers_found += found.corners_per_fiducial[f] > 0;
    }
  }
  AlignPoseOptions pose_options;
  pose_options.threads = 1;
  const AlignedPose pose =
      align_pose(ps.trace, *index, ps.info.rectangle_solids, fiducials, model, found.corners, pose_options);
  s.pose_seconds = clock.seconds();
  s.pose_error = pose_error(pose.fit.camera_from_world, truth);
  s.pinhole_error = pose_error(pose.pinhole.camera_from_world, truth);
  s.pose_rms_px = pose.fit.rms_px;
  s.pinhole_rms_px = pose.pinhole.rms_px;
  s.pose_inliers = pose.fit.inlier_count;
  s.pose_outliers = pose.fit.outlier_count;
  for (const FiducialFit& f : pose.fiducials)
    if (is_board[static_cast<std::size_t>(f.fiducial)]) s.board_inliers += f.corners - f.outliers;
  s.glass_displacement_px = pose.glass_displacement_px;
  s.position_sigma_mm = pose.fit.position_sigma_mm;
  s.rotation_sigma_deg = pose.fit.rotation_sigma_deg;

  // Refinement on the picture and the fiducial corners (as `glasspiv align
  // refine` does) from a start 2 mm along a skew direction and 1 degree about
  // another (camera frame), as tests/align/align_refine_test.cpp.
  std::printf("   refining the pose on the picture from a start off by 2 mm and 1 degree...\n");
  const RigidTransform start =
      RigidTransform::from_rvec_tvec(Eigen::Vector3d(0.6, -0.7, 0.4).normalized() * (M_PI / 180),
                                     Eigen::Vector3d(1.2, 0.9, -1.3).normalized() * 2) *
      truth;
  s.start_error = pose_error(start, truth);
  RefineOptions refine;
  refine.binning_levels = kRefineLevels;
  const std::vector<RefineCorner> corners = refine_corners(found.corners, fiducials, ps.info.rectangle_solids);
  const RefineResult r = refine_alignment(ps.trace, look, model, start, photo, {}, refine, corners);
  s.refined_error = pose_error(r.camera_from_world, truth);
  s.levels = r.levels;
  s.renders = r.renders;
  s.refine_seconds = r.seconds;

  // Overlays and scores at the demo camera's full size, before and after.
  std::vector<float> before = render(start, 1), after = render(r.camera_from_world, 1), at_truth = render_with(true_model, truth, 1);
  const PhotoEdgeModel photo_edges(photo);
  const Similarity score_before = photo_edges.compare(as_mat(before)), score_after = photo_edges.compare(as_mat(after));
  s.gradient_ncc_before = score_before.gradient_ncc;
  s.gradient_ncc_after = score_after.gradient_ncc;
  s.edge_distance_before_px = score_before.chamfer_px;
  s.edge_distance_after_px = score_after.chamfer_px;
  s.gradient_ncc_truth = photo_edges.compare(as_mat(at_truth)).gradient_ncc;
  s.overlay_before_png = (out / "overlay_before.png").string();
  s.overlay_before_edges_png = (out / "overlay_before_edges.png").string();
  s.overlay_after_png = (out / "overlay_after.png").string();
  s.overlay_after_edges_png = (out / "overlay_after_edges.png").string();
  write_png(s.overlay_before_png, overlay_blend(as_mat(before), photo));
  write_png(s.overlay_before_edges_png, overlay_edges(as_mat(before), photo));
  write_png(s.overlay_after_png, overlay_blend(as_mat(after), photo));
  write_png(s.overlay_after_edges_png, overlay_edges(as_mat(after), photo));

  // Sensitivity of the measurement to what remains uncertain after the marker pose.
  std::printf("   the sensitivity map...\n");
  clock.restart();
  ModelTolerances tolerances;
  tolerances.pose_covariance = pose.fit.covariance.topLeftCorner<6, 6>();
  SensitivityOptions sensitivity;
  sensitivity.grid_step_px = kSensitivityStepPx;
  const SensitivityMap m = model_sensitivity(ps.trace, model, pose.fit.camera_from_world, tolerances, 2, 1, sensitivity);
  s.sensitivity_seconds = clock.seconds();
  s.sensitivity_step_px = m.grid_step_px;
  s.sensitivity_valid_points = m.valid_points;
  for (const SensitivityParameter& p : m.parameters)
    s.sensitivity.push_back({p.name, p.sigma, p.median_px, p.p95_px, p.median_mm, p.p95_mm});
  s.sensitivity.push_back({"all together", 0, m.median_px, m.p95_px, m.median_mm, m.p95_mm});
  s.sensitivity_png = (out / "sensitivity_mm.png").string();
  write_png(s.sensitivity_png, sensitivity_heat_map(m, m.displacement_mm, m.p95_mm));

  s.recovered = Camera{ps.camera().name, model, r.camera_from_world, ps.camera().pixel_pitch_um};
  s.html = write_page(out, s, m.p95_mm);
  s.seconds = total.seconds();
  return s;
}

}  // namespace glasspiv
