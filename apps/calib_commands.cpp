// glasspiv calib intrinsics | report (and detect, registered from calib_detect_command.cpp)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>

#include <fmt/format.h>

#include "apps/calibration_report.h"
#include "apps/cli_checks.h"
#include "apps/commands.h"
#include "apps/photo_detection.h"
#include "calib/fit/multi_start.h"
#include "calib/io/camera_file.h"
#include "targets/observations_io.h"
#include "targets/target_yaml.h"
#include "util/input_error.h"
#include "util/progress_bar.h"

namespace glasspiv {
namespace {
namespace fs = std::filesystem;

struct FitCliOptions {
  std::string lens_model = "opencv5";
  bool fix_aspect_ratio = false, zero_tangential = false, fix_principal_point = false;
  double outlier_k = 4.0;
  std::string initial_camera;
  bool single_start = false;  // rich models: the staged fit alone, no multi-start

  IntrinsicFitOptions to_options(const Observations& observations) const {
    IntrinsicFitOptions o;
    o.lens_model = lens_model_from_name(lens_model);
    o.fix_aspect_ratio = fix_aspect_ratio;
    o.zero_tangential = zero_tangential;
    o.fix_principal_point = fix_principal_point;
    o.outlier_k = outlier_k;
    if (!initial_camera.empty()) {
      const Camera c = read_camera(initial_camera);
      if (c.model.width_px() != observations.image_width_px || c.model.height_px() != observations.image_height_px)
        throw InputError(initial_camera, "image size",
                         fmt::format("is {}x{} px but the photos are {}x{} px", c.model.width_px(),
                                     c.model.height_px(), observations.image_width_px, observations.image_height_px));
      o.initial_camera = c.model;
    }
    return o;
  }
};

// A number option's check: finite (CLI11's NonNegativeNumber and PositiveNumber
// let "nan" and "inf" through) and within [min, max]; `zero_too` also admits 0.
CLI::Validator finite_range(double min, double max, bool zero_too = false) {
  const std::string range = fmt::format("{}[{:g}, {:g}]", zero_too ? "0 or " : "", min, max);
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        char* end = nullptr;
        const double value = std::strtod(text.c_str(), &end);
        if (text.empty() || end == text.c_str() || *end != '\0') return "'" + text + "' is not a number";
        if (!std::isfinite(value)) return "'" + text + "' is not a finite number";
        if (zero_too && value == 0) return "";
        if (min > 0 && !(value > 0)) return "'" + text + "' must be above 0 (in " + range + ")";
        if (!(value >= min && value <= max)) return "'" + text + "' is outside " + range;
        return "";
      },
      "NUMBER in " + range);
}

void add_fit_options(CLI::App* app, FitCliOptions& o) {
  app->add_option("--lens-model", o.lens_model, "pinhole, opencv4, opencv5, opencv8, opencv12 or opencv14")
      ->check(CLI::IsMember({"pinhole", "opencv4", "opencv5", "opencv8", "opencv12", "opencv14"}))
      ->capture_default_str();
  app->add_flag("--fix-aspect-ratio", o.fix_aspect_ratio, "Hold fy/fx (1, or the initial camera's)");
  app->add_flag("--zero-tangential", o.zero_tangential, "Hold p1 = p2 = 0");
  app->add_flag("--fix-principal-point", o.fix_principal_point,
                "Hold the principal point at the image centre (or the initial camera's)");
  app->add_option("--outlier-k", o.outlier_k, "Drop corners beyond k sigma and refit (1 to 1000); 0 keeps all")
      ->check(finite_range(1, 1000, true))
      ->capture_default_str();
  app->add_option("--initial-camera", o.initial_camera, "Start from this camera file instead of the closed form")
      ->check(CLI::ExistingFile);
}

// Which projection uncertainty the command prints and the report shows.
struct UncertaintyCliOptions {
  std::string method = "board-frames";
  std::string distance = "1000";  // mm, or "inf"
  UncertaintyMethod to_method() const { return uncertainty_method_from_name(method); }
  double distance_mm() const { return distance == "inf" ? kAtInfinity : std::strtod(distance.c_str(), nullptr); }
};

