// glasspiv demo: the embedded example session: the example camera in all four
// file formats, a calibration session on synthetic photos, the reactor rendered,
// corrected, aligned on a photograph, and a simulated PIV experiment in it
// evaluated against the truth.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "apps/camera_text.h"
#include "apps/cli_files.h"
#include "apps/commands.h"
#include "apps/demo_alignment.h"
#include "apps/demo_calibration.h"
#include "apps/demo_correction.h"
#include "apps/demo_piv.h"
#include "apps/demo_render.h"
#include "apps/demo_report.h"
#include "apps/plots.h"
#include "calib/io/camera_file.h"
#include "calib/lens_maps.h"
#include "targets/target_spec.h"
#include "targets/target_yaml.h"
#include "util/atomic_file.h"
#include "util/stopwatch.h"

namespace glasspiv::demo_cameras {
const std::vector<std::pair<std::string_view, std::string_view>>& embedded_files();
}
namespace glasspiv::demo_scenes {
const std::vector<std::pair<std::string_view, std::string_view>>& embedded_files();
}
namespace glasspiv::demo_scene_markers {
const std::vector<std::pair<std::string_view, std::string_view>>& embedded_files();
}
namespace glasspiv::demo_targets {
const std::vector<std::pair<std::string_view, std::string_view>>& embedded_files();
}

