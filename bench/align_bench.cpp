// align_bench: the alignment's costs (align/), with OpenCV as the same-run peer
// where there is one.
//
//   align_bench [repeats] [refinement marker size mm]
//
// repeats (default 11): every timing is the median of that many runs (pose
// fits 4x as many; the traced pose, full-size detection and renders fewer, see
// the printed header); the refinement runs once. The marker size of the
// refinement's setup defaults to 12 mm (see bench/RESULTS.md for 8 mm).
//
// Setups: sim/marker_setup.h, 20 ArUco markers (DICT_4X4_50) on a frame at two
// depths 500 mm from the camera, photographed by sim/setup_photo.h (blur
// 0.7 px, vignette, 0.5 grey levels of noise; 2 x 2 samples per pixel, the
// full-size photo 1).
// "1.3 MP" is the align tests' setup, 1280 x 1024 at f = 2500 px with 8 mm
// markers (40 px); "full" the demo camera's size (data/cameras/example.yaml,
// 2560 x 2160) with the focal scaled by 2160 / 1024, so that it sees the same
// frame (markers 84 px). Rows:
//  1. pose from the 80 corners: calib/fit/extrinsic_fit.h fit_camera_pose
//     (defaults: outlier rounds, covariance; and with outlier_k = 0) against
//     cv::solvePnP(SOLVEPNP_SQPNP) + cv::solvePnPRefineLM (OpenCV's default
//     criteria) on the same points and intrinsics; reprojection RMS of both.
//  2. the traced pose behind a 10 mm N-BK7 window (align/align_pose.h): total,
//     the pinhole fit, and the traced refit split into its traced projections
//     (align/refraction_pose.h, counted and timed inside a projector that does
//     what traced_point_projector does) and the rest (Ceres, covariance).
//  3. marker detection (targets/marker_detect.h) at 1.3 MP and full size,
//     against cv::aruco::detectMarkers alone (glasspiv = detectMarkers + its
//     edge fit) and with OpenCV's CORNER_REFINE_SUBPIX.
//  4. one score evaluation (align/setup_similarity.h PhotoEdgeModel::compare
//     with a kept SimilarityWorkspace) and one setup render
//     (render/setup_render.h with the refinement's settings: 1 sample per
//     pixel, reflections on, min_weight 1e-2) at 1.3 MP and full size; the
//     same-run reference for the score is OpenCV's NCC of the two images
//     (cv::matchTemplate, TM_CCOEFF_NORMED, same size), and the feature the
//     refinement compares per pixel (blurred_gradient_magnitude).
//  5. one whole refinement (align/align_refine.h refine_alignment, default
//     options: levels 8, 4, 2, 1) at 1 MP (1024 x 1024, f = 2500 px, 12 mm
//     markers: 60 px; the outermost are cut by the image's sides) from a start
//     off by 2 mm and 1 degree: per level, renders and seconds, a render and its features alone
//     at that level's size; the final error against the truth.
#include <sys/utsname.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include "align/align_pose.h"
#include "align/align_refine.h"
#include "align/fiducial_detection.h"
#include "align/prepared_scene.h"
#include "align/refraction_pose.h"
#include "align/setup_similarity.h"
#include "bench_common.h"
#include "calib/fit/extrinsic_fit.h"
#include "render/setup_render.h"
#include "sim/marker_setup.h"
#include "sim/setup_photo.h"
#include "targets/marker_detect.h"

namespace {

using namespace glasspiv;
using bench::median;
using bench::seconds_of;

template <typename Fn>
double median_seconds(int repeats, const Fn& fn) {
  std::vector<double> t;
  for (int i = 0; i < repeats; ++i) t.push_back(seconds_of(fn));
  return median(t);
}

struct Setup {
  std::string name;
  PreparedScene ps;
  std::vector<SceneFiducial> fiducials;
  std::unique_ptr<SceneIndex> index;
  SetupLook look;
  cv::Mat photo8, photo32f;
  RigidTransform truth;
  double photo_seconds = 0;
  std::string marker_label;  // "8 mm (40 px)"