void add_uncertainty_options(CLI::App* app, UncertaintyCliOptions& o) {
  app->add_option("--uncertainty", o.method,
                  "Projection uncertainty: board-frames (mrcal's: through the intrinsics and the board poses) or "
                  "intrinsics-only (the intrinsics' covariance, the point fixed in the camera frame)")
      ->check(CLI::IsMember({"board-frames", "intrinsics-only"}))
      ->capture_default_str();
  app->add_option("--uncertainty-distance-mm", o.distance,
                  "Distance of the point whose projection uncertainty is shown (mm, 1e-3 to 1e12), or inf")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            if (text == "inf") return "";
            char* end = nullptr;
            const double value = std::strtod(text.c_str(), &end);
            if (text.empty() || end == text.c_str() || *end != '\0' || !std::isfinite(value))
              return "'" + text + "' is not a finite number or inf";
            if (!(value >= 1e-3 && value <= 1e12)) return "'" + text + "' is outside [0.001, 1e+12]";
            return "";
          },
          "NUMBER in [0.001, 1e+12] or inf"))
      ->capture_default_str();
}

bool is_observations_file(const std::string& path) {
  const std::string ext = fs::path(path).extension().string();
  return ext == ".yaml" || ext == ".yml" || ext == ".json";
}

struct FitOutcome {
  IntrinsicFit fit;
  std::optional<CrossValidation> cross_validation;
  std::string cross_validation_note;
  std::string start_note;  // the multi-start's winner (rich models)
};

// The fit, then the cross-validation when both halves have enough views.
// Rich models (opencv8/12/14) by the multi-start (calib/fit/multi_start.h)
// unless `multi_start` is off.
FitOutcome fit_with_diagnostics(const Observations& observations, const IntrinsicFitOptions& options,
                                UncertaintyMethod method, bool multi_start = true) {
  ProgressBar bar("fitting", 2);
  std::string note;
  IntrinsicFit fit = [&] {
    if (!multi_start || !is_rich_lens_model(options.lens_model)) return fit_intrinsics(observations, options);
    MultiStartFit m = fit_intrinsics_multi_start(observations, options);
    int kept = 0, refused = 0;
    for (const FitStart& s : m.starts) {
      kept += s.ok;
      refused += !s.validity.one_to_one;
    }
    note = fmt::format("multi-start: '{}' won (RMS {:.6f} px; the staged fit {:.6f} px; {} of {} starts converged to "
                       "a lens one to one over the corners, {} not one to one; {:.2f} s)",
                       m.starts[m.winner].name, m.fit.rms_px, m.starts[0].rms_px, kept, m.starts.size(), refused,
                       m.total_time_s);
    const LensValidity& v = m.starts[m.winner].validity;
    if (!v.one_to_one)
      note += fmt::format("\nwarning: no start found a lens one to one over the observed corners ({}); a simpler "
                          "lens model (--lens-model opencv5) may describe this lens",
                          v.why);
    return std::move(m.fit);
  }();
  FitOutcome out{std::move(fit), std::nullopt, "", note};
  bar.advance();
  try {
    out.cross_validation = cross_validation(observations, options, 64, method);
  } catch (const InputError& e) {
    out.cross_validation_note = e.problem();
  }
  bar.advance();
  bar.finish();
  return out;
}

// A figure for the user: never "nan" or "inf".
std::string figure(double value, const char* unit = " px") {
  return std::isfinite(value) ? fmt::format("{:.4f}{}", value, unit) : std::string("not defined");
}

void print_fit(const FitOutcome& o, const UncertaintyCliOptions& u) {
  const IntrinsicFit& f = o.fit;
  if (!o.start_note.empty()) std::printf("%s\n", o.start_note.c_str());
  std::printf("fit: RMS %s over %d corners (%d outliers dropped), %d views%s; %.2f s\n", figure(f.rms_px).c_str(),
              f.inlier_count, f.outlier_count, static_cast<int>(f.view_rms_px.size() - f.skipped_views.size()),
              f.skipped_views.empty() ? "" : fmt::format(" ({} skipped)", f.skipped_views.size()).c_str(),
              f.total_time_s);
  const CameraModel& m = f.camera;
  std::printf("     fx %.6g  fy %.6g  cx %.6g  cy %.6g px  distortion [%s]\n", m.fx_px(), m.fy_px(), m.cx_px(),
              m.cy_px(), fmt::format("{:.6g}", fmt::join(m.distortion(), ", ")).c_str());
  if (f.intrinsics_covariance.size() > 0) {
    const double distance_mm = u.distance_mm();
    const UncertaintyFigures figures = uncertainty_figures(f, distance_mm, u.to_method());
    std::string centre = figures.centre_status == UncertaintyStatus::ok
                             ? figure(figures.centre_px)
                             : fmt::format("not defined ({})", to_string(figures.centre_status));
    std::string corners = figures.undefined_corners() < 4 ? figure(figures.worst_corner_px()) : "not defined";
    std::vector<std::string> missing;
    for (int i = 0; i < 4; ++i)
      if (figures.corner_status[i] != UncertaintyStatus::ok) missing.push_back(UncertaintyFigures::kCornerNames[i]);
    if (!missing.empty())
      corners += fmt::format(" (the fitted model has no ray at {} of the 4 image corners: {})", missing.size(),
                             fmt::join(missing, ", "));
    std::printf("     projection uncertainty (1 sigma, %s, %s): centre %s, worst corner %s\n", u.method.c_str(),
                std::isinf(distance_mm) ? "at infinity" : fmt::format("at {:g} mm", distance_mm).c_str(),
                centre.c_str(), corners.c_str());
  }
  if (o.cross_validation)
    std::printf("     cross-validation: even vs odd views differ by %s RMS%s (%s the noise's %s)\n",
                figure(o.cross_validation->difference.rms_px).c_str(),
                o.cross_validation->method == UncertaintyMethod::board_frames ? " after the implied rotation" : "",
                figure(o.cross_validation->ratio, "x").c_str(), figure(o.cross_validation->expected.rms_px).c_str());
  else
    std::printf("     cross-validation: not possible (%s)\n", o.cross_validation_note.c_str());
}