namespace glasspiv {
namespace {
namespace fs = std::filesystem;

constexpr double kCompareDistanceMm = 1000.0;
constexpr double kStepPx = 16.0;

// Largest pose difference: rotation angle (rad) and translation (mm).
std::pair<double, double> pose_difference(const Camera& a, const Camera& b) {
  if (!a.camera_from_world || !b.camera_from_world) return {0.0, 0.0};
  const RigidTransform d = *a.camera_from_world * b.camera_from_world->inverse();
  return {Eigen::AngleAxisd(d.rotation).angle(), d.translation_mm.norm()};
}

// The reactor's camera, binned as the demo reads it out, calibrated as step 4
// calibrates its camera: the intrinsics the alignment and the PIV step use.
// The board is photographed from where it spans 60 % to 40 % of the image's
// width, as step 4's 300-450 mm do for its camera.
DemoCalibrationSummary calibrate_reactor_camera(const fs::path& out, const Camera& reactor, int binning,
                                                const fs::path& target) {
  std::printf("\n7. The reactor's camera (binned %dx%d) calibrated from 20 synthetic photos of the ChArUco board, as in "
              "step 4:\n", binning, binning);
  const Camera truth{"reactor_truth", binned(reactor.model, binning), std::nullopt,
                     reactor.pixel_pitch_um ? std::optional<double>(*reactor.pixel_pitch_um * binning) : std::nullopt};
  const fs::path folder = out / "reactor_calibration";
  const std::string truth_path = (folder / "reactor_truth.yaml").string();
  write_cameras(truth_path, {truth});
  const Eigen::Vector2d board_mm = board_size_mm(read_target_yaml(target.string()));
  const double span_px = truth.model.fx_px() * board_mm.x() / truth.model.width_px();  // board width x f / image width
  DemoCalibrationViews views;
  views.near_mm = span_px / 0.6;
  views.far_mm = span_px / 0.4;
  const DemoCalibrationSummary c = run_calibration_demo(folder.string(), truth_path, target.string(), views);
  std::printf("   board %.0f-%.0f mm away; fit RMS %.3f px; focal length error %.4f%%; principal point error %.3f px; "
              "fitted vs true camera %.4f px RMS (%.4f px after the implied rotation)\n",
              views.near_mm, views.far_mm, c.rms_px, 100 * c.focal_error_rel, c.principal_point_error_px,
              c.truth_difference_rms_px, c.truth_difference_rotated_rms_px);
  std::printf("   report: %s\n", c.report_html.c_str());
  return c;
}

// 8. Alignment: the model placed on a photograph of the setup.
DemoAlignmentSummary run_alignment_step(const fs::path& out, const fs::path& scenes_dir, int binning,
                                        const Camera& calibrated) {
  std::printf("\n8. Alignment: a photograph of the reactor with 14 ArUco markers on its frame and a ChArUco board behind "
              "the packing (scenes/reactor_markers.yaml), the model with the calibrated camera placed on it:\n");
  const DemoAlignmentSummary al = run_alignment_demo(
      (out / "align").string(), (scenes_dir / "reactor_markers.yaml").string(), binning, &calibrated.model);
  std::printf("   %-40s the photograph (%dx%d, blur, vignette, 0.5 grey levels of noise), rendered in %.1f s\n",
              al.photo_png.c_str(), al.width, al.height, al.photo_seconds);
  std::printf("   found %d of %d markers and %d of the rear board's %d corners%s\n", al.markers_found, al.markers,
              al.board_corners, al.board_corner_ids,
              al.board_corners ? "" : " (seen only through the spheres, in pieces: it aligns by the picture alone)");
  std::printf("   pose from the fiducials, traced through the glass: %.4f mm, %.5f deg from the truth (RMS %.3f px, %d "
              "corners, %d outliers; 1-sigma %.3f mm, %.4f deg)\n",
              al.pose_error.position_mm, al.pose_error.rotation_deg, al.pose_rms_px, al.pose_inliers, al.pose_outliers,
              al.position_sigma_mm.norm(), al.rotation_sigma_deg);
  if (al.glass_displacement_px < 0.01)
    std::printf("   the plain pinhole fit: %.4f mm, %.5f deg, the same: no corner found is seen through glass\n",
                al.pinhole_error.position_mm, al.pinhole_error.rotation_deg);
  else
    std::printf("   the plain pinhole fit: %.4f mm, %.5f deg (RMS %.3f px); the glass displaces corners by up to %.1f px\n",
                al.pinhole_error.position_mm, al.pinhole_error.rotation_deg, al.pinhole_rms_px,
                al.glass_displacement_px);
  std::printf("   refinement on the picture and the corners from a start off by %.2f mm, %.2f deg:\n",
              al.start_error.position_mm, al.start_error.rotation_deg);
  for (const RefineLevel& l : al.levels)
    std::printf("     binning %d more (%dx%d): gradient NCC %.4f -> %.4f, corners %.3f px, in %d steps, %d renders, %.1f s\n",
                l.binning, l.width_px, l.height_px, l.gradient_ncc_before, l.gradient_ncc_after, l.corner_rms_px_after,
                l.iterations, l.renders, l.seconds);
  std::printf("   refined: %.4f mm, %.5f deg from the truth; at %dx%d gradient NCC %.4f -> %.4f (the truth's %.4f), edge "
              "distance %.2f -> %.3f px\n",
              al.refined_error.position_mm, al.refined_error.rotation_deg, al.width, al.height, al.gradient_ncc_before,
              al.gradient_ncc_after, al.gradient_ncc_truth, al.edge_distance_before_px, al.edge_distance_after_px);
  std::printf("   %-40s overlay of the start (photo green, render magenta); also %s\n", al.overlay_before_png.c_str(),
              fs::path(al.overlay_before_edges_png).filename().c_str());
  std::printf("   %-40s overlay after the refinement; also %s\n", al.overlay_after_png.c_str(),
              fs::path(al.overlay_after_edges_png).filename().c_str());
  std::printf("   sensitivity (first order, every %d px, the marker pose's covariance; %.2f s):\n",
              al.sensitivity_step_px, al.sensitivity_seconds);
  std::printf("     %-26s %10s %10s %10s %10s\n", "parameter (1-sigma)", "median px", "95% px", "median mm", "95% mm");
  for (const DemoSensitivityRow& r : al.sensitivity)
    std::printf("     %-26s %10.4g %10.4g %10.4g %10.4g\n",
                (r.sigma > 0 ? fmt::format("{} ({:g})", r.name, r.sigma) : r.name).c_str(), r.median_px, r.p95_px,
                r.median_mm, r.p95_mm);
  std::printf("   %-40s the sheet point each pixel sees: how far it moves, mm\n", al.sensitivity_png.c_str());
  std::printf("   report: %s (%.1f s for this step)\n", al.html.c_str(), al.seconds);
  return al;
}

// 9. PIV: a simulated experiment in the reactor, corrected and evaluated against the truth.
DemoPivSummary run_piv_step(const fs::path& out, const fs::path& scenes_dir, int binning, const Camera& recovered) {
  std::printf("\n9. PIV: a simulated experiment in the reactor (a Lamb-Oseen vortex on the sheet), evaluated on the "
              "reference, corrected and uncorrected pairs against the truth:\n");
  const DemoPivSummary p = run_piv_demo((out / "piv").string(), scenes_dir.string(), binning,
                                        (out / "correct" / "cache").string(), &recovered);
  std::printf("   %dx%d px, %zu tracers (%g ppp, %g px images, %d-bit), largest displacement %.2f px; simulated in "
              "%.1f s\n",
              p.width, p.height, p.tracers, p.density_ppp, p.particle_px, p.bit_depth, p.max_displacement_px,
              p.simulate_seconds);
  for (const std::string& w : p.warnings) std::printf("   warning: %s\n", w.c_str());
  std::printf("   PIV %s px windows, %.0f%% overlap (%dx%d vectors, reference and uncorrected pairs in %.1f s); RMS error against the truth:\n",
              fmt::format("{}", fmt::join(p.window_px, "-")).c_str(), 100 * p.overlap, p.grid_cols, p.grid_rows,
              p.piv_seconds);
  std::printf("     no glass %.4f px (%d vectors), corrected %.4f px (%d), uncorrected %.4f px (%d, on the same "
              "unmasked centres); corrected in windows clear of the mask %.4f px (%d)\n",
              p.no_glass.rms_px, p.no_glass.vectors, p.corrected.rms_px, p.corrected.vectors, p.uncorrected.rms_px,
              p.uncorrected.vectors, p.corrected_inner.rms_px, p.corrected_inner.vectors);
  if (p.own_model)
    std::printf("     corrected with the demo's own camera (calibrated in step 7: %.3f px from the truth's projection, "
                "%.3f px after the implied rotation; aligned in step 8: centre %.3f mm from the truth's) %.4f px (%d)\n",
                p.own_projection_difference_px, p.own_projection_difference_rotated_px, p.own_pose_error_mm,
                p.corrected_own_model.rms_px, p.corrected_own_model.vectors);
  std::printf("   run time against error (%.1f s), ms per frame and RMS error:", p.sweep_seconds);
  for (std::size_t i = 0; i < p.sweep.size(); ++i) {
    const ChainRow& r = p.sweep[i];
    const bool on = on_front(p.sweep_front, i);
    std::printf("%s %s %.2f ms %.4f px%s", i ? ";" : "", r.setting.label.c_str(), r.frame_ms, r.error.rms_px,
                on ? " (Pareto)" : "");
  }
  std::printf("\n   %-40s the Pareto plot\n", p.pareto_png.c_str());
  std::printf("   %.1f%% of the camera's pixels masked by the correction; masked of the sheet grid's fluid region: one "
              "camera %.1f%%, five (binned %dx%d) %.1f%% (their centre camera alone %.1f%%)\n",
              100 * p.masked_pixel_fraction, 100 * p.one_camera_sheet_masked, p.five_binning, p.five_binning,
              100 * p.sheet.all.masked_fraction, 100 * p.sheet.centre.masked_fraction);
  const SheetPivSummary& f = p.sheet;
  std::printf("   five cameras (binned %dx%d) on the sheet grid (%dx%d cells of %.3f mm), PIV against the sheet truth: all "
              "five %.4f px RMS (%d vectors; %.4f px on the centre camera's %d), the centre camera alone %.4f px; "
              "%.1f s\n",
              p.five_binning, p.five_binning, f.grid.cols, f.grid.rows, f.grid.mm_per_px, f.all.least_squares.rms_px,
              f.all.least_squares.vectors, f.all_on_centre_vectors.rms_px, f.all_on_centre_vectors.vectors,
              f.centre.least_squares.rms_px, p.five_seconds);
  std::printf("   %-40s frame A through the glass\n", p.distorted_png.c_str());
  std::printf("   %-40s frame A corrected onto the glass-removed camera grid\n", p.corrected_png.c_str());
  std::printf("   %-40s |measured - true|, corrected; also %s\n", p.error_corrected_png.c_str(),
              fs::path(p.error_uncorrected_png).filename().c_str());
  std::printf("   report: %s, %s (%.1f s for this step)\n", p.html.c_str(),
              fs::path(p.metrics_json).filename().c_str(), p.seconds);
  return p;
}

void run_demo(const std::string& out_dir) {
  const Stopwatch total;
  const fs::path out(out_dir);
  // The demo owns its folder: anything in it that is not a plain file or folder is refused before any work.
  check_output_folder(out_dir, "-o");
  std::printf("glasspiv demo -> %s/\n\n", out_dir.c_str());
  std::printf("Writing the example camera in four formats and the example target...\n");

  // 1. The example camera, as each tool of the field would save it.
  const fs::path cameras_dir = out / "cameras", targets_dir = out / "targets";
  for (const auto& [name, contents] : demo_cameras::embedded_files())
    write_file_atomically((cameras_dir / std::string(name)).string(), contents);
  for (const auto& [name, contents] : demo_targets::embedded_files())
    write_file_atomically((targets_dir / std::string(name)).string(), contents);
  const Camera reference = read_camera((cameras_dir / "example.yaml").string());
  std::fputs(describe_camera(reference).c_str(), stdout);

  std::printf("\n1. The same camera read from four formats (difference to example.yaml over the image):\n");
  std::printf("   %-22s %-9s %14s %14s %12s %12s\n", "file", "format", "RMS px", "max px", "rot rad", "trans mm");
  const std::vector<std::string> files = {"example.yaml", "example_opencv.yaml", "example.cameramodel",
                                          "example_davis.xml"};
  double worst_px = 0;
  for (const std::string& file : files) {
    const std::string path = (cameras_dir / file).string();
    const Camera camera = read_camera(path);
    const GridValues diff = projection_difference(reference.model, camera.model, kCompareDistanceMm, kStepPx);
    const auto [rot, trans] = pose_difference(reference, camera);
    worst_px = std::max(worst_px, diff.max_px);
    std::printf("   %-22s %-9s %14.3g %14.3g %12.3g %12.3g\n", file.c_str(),
                format_name(detect_format(read_file(path), path)).c_str(), diff.rms_px, diff.max_px, rot, trans);
  }

  // 2. Round trips through every format, written by glasspiv.
  std::printf("\n2. Round trips glasspiv -> format -> glasspiv:\n");
  const std::vector<std::pair<CameraFileFormat, std::string>> targets = {
      {CameraFileFormat::Glasspiv, "example.yaml"},
      {CameraFileFormat::OpenCV, "example_opencv.yaml"},
      {CameraFileFormat::Mrcal, "example.cameramodel"},
      {CameraFileFormat::Davis, "example_davis.xml"}};
  for (const auto& [format, file] : targets) {
    const std::string path = (out / "converted" / file).string();
    write_cameras(path, {reference}, format);
    const Camera back = read_camera(path);
    const bool exact = back.model == reference.model;
    const GridValues diff = projection_difference(reference.model, back.model, kCompareDistanceMm, kStepPx);
    std::printf("   %-9s intrinsics %s, projection max %.3g px\n", format_name(format).c_str(),
                exact ? "bit-identical" : "differ", diff.max_px);
  }

  // 3. Pictures.
  std::printf("\n3. Pictures:\n");
  const std::string field_png = (out / "distortion_example.png").string();
  const GridValues field = distortion_field(reference.model, 64.0);
  write_vector_field_png(field, reference.model.width_px(), reference.model.height_px(),
                         {"distortion of the example camera (distorted - pinhole pixel)", "|distortion| px"},
                         field_png);
  std::printf("   %-40s distortion field, max %.3g px\n", field_png.c_str(), field.max_px);

  const Camera wide = read_camera((cameras_dir / "wide_opencv8.yaml").string());
  const std::string wide_png = (out / "distortion_wide_opencv8.png").string();
  const GridValues wide_field = distortion_field(wide.model, 48.0);
  write_vector_field_png(wide_field, wide.model.width_px(), wide.model.height_px(),
                         {"distortion of a wide lens (OpenCV8 model)", "|distortion| px"}, wide_png);
  std::printf("   %-40s distortion field, max %.3g px\n", wide_png.c_str(), wide_field.max_px);

  const CameraModel pinhole(reference.model.width_px(), reference.model.height_px(), reference.model.fx_px(),
                            reference.model.fy_px(), reference.model.cx_px(), reference.model.cy_px());
  const GridValues ignore = projection_difference(reference.model, pinhole, kCompareDistanceMm, kStepPx);
  const std::string ignore_png = (out / "compare_without_distortion.png").string();
  write_magnitude_png(ignore, reference.model.width_px(), reference.model.height_px(),
                      {"error made by ignoring the distortion of the example lens", "|difference| px"}, ignore_png);
  std::printf("   %-40s ignoring distortion: RMS %.3g px, max %.3g px\n", ignore_png.c_str(), ignore.rms_px,
              ignore.max_px);

  const Camera davis = read_camera((cameras_dir / "example_davis.xml").string());
  const GridValues agree = projection_difference(reference.model, davis.model, kCompareDistanceMm, kStepPx);
  const std::string agree_png = (out / "compare_glasspiv_davis.png").string();
  write_magnitude_png(agree, reference.model.width_px(), reference.model.height_px(),
                      {"glasspiv YAML vs DaVis XML of the same camera", "|difference| px"}, agree_png);
  std::printf("   %-40s glasspiv vs DaVis: max %.3g px\n", agree_png.c_str(), agree.max_px);

  std::printf("\nAll four formats agree to %.2g px.\n", worst_px);

  // 4. A calibration session on synthetic photos of a ChArUco board.
  std::printf("\n4. Calibration session: 20 synthetic photos of a ChArUco board, then detect, fit, report:\n");
  const std::string truth_path = (cameras_dir / "session_truth.yaml").string();
  const DemoCalibrationSummary session =
      run_calibration_demo((out / "session").string(), truth_path, (targets_dir / "charuco_11x8_15mm.yaml").string());
  std::printf("   fit RMS %.3f px; focal length error %.4f%%; principal point error %.3f px\n", session.rms_px,
              100 * session.focal_error_rel, session.principal_point_error_px);
  std::printf("   fitted vs true camera over the image: %.4f px RMS (%.4f px after the implied rotation)\n",
              session.truth_difference_rms_px, session.truth_difference_rotated_rms_px);
  std::printf("   report: %s\n", session.report_html.c_str());

  // 5. The reference-like reactor, rendered.
  constexpr int kBinning = 4;
  std::printf("\n5. The packed-bed reactor (bcc, 40 mm N-BK7 spheres, the sheet behind two layers), its camera "
              "binned %dx%d:\n", kBinning, kBinning);
  const fs::path scenes_dir = out / "scenes";
  for (const auto& [name, contents] : demo_scenes::embedded_files())
    write_file_atomically((scenes_dir / std::string(name)).string(), contents);
  for (const auto& [name, contents] : demo_scene_markers::embedded_files())
    write_file_atomically((scenes_dir / "markers" / std::string(name)).string(), contents);
  const DemoRenderSummary render =
      run_render_demo((out / "render").string(), (scenes_dir / "reactor.yaml").string(), kBinning);
  std::printf("   transport map %dx%d %s in %.2f s (%.2f sheet crossings per pixel; %.0f%% of the rays met no "
              "glass and took the closed form), saved to %s\n",
              render.width, render.height, render.map_from_earlier_run ? "reused from an earlier run" : "traced",
              render.trace_seconds, render.crossings_per_pixel,
              100 * render.closed_form_fraction, render.map_file.c_str());
  std::printf("   reloaded from the cache in %.3f s; each image then renders in %.3f s\n", render.reload_seconds,
              render.render_seconds);
  std::printf("   %-40s 5 mm checkerboard on the sheet: magnified, inverted behind the spheres\n",
              render.checkerboard_png.c_str());
  std::printf("   %-40s a particle field, 16-bit, as a PIV camera records it\n", render.particles_tif.c_str());
  std::printf("   %-40s the setup itself (lit backdrop), to hold against a photograph (%.2f s)\n",
              render.setup_png.c_str(), render.setup_seconds);

  // 6. Correction: the distorted frame made undistorted, one camera and five.
  std::printf("\n6. Correction: a particle field on the sheet, rendered through the glass, then corrected:\n");
  const DemoCorrectionSummary corr =
      run_correction_demo((out / "correct").string(), scenes_dir.string(), kBinning);
  std::printf("   one camera (%dx%d): operator ready in %.2f s; a frame corrected in %.1f ms; %.1f%% of the sheet's fluid "
              "region reconstructable\n",
              corr.width, corr.height, corr.operator_seconds, corr.correct_ms, 100 * corr.one_valid_fraction);
  std::printf("   corrected vs the same camera without glass, on the valid pixels: NCC %.3f (back-projection), %.3f "
              "(least squares)\n", corr.one_ncc, corr.one_lsq_ncc);
  std::printf("   %-40s distorted | corrected | without glass | mask\n", corr.side_by_side_png.c_str());
  std::printf("   five cameras: %.1f%% of the fluid region reconstructable (the centre camera alone %.1f%%; %.1f%% of what "
              "they see directly)\n",
              100 * corr.five_valid_fraction, 100 * corr.centre_valid_fraction, 100 * corr.five_seen_fraction);
  std::printf("   error against the true field: accumulation RMS %.4f, least squares RMS %.4f (%d iterations): "
              "the ghosts of reflections removed\n", corr.accumulation_rms, corr.lsq_rms, corr.lsq_iterations);
  std::printf("   %-40s truth | accumulation | least squares | mask (sheet grid)\n", corr.five_png.c_str());


  // 7. The reactor's camera calibrated; 8. placed on a photograph of the setup.
  const DemoCalibrationSummary reactor_calibration = calibrate_reactor_camera(
      out, read_camera((cameras_dir / "example.yaml").string()), kBinning, targets_dir / "charuco_11x8_15mm.yaml");
  const DemoAlignmentSummary al = run_alignment_step(out, scenes_dir, kBinning, *reactor_calibration.fitted);

  // 9. PIV: a simulated experiment, corrected with the true and the recovered camera, evaluated against the truth.
  const DemoPivSummary piv = run_piv_step(out, scenes_dir, kBinning, *al.recovered);

  // One page and one metrics file for the whole session.
  DemoSession session_pages;
  session_pages.formats_worst_px = worst_px;
  session_pages.calibration = &session;
  session_pages.render = &render;
  session_pages.correction = &corr;
  session_pages.reactor_calibration = &reactor_calibration;
  session_pages.alignment = &al;
  session_pages.piv = &piv;
  session_pages.binning = kBinning;
  session_pages.seconds = total.seconds();
  const DemoReportFiles report = write_demo_report(out_dir, session_pages);
  std::printf("\nThe whole session on one page: %s (every figure in %s; %.0f s in all)\n", report.html.c_str(),
              report.metrics_json.c_str(), session_pages.seconds);

  std::printf("\nNext: `glasspiv camera --help`, `glasspiv calib --help`, `glasspiv target --help`, "
              "`glasspiv render --help`, `glasspiv correct --help`, `glasspiv coverage --help`, `glasspiv align --help`, "
              "`glasspiv simulate --help`, `glasspiv piv --help`.\n");
}

}  // namespace

void register_demo_command(CLI::App& app) {
  auto out_dir = std::make_shared<std::string>("glasspiv-demo");
  CLI::App* demo = app.add_subcommand("demo", "Run the embedded example session and write its results");
  demo->add_option("-o,--output", *out_dir, "Output folder")->capture_default_str();
  demo->callback([out_dir] { run_demo(*out_dir); });
}

}  // namespace glasspiv