  const CameraModel& model() const { return ps.camera().model; }
};

// The marker frame written into `folder`, prepared, and photographed from the
// scene's own pose (the truth) with `samples` per pixel and axis.
std::unique_ptr<Setup> make_setup(const std::string& name, const std::string& folder, const MarkerSetupOptions& o,
                                  int samples) {
  auto s = std::make_unique<Setup>();
  s->name = name;
  char label[64];
  std::snprintf(label, sizeof label, "%g mm (%.0f px)", o.marker_size_mm,
                o.marker_size_mm * o.focal_px / o.camera_distance_mm);
  s->marker_label = label;
  s->ps = prepare_scene(write_marker_setup(folder, o), "cam");
  s->fiducials = scene_fiducials(s->ps.scene);
  s->index = make_scene_index(s->ps.trace);
  s->look.background_radiance = s->ps.scene.background.radiance;
  s->look.textures = s->ps.textures_by_solid();
  s->truth = *s->ps.camera().camera_from_world;
  const CameraModel& m = s->model();
  s->photo_seconds = seconds_of([&] {
    const std::vector<float> radiance = render_setup(s->ps.trace, *s->index, s->look, m, s->truth, TraceOptions{},
                                                     samples, 0);
    s->photo8 = photo_from_radiance(radiance, m.width_px(), m.height_px(), PhotoLook{});
  });
  s->photo8.convertTo(s->photo32f, CV_32F, 1.0 / 255);
  return s;
}

struct PoseError {
  double position_mm = 0, rotation_deg = 0;
};

PoseError pose_error(const RigidTransform& fitted, const RigidTransform& truth) {
  const Eigen::AngleAxisd d(fitted.rotation * truth.rotation.transpose());
  return {(fitted.inverse().translation_mm - truth.inverse().translation_mm).norm(),
          std::abs(d.angle()) * 180 / M_PI};
}

std::vector<PointObservation> points_of(const std::vector<FiducialCorner>& corners) {
  std::vector<PointObservation> points;
  for (const FiducialCorner& c : corners) points.push_back({c.world_mm, c.pixel_px, c.fiducial, ""});
  return points;
}

// --- 1. Pose from 80 corners: glasspiv against OpenCV.
struct OpenCVPnP {
  std::vector<cv::Point3d> world;
  std::vector<cv::Point2d> pixels;
  cv::Mat k;
  std::vector<double> dist;
  cv::Mat rvec, tvec;

  OpenCVPnP(const CameraModel& m, const std::vector<PointObservation>& points) {
    for (const PointObservation& p : points) {
      world.emplace_back(p.point_world_mm.x(), p.point_world_mm.y(), p.point_world_mm.z());
      pixels.emplace_back(p.pixel_px.x(), p.pixel_px.y());
    }
    k = (cv::Mat_<double>(3, 3) << m.fx_px(), 0, m.cx_px(), 0, m.fy_px(), m.cy_px(), 0, 0, 1);
    dist = m.distortion();
  }
  void solve() {
    cv::solvePnP(world, pixels, k, dist, rvec, tvec, false, cv::SOLVEPNP_SQPNP);
    cv::solvePnPRefineLM(world, pixels, k, dist, rvec, tvec);  // OpenCV's default criteria (20 it., FLT_EPSILON)
  }
  double rms_px() const {
    std::vector<cv::Point2d> projected;
    cv::projectPoints(world, rvec, tvec, k, dist, projected);
    double sum = 0;
    for (std::size_t i = 0; i < pixels.size(); ++i) sum += (projected[i] - pixels[i]).dot(projected[i] - pixels[i]);
    return std::sqrt(sum / static_cast<double>(pixels.size()));
  }
  RigidTransform pose() const {
    return RigidTransform::from_rvec_tvec(Eigen::Vector3d(rvec.at<double>(0), rvec.at<double>(1), rvec.at<double>(2)),
                                          Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2)));
  }
};