struct IntrinsicsOptions {
  std::vector<std::string> inputs;
  std::string target, output, to, report_dir, observations_out, name, overlay_dir;
  double pixel_pitch_um = 0;
  bool no_report = false;
  FitCliOptions fit;
  UncertaintyCliOptions uncertainty;
};

std::string report_dir_for(const IntrinsicsOptions& o) {
  if (o.no_report) return "";
  return o.report_dir.empty() ? fs::path(o.output).replace_extension("").string() + "_report" : o.report_dir;
}

void run_intrinsics(const IntrinsicsOptions& o) {
  const bool from_observations = o.inputs.size() == 1 && is_observations_file(o.inputs[0]);
  std::vector<std::string> photos;
  if (!from_observations) {
    if (o.target.empty()) throw InputError("", "--target", "is needed to find the target in photos");
    photos = expand_photo_inputs(o.inputs);
  }
  // No output may replace an input: checked before any detection or fit.
  {
    std::vector<std::string> inputs = from_observations ? std::vector<std::string>{o.inputs[0]} : photos;
    inputs.push_back(o.target);
    inputs.push_back(o.fit.initial_camera);
    std::vector<CalibOutput> outputs = {{o.output, "-o"}, {report_dir_for(o), "--report", OutputKind::folder}};
    if (!report_dir_for(o).empty())
      for (const std::string& path : calibration_report_file_paths(report_dir_for(o))) outputs.push_back({path, "--report"});
    if (!from_observations) {
      outputs.push_back({o.observations_out, "--observations-out"});
      outputs.push_back({o.overlay_dir, "--overlay-dir", OutputKind::folder});
      for (const std::string& path : overlay_paths(photos, o.overlay_dir)) outputs.push_back({path, "--overlay-dir"});
    }
    check_calib_outputs(inputs, outputs);
  }
  const CameraFileFormat format = o.to.empty() ? format_for_output_path(o.output) : format_from_name(o.to);
  Observations observations;
  // The file fit errors name: the observations, saved or read, else the photos.
  std::string source = o.inputs[0];
  if (from_observations) {
    observations = read_observations(o.inputs[0]);
  } else {
    const TargetSpec spec = read_target_yaml(o.target);
    require_target_corners(spec, o.target, "an intrinsic calibration");
    PhotoDetectionOptions detection;
    detection.overlay_dir = o.overlay_dir;
    observations = detect_in_photos(photos, spec, o.target, detection);
    if (!o.observations_out.empty()) {
      write_observations(o.observations_out, observations);
      source = o.observations_out;
    } else if (o.inputs.size() > 1) {
      source = fmt::format("{} (and {} more photo inputs)", o.inputs[0], o.inputs.size() - 1);
    }
  }
  const IntrinsicFitOptions options = o.fit.to_options(observations);
  const FitOutcome outcome =
      naming_file(source, [&] {
        return fit_with_diagnostics(observations, options, o.uncertainty.to_method(), !o.fit.single_start);
      });
  print_fit(outcome, o.uncertainty);

  Camera camera{o.name.empty() ? fs::path(o.output).stem().string() : o.name, outcome.fit.camera, std::nullopt,
                std::nullopt};
  if (o.pixel_pitch_um > 0) camera.pixel_pitch_um = o.pixel_pitch_um;
  write_cameras(o.output, {camera}, format);
  std::printf("wrote %s (%s)\n", o.output.c_str(), format_name(format).c_str());
  if (!o.no_report) {
    const std::string dir = report_dir_for(o);
    const CalibrationReportFiles files = naming_file(source, [&] {
      return write_calibration_report(
          dir, {observations, options, outcome.fit, outcome.cross_validation ? &*outcome.cross_validation : nullptr,
                camera.name, camera.pixel_pitch_um, std::nullopt, o.uncertainty.distance_mm(),
                o.uncertainty.to_method()});
    });
    std::printf("wrote %s and %s\n", files.html.c_str(), files.metrics_json.c_str());
  }
}