void bench_pose(const Setup& s, const std::vector<FiducialCorner>& corners, int repeats) {
  const std::vector<PointObservation> points = points_of(corners);
  ExtrinsicFitOptions bare;
  bare.outlier_k = 0;
  ExtrinsicFit defaults_fit, bare_fit;
  const double t_defaults = median_seconds(repeats, [&] { defaults_fit = fit_camera_pose(s.model(), points); });
  const double t_bare = median_seconds(repeats, [&] { bare_fit = fit_camera_pose(s.model(), points, bare); });
  OpenCVPnP cv_pnp(s.model(), points);
  const double t_cv = median_seconds(repeats, [&] { cv_pnp.solve(); });
  const PoseError e_g = pose_error(defaults_fit.camera_from_world, s.truth);
  const PoseError e_b = pose_error(bare_fit.camera_from_world, s.truth);
  const PoseError e_cv = pose_error(cv_pnp.pose(), s.truth);
  const double cv_rms = cv_pnp.rms_px();
  std::printf("\n1. Pose from 20 markers (%zu corners), %s, median of %d\n\n", points.size(), s.name.c_str(), repeats);
  std::printf("| implementation | ms per pose | vs OpenCV | RMS px | RMS / OpenCV's - 1 | from truth |\n");
  std::printf("|---|---:|---:|---:|---:|---|\n");
  std::printf("| glasspiv fit_camera_pose (defaults: outlier rounds, covariance) | %.3f | %.2fx | %.9f | %+.1e | %.4f mm, %.5f deg |\n",
              1e3 * t_defaults, t_cv / t_defaults, defaults_fit.rms_px, defaults_fit.rms_px / cv_rms - 1,
              e_g.position_mm, e_g.rotation_deg);
  std::printf("| glasspiv fit_camera_pose (outlier_k = 0; covariance) | %.3f | %.2fx | %.9f | %+.1e | %.4f mm, %.5f deg |\n",
              1e3 * t_bare, t_cv / t_bare, bare_fit.rms_px, bare_fit.rms_px / cv_rms - 1, e_b.position_mm,
              e_b.rotation_deg);
  std::printf("| cv::solvePnP SQPNP + cv::solvePnPRefineLM | %.3f | 1.00x | %.9f | 0 | %.4f mm, %.5f deg |\n",
              1e3 * t_cv, cv_rms, e_cv.position_mm, e_cv.rotation_deg);
  std::printf("\nglasspiv defaults: %d Ceres solve(s), %d iterations, Ceres Solve() %.3f ms of the %.3f ms\n",
              defaults_fit.rounds, defaults_fit.iterations, 1e3 * defaults_fit.solve_time_s, 1e3 * t_defaults);
}

// --- 2. The traced pose behind a window.
void bench_traced_pose(const Setup& s, const std::vector<FiducialCorner>& corners, int repeats) {
  std::vector<Eigen::Vector3d> world;
  std::vector<int> solids;
  for (const FiducialCorner& c : corners) {
    world.push_back(c.world_mm);
    solids.push_back(s.ps.info.rectangle_solids.at(
        static_cast<std::size_t>(s.fiducials.at(static_cast<std::size_t>(c.fiducial)).rectangle)));
  }
  AlignedPose pose;
  const double t_total = median_seconds(
      repeats, [&] { pose = align_pose(s.ps.trace, *s.index, s.ps.info.rectangle_solids, s.fiducials, s.model(), corners); });
  const std::vector<PointObservation> points = points_of(corners);
  const double t_pinhole = median_seconds(repeats, [&] { fit_camera_pose(s.model(), points); });

  // The traced refit as align_pose makes it, with a projector that counts:
  // the same calls as traced_point_projector (Newton from the pinhole pixel).
  const TracedProjectionOptions topt;
  long projections = 0, failed = 0, newton = 0;
  double inside_s = 0;
  const PointProjector counting = [&](const RigidTransform& camera_from_world, int i, Eigen::Vector2d* px) {
    const Stopwatch inside;
    ++projections;
    const auto pinhole = s.model().project(camera_from_world.apply(world[static_cast<std::size_t>(i)]));
    if (!pinhole) return ++failed, false;
    const TracedProjection tp = project_through_scene(s.ps.trace, *s.index, s.model(), camera_from_world,
                                                      world[static_cast<std::size_t>(i)],
                                                      solids[static_cast<std::size_t>(i)], *pinhole, topt);
    newton += tp.iterations;
    inside_s += inside.seconds();
    if (!tp.ok()) return ++failed, false;
    *px = tp.pixel_px;
    return true;
  };
  ExtrinsicFitOptions traced;
  traced.initial_camera_from_world = pose.pinhole.camera_from_world;
  traced.projector = counting;
  ExtrinsicFit refit;
  const double t_refit = seconds_of([&] { refit = fit_camera_pose(s.model(), points, traced); });
  const double t_projection = inside_s / static_cast<double>(projections);
  const PoseError e_t = pose_error(pose.fit.camera_from_world, s.truth);
  const PoseError e_p = pose_error(pose.pinhole.camera_from_world, s.truth);
  const double per_projection_newton = static_cast<double>(newton) / static_cast<double>(projections);
  std::printf("\n2. Traced pose behind a 10 mm N-BK7 window, %s (%zu corners), median of %d\n\n", s.name.c_str(),
              corners.size(), repeats);
  std::printf("| step | time | share | figure |\n|---|---:|---:|---|\n");
  std::printf("| align_pose, through_glass (total) | %.1f ms | 100 %% | traced %.4f mm, %.5f deg from truth; RMS %.3f px |\n",
              1e3 * t_total, e_t.position_mm, e_t.rotation_deg, pose.fit.rms_px);
  std::printf("| pinhole fit (the start) | %.2f ms | %.1f %% | %.4f mm, %.5f deg from truth; RMS %.3f px |\n",
              1e3 * t_pinhole, 100 * t_pinhole / t_total, e_p.position_mm, e_p.rotation_deg, pose.pinhole.rms_px);
  std::printf("| traced refit (one counted run) | %.1f ms | %.1f %% | %d Ceres iterations, %d round(s) |\n",
              1e3 * t_refit, 100 * t_refit / t_total, refit.iterations, refit.rounds);
  std::printf("| of it: %ld traced projections x %.2f us | %.1f ms | %.1f %% of the refit | %.2f Newton steps each (%ld in all), %ld failed |\n",
              projections, 1e6 * t_projection, 1e3 * inside_s, 100 * inside_s / t_refit, per_projection_newton,
              newton, failed);
  std::printf("| of it: Ceres, covariance, the rest | %.1f ms | %.1f %% of the refit | |\n", 1e3 * (t_refit - inside_s),
              100 * (t_refit - inside_s) / t_refit);
  std::printf("| glass displacement of the corners | | | up to %.2f px |\n", pose.glass_displacement_px);
}

// --- 3. Marker detection.
void bench_detection(const Setup& s, int repeats) {
  const MarkerDetector detector("DICT_4X4_50");
  MarkerDetection found;
  const double t_g = median_seconds(repeats, [&] { found = detector.detect(s.photo8, "photo"); });
  const cv::Ptr<cv::aruco::Dictionary> dictionary = cv::aruco::getPredefinedDictionary(cv::aruco::DICT_4X4_50);
  const cv::Ptr<cv::aruco::DetectorParameters> parameters = cv::aruco::DetectorParameters::create();
  parameters->cornerRefinementMethod = cv::aruco::CORNER_REFINE_NONE;  // as glasspiv calls it
  std::vector<std::vector<cv::Point2f>> corners;
  std::vector<int> ids;
  const double t_cv =
      median_seconds(repeats, [&] { cv::aruco::detectMarkers(s.photo8, dictionary, corners, ids, parameters); });
  parameters->cornerRefinementMethod = cv::aruco::CORNER_REFINE_SUBPIX;
  std::vector<std::vector<cv::Point2f>> corners_subpix;
  std::vector<int> ids_subpix;
  const double t_cv_subpix = median_seconds(
      repeats, [&] { cv::aruco::detectMarkers(s.photo8, dictionary, corners_subpix, ids_subpix, parameters); });
  std::printf("| %s (%d x %d) | %.1f | %.1f | %.1f | %.2fx | %zu / %zu / %zu |\n", s.name.c_str(), s.model().width_px(),
              s.model().height_px(), 1e3 * t_g, 1e3 * t_cv, 1e3 * t_cv_subpix, t_g / t_cv, found.markers.size(),
              ids.size(), ids_subpix.size());
}

// --- 4. One score evaluation and one render.
struct RenderScore {
  double render_s = 0, compare_s = 0, model_s = 0, features_s = 0, opencv_ncc_s = 0;
  long rays = 0;
};