struct ReportOptions {
  std::string observations, output_dir, name;
  double pixel_pitch_um = 0;
  FitCliOptions fit;
  UncertaintyCliOptions uncertainty;
};

void run_report(const ReportOptions& o) {
  std::vector<CalibOutput> outputs = {{o.output_dir, "-o", OutputKind::folder}};
  for (const std::string& path : calibration_report_file_paths(o.output_dir)) outputs.push_back({path, "-o"});
  check_calib_outputs({o.observations, o.fit.initial_camera}, outputs);
  const Observations observations = read_observations(o.observations);
  const IntrinsicFitOptions options = o.fit.to_options(observations);
  const FitOutcome outcome = naming_file(
      o.observations, [&] { return fit_with_diagnostics(observations, options, o.uncertainty.to_method()); });
  print_fit(outcome, o.uncertainty);
  const CalibrationReportFiles files = naming_file(o.observations, [&] {
    return write_calibration_report(
        o.output_dir,
        {observations, options, outcome.fit, outcome.cross_validation ? &*outcome.cross_validation : nullptr,
         o.name.empty() ? "camera" : o.name,
         o.pixel_pitch_um > 0 ? std::optional<double>(o.pixel_pitch_um) : std::nullopt, std::nullopt,
         o.uncertainty.distance_mm(), o.uncertainty.to_method()});
  });
  std::printf("wrote %s and %s\n", files.html.c_str(), files.metrics_json.c_str());
}

}  // namespace

void register_calib_commands(CLI::App& app) {
  CLI::App* calib = app.add_subcommand("calib", "Calibration sessions: detect targets, fit intrinsics, report");
  calib->require_subcommand(1);
  register_calib_detect_command(*calib);
  register_calib_next_command(*calib);

  auto in = std::make_shared<IntrinsicsOptions>();
  CLI::App* i = calib->add_subcommand(
      "intrinsics", "Fit a camera's intrinsics from photos of a target (or from an observations file)");
  i->add_option("inputs", in->inputs, "Photos, folders of photos, or one observations file (.yaml/.json)")->required();
  i->add_option("--target", in->target, "Target spec YAML (needed for photos)")->check(CLI::ExistingFile);
  i->add_option("-o,--output", in->output, "Camera file to write (.yaml, .cameramodel, .xml; --to opencv)")->required();
  i->add_option("--to", in->to, "Output format: glasspiv, opencv, mrcal or davis")
      ->check(CLI::IsMember({"glasspiv", "opencv", "mrcal", "davis"}));
  i->add_option("--report", in->report_dir, "Report folder (default: OUTPUT without extension + _report)");
  i->add_flag("--no-report", in->no_report, "Do not write the report");
  i->add_option("--observations-out", in->observations_out, "Also save the detected observations (.yaml/.json)");
  i->add_option("--overlay-dir", in->overlay_dir, "Write each photo with its detected corners as PNG here");
  i->add_option("--name", in->name, "Camera name (default: the output file's stem)");
  i->add_flag("--single-start", in->fit.single_start,
              "opencv8/12/14: the staged fit alone (default: several starts, the lowest cost kept; "
              "docs/intrinsic_fit.md)");
  i->add_option("--pixel-pitch-um", in->pixel_pitch_um, "Sensor pixel size in um (for DaVis output; 0.1 to 1000)")
      ->check(finite_range(0.1, 1000));
  add_fit_options(i, in->fit);
  add_uncertainty_options(i, in->uncertainty);
  i->callback([in] { run_intrinsics(*in); });

  auto rep = std::make_shared<ReportOptions>();
  CLI::App* r = calib->add_subcommand("report", "Fit observations and write the HTML report with its pictures");
  r->add_option("observations", rep->observations, "Observations file (.yaml/.json) from calib detect")
      ->required()
      ->check(CLI::ExistingFile);
  r->add_option("-o,--output", rep->output_dir, "Report folder")->required();
  r->add_option("--name", rep->name, "Camera name shown in the report");
  r->add_option("--pixel-pitch-um", rep->pixel_pitch_um, "Sensor pixel size in um (0.1 to 1000)")
      ->check(finite_range(0.1, 1000));
  add_fit_options(r, rep->fit);
  add_uncertainty_options(r, rep->uncertainty);
  r->callback([rep] { run_report(*rep); });
}

}  // namespace glasspiv