RenderScore bench_render_score(const Setup& s, int render_repeats, int repeats) {
  RenderScore out;
  const RefineOptions refine;  // the settings the refinement renders with
  std::vector<float> radiance;
  SetupRenderStats stats;
  out.render_s = median_seconds(render_repeats, [&] {
    radiance = render_setup(s.ps.trace, *s.index, s.look, s.model(), s.truth, refine.trace, refine.samples_per_axis, 0,
                            {}, &stats);
  });
  out.rays = stats.camera_rays;
  const cv::Mat render(s.model().height_px(), s.model().width_px(), CV_32F, radiance.data());
  std::unique_ptr<PhotoEdgeModel> model;
  out.model_s = median_seconds(std::max(1, repeats / 3), [&] { model = std::make_unique<PhotoEdgeModel>(s.photo32f); });
  SimilarityWorkspace workspace;
  model->compare(render, workspace);  // buffers allocated once, as the optimiser keeps them
  Similarity sim;
  out.compare_s = median_seconds(repeats, [&] { sim = model->compare(render, workspace); });
  out.features_s = median_seconds(repeats, [&] { blurred_gradient_magnitude(render, refine.blur_px); });
  cv::Mat ncc;
  out.opencv_ncc_s = median_seconds(repeats, [&] { cv::matchTemplate(s.photo32f, render, ncc, cv::TM_CCOEFF_NORMED); });
  std::printf("| %s (%d x %d) | %.1f | %.2f | %.2f | %.2f | %.2f | %.0fx | %.0fx | NCC %.4f, gradient NCC %.4f, chamfer %.3f px |\n",
              s.name.c_str(), s.model().width_px(), s.model().height_px(), 1e3 * out.render_s, 1e3 * out.compare_s,
              1e3 * out.opencv_ncc_s, 1e3 * out.features_s, 1e3 * out.model_s, out.render_s / out.compare_s,
              out.render_s / out.features_s, sim.ncc, sim.gradient_ncc, sim.chamfer_px);
  return out;
}

// --- 5. A whole refinement.
void bench_refine(const Setup& s, int repeats, const RefineOptions& options) {
  const RigidTransform delta = RigidTransform::from_rvec_tvec(
      Eigen::Vector3d(0.6, -0.7, 0.4).normalized() * (M_PI / 180), Eigen::Vector3d(1.2, 0.9, -1.3).normalized() * 2);
  const RigidTransform start = delta * s.truth;
  const PoseError e0 = pose_error(start, s.truth);
  const RefineResult r = refine_alignment(s.ps.trace, s.look, s.model(), start, s.photo32f, {}, options);
  const PoseError e = pose_error(r.camera_from_world, s.truth);
  std::string levels;
  for (int b : options.binning_levels) levels += (levels.empty() ? "" : ", ") + std::to_string(b);
  std::printf("\n5. Refinement, %s (%d x %d), %s markers, levels %s, from %.2f mm / %.3f deg off (one run)\n\n",
              s.name.c_str(), s.model().width_px(), s.model().height_px(), s.marker_label.c_str(), levels.c_str(),
              e0.position_mm, e0.rotation_deg);
  std::printf("| binning | size | LM steps | renders | level s | ms per evaluation | one render alone, ms | "
              "its features alone, ms | gradient NCC before -> after |\n");
  std::printf("|---:|---|---:|---:|---:|---:|---:|---:|---|\n");
  for (const RefineLevel& l : r.levels) {
    const CameraModel m = binned(s.model(), l.binning);
    std::vector<float> radiance;
    const double one = median_seconds(repeats, [&] {
      radiance = render_setup(s.ps.trace, *s.index, s.look, m, r.camera_from_world, options.trace,
                              options.samples_per_axis, 0);
    });
    const cv::Mat render(m.height_px(), m.width_px(), CV_32F, radiance.data());
    const double features = median_seconds(3 * repeats, [&] { blurred_gradient_magnitude(render, options.blur_px); });
    std::printf("| %d | %d x %d | %d | %d | %.2f | %.2f | %.2f | %.3f | %.4f -> %.4f |\n", l.binning, l.width_px,
                l.height_px, l.iterations, l.renders, l.seconds, 1e3 * l.seconds / l.renders, 1e3 * one,
                1e3 * features, l.gradient_ncc_before, l.gradient_ncc_after);
  }
  std::printf("| all | | | %d | %.2f | | | | |\n", r.renders, r.seconds);
  std::printf("\nrefined: %.4f mm, %.5f deg from the truth (start %.2f mm, %.3f deg)\n", e.position_mm, e.rotation_deg,
              e0.position_mm, e0.rotation_deg);
}

}  // namespace

int main(int argc, char** argv) {
  int repeats = 11;
  double refine_marker_mm = 12;
  if (argc > 1) repeats = std::atoi(argv[1]);
  if (argc > 2) refine_marker_mm = std::atof(argv[2]);
  if (repeats <= 0 || !(refine_marker_mm > 0) || argc > 3) {
    std::fprintf(stderr, "usage: align_bench [repeats] [refinement marker size mm]\n");
    return 2;
  }
  const Stopwatch clock;
  utsname host{};
  uname(&host);
  std::printf("align_bench: medians of %d repeats (pose fits: of %d; traced pose and full-size detection: of %d; "
              "full-size renders: of %d; the refinement: one run)\n",
              repeats, 4 * repeats, std::max(3, repeats / 2), std::max(1, repeats / 4));
  std::printf("machine: %s %s, %u hardware threads (renders use all; fits and scores one; detection OpenCV's "
              "default threads); OpenCV %s; compiler %s\n",
              host.sysname, host.machine, std::thread::hardware_concurrency(), CV_VERSION, __VERSION__);

  const std::filesystem::path work = std::filesystem::temp_directory_path() / "glasspiv_align_bench";
  std::filesystem::remove_all(work);
  const MarkerSetupOptions one_mp;  // 1280 x 1024, f 2500 px, 8 mm markers (40 px): the align tests' setup
  MarkerSetupOptions window = one_mp;
  window.window_thickness_mm = 10;
  MarkerSetupOptions full;  // the demo camera's size, the same view
  full.width_px = 2560;
  full.height_px = 2160;
  full.focal_px = one_mp.focal_px * 2160.0 / one_mp.height_px;
  MarkerSetupOptions refine = one_mp;  // 1 MP; larger markers: see bench/RESULTS.md for 8 mm
  refine.width_px = 1024;
  refine.height_px = 1024;
  refine.marker_size_mm = refine_marker_mm;

  const auto open = make_setup("1.3 MP", (work / "open").string(), one_mp, 2);
  const auto glass = make_setup("1.3 MP behind glass", (work / "window").string(), window, 2);
  const auto big = make_setup("full", (work / "full").string(), full, 1);
  const auto refine_setup = make_setup("1 MP", (work / "refine").string(), refine, 2);
  std::printf("photos rendered: 1.3 MP %.1f s, behind glass %.1f s, 1 MP %.1f s (2 x 2 samples per pixel), "
              "full %.1f s (1 sample)\n",
              open->photo_seconds, glass->photo_seconds, refine_setup->photo_seconds, big->photo_seconds);

  const FiducialsInPhoto open_found = detect_fiducials(open->photo8, open->fiducials, "photo");
  const FiducialsInPhoto glass_found = detect_fiducials(glass->photo8, glass->fiducials, "photo");
  std::printf("corners found: %zu in the open, %zu behind glass (of 80)\n", open_found.corners.size(),
              glass_found.corners.size());

  bench_pose(*open, open_found.corners, 4 * repeats);
  bench_traced_pose(*glass, glass_found.corners, std::max(3, repeats / 2));

  std::printf("\n3. Detection of 20 markers (8 mm), median of %d (full: %d)\n\n", repeats, std::max(3, repeats / 2));
  std::printf("| photo | glasspiv MarkerDetector::detect ms | cv::aruco::detectMarkers (no refinement) ms | "
              "detectMarkers + CORNER_REFINE_SUBPIX ms | glasspiv / detectMarkers | markers glasspiv / OpenCV / subpix |\n");
  std::printf("|---|---:|---:|---:|---:|---|\n");
  bench_detection(*open, repeats);
  bench_detection(*big, std::max(3, repeats / 2));

  std::printf("\n4. One setup render (1 sample per pixel, the refinement's settings, all threads) and one score "
              "evaluation (one thread), from the true pose\n\n");
  std::printf("| photo | render ms | compare ms (workspace kept) | OpenCV NCC (matchTemplate) ms | "
              "blurred gradient magnitude ms | PhotoEdgeModel build ms | render / compare | render / gradient | "
              "score of the truth's render |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---|\n");
  bench_render_score(*open, std::max(3, repeats / 2), repeats);
  bench_render_score(*big, std::max(1, repeats / 4), std::max(3, repeats / 2));

  bench_refine(*refine_setup, 3, RefineOptions{});
  std::filesystem::remove_all(work);
  std::printf("\ntotal run time %.0f s\n", clock.seconds());
  return 0;
}
