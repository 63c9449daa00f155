#include "apps/demo_report.h"

#include <algorithm>

#include <filesystem>
#include <stdexcept>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "apps/html_text.h"
#include "util/json_document.h"
#include "util/atomic_file.h"

namespace glasspiv {
namespace {
namespace fs = std::filesystem;

// A step's file as the page refers to it: relative to the demo's folder.
std::string relative(const fs::path& out, const std::string& path) {
  return fs::path(path).lexically_relative(out).generic_string();
}

// A figure with its picture, if the step wrote it.
std::string figure(const fs::path& out, const std::string& path, const std::string& caption) {
  if (path.empty() || !fs::exists(path)) return "";
  const std::string src = html_escape(relative(out, path));
  return fmt::format("<figure><a href=\"{0}\"><img src=\"{0}\" alt=\"\"></a><figcaption>{1}</figcaption></figure>\n",
                     src, caption);
}

std::string link(const fs::path& out, const std::string& path, const std::string& text) {
  return fmt::format("<a href=\"{}\">{}</a>", html_escape(relative(out, path)), text);
}

std::string report_picture(const DemoCalibrationSummary& c, const char* name) {
  return (fs::path(c.report_html).parent_path() / name).string();
}

nlohmann::json calibration_json(const DemoCalibrationSummary& c) {
  return {{"rms_px", c.rms_px},
          {"focal_error_relative", c.focal_error_rel},
          {"principal_point_error_px", c.principal_point_error_px},
          {"truth_difference_rms_px", c.truth_difference_rms_px},
          {"truth_difference_after_implied_rotation_rms_px", c.truth_difference_rotated_rms_px}};
}

nlohmann::json pose_json(const DemoPoseError& e) { return {{"position_mm", e.position_mm}, {"rotation_deg", e.rotation_deg}}; }

}  // namespace

DemoReportFiles write_demo_report(const std::string& out_dir, const DemoSession& d) {
  if (!d.calibration || !d.render || !d.correction || !d.reactor_calibration || !d.alignment || !d.piv)
    throw std::invalid_argument("write_demo_report: every step's summary is needed");
  const fs::path out(out_dir);
  const DemoCalibrationSummary& c4 = *d.calibration;
  const DemoRenderSummary& r5 = *d.render;
  const DemoCorrectionSummary& c6 = *d.correction;
  const DemoCalibrationSummary& c7 = *d.reactor_calibration;
  const DemoAlignmentSummary& a8 = *d.alignment;
  const DemoPivSummary& p9 = *d.piv;

  std::string page;
  page += "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>glasspiv demo</title>\n";
  page += "<style>body{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}"
          "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}"
          "th{background:#f4f4f4}td:first-child,th:first-child{text-align:left}img{max-width:100%;border:1px solid #ddd}"
          "figure{margin:0.5em 0}.row{display:flex;gap:1em}.row figure{flex:1}</style>\n";
  page += "</head><body>\n<h1>glasspiv demo: a calibration-to-PIV session in the computer</h1>\n";
  page += fmt::format(
      "<p>A camera calibrated from synthetic target photos, the packed-bed reactor rendered and its images "
      "corrected, the camera placed on a photograph of the setup, and a simulated PIV experiment evaluated through "
      "the glass, every figure against the exact truth the simulation knows. The reactor's camera is read out "
      "binned {0}&times;{0}. The whole session ran in {1:.0f} s; every figure is in "
      "<a href=\"metrics.json\">metrics.json</a>.</p>\n",
      d.binning, d.seconds);

  page += "<h2>Summary</h2>\n<table><tr><th>step</th><th>figure</th><th>value</th><th>page</th></tr>\n";
  const auto row = [&](const std::string& step, const std::string& what, const std::string& value,
                       const std::string& where) {
    page += fmt::format("<tr><td>{}</td><td style=\"text-align:left\">{}</td><td>{}</td><td>{}</td></tr>\n", step,
                        what, value, where);
  };
  row("1-2 camera formats", "largest projection difference between the four formats", fmt::format("{:.2g} px", d.formats_worst_px), "");
  const std::string c4_page = link(out, c4.report_html, "report");
  row("4 calibration", "fit RMS", fmt::format("{:.3f} px", c4.rms_px), c4_page);
  row("", "focal length error", fmt::format("{:.4f} %", 100 * c4.focal_error_rel), "");
  row("", "fitted vs true camera, after the implied rotation", fmt::format("{:.4f} px RMS", c4.truth_difference_rotated_rms_px), "");
  row("5 render", "transport map traced", fmt::format("{:.2f} s ({}&times;{} px)", r5.trace_seconds, r5.width, r5.height), "");
  row("", "one image from the cached map", fmt::format("{:.3f} s", r5.render_seconds), "");
  row("6 correction", "sheet's fluid region reconstructable: one camera / five",
      fmt::format("{:.1f} % / {:.1f} %", 100 * c6.one_valid_fraction, 100 * c6.five_valid_fraction), "");
  row("", "corrected vs glass-free NCC (least squares)", fmt::format("{:.3f}", c6.one_lsq_ncc), "");
  row("", "five cameras: error against the true field, accumulation / least squares",
      fmt::format("{:.4f} / {:.4f}", c6.accumulation_rms, c6.lsq_rms), "");
  row("7 reactor camera", "fitted vs true camera, after the implied rotation",
      fmt::format("{:.4f} px RMS", c7.truth_difference_rotated_rms_px), link(out, c7.report_html, "report"));
  const std::string a8_page = link(out, a8.html, "alignment");
  row("8 alignment", "pose from the markers (calibrated intrinsics)",
      fmt::format("{:.3f} mm, {:.4f}&deg;", a8.pose_error.position_mm, a8.pose_error.rotation_deg), a8_page);
  row("", "refined on the picture from 2 mm, 1&deg; off",
      fmt::format("{:.3f} mm, {:.4f}&deg;", a8.refined_error.position_mm, a8.refined_error.rotation_deg), "");
  const std::string p9_page = link(out, p9.html, "PIV");
  row("9 PIV", "RMS error, no glass", fmt::format("{:.4f} px", p9.no_glass.rms_px), p9_page);
  row("", "RMS error, corrected (true model)", fmt::format("{:.4f} px", p9.corrected.rms_px), "");
  if (p9.own_model)
    row("", "RMS error, corrected with the demo's own camera (steps 7-8)",
        fmt::format("{:.4f} px", p9.corrected_own_model.rms_px), "");
  row("", "RMS error, uncorrected", fmt::format("{:.3f} px", p9.uncorrected.rms_px), "");
  row("", "masked share of the sheet's fluid region: one camera / five",
      fmt::format("{:.1f} % / {:.1f} %", 100 * p9.one_camera_sheet_masked, 100 * p9.sheet.all.masked_fraction), "");
  {
    std::size_t def = 0;
    while (def < p9.sweep.size() && !p9.sweep[def].setting.is_default) ++def;
    const bool on = on_front(p9.sweep_front, def);
    row("", "correction defaults against one knob changed",
        fmt::format("{} of {} settings on the Pareto front, the default {}", p9.sweep_front.size(), p9.sweep.size(),
                    def == p9.sweep.size() ? "not run" : on ? "among them" : "not"),
        "");
  }
  row("", "on the sheet grid: RMS error, five cameras / the centre camera alone",
      fmt::format("{:.4f} px / {:.4f} px", p9.sheet.all.least_squares.rms_px, p9.sheet.centre.least_squares.rms_px), "");
  page += "</table>\n";

  page += "<h2>Calibration (step 4)</h2>\n<div class=\"row\">";
  page += figure(out, report_picture(c4, "residuals.png"), "Mean residual per image cell.");
  page += figure(out, report_picture(c4, "uncertainty.png"), "Projection uncertainty (1&sigma;).");
  page += "</div>\n";
  page += "<h2>The reactor rendered (step 5) and corrected (step 6)</h2>\n<div class=\"row\">";
  page += figure(out, r5.checkerboard_png, "A 5 mm checkerboard on the sheet, seen through the spheres.");
  page += figure(out, r5.setup_png, "The setup against a lit backdrop.");
  page += "</div>\n";
  page += figure(out, c6.side_by_side_png, "Distorted | corrected | the same camera without glass | mask.");
  page += figure(out, c6.five_png, "Five cameras on the sheet grid: truth | accumulation | least squares | mask.");
  page += "<h2>Alignment on a photograph (step 8)</h2>\n<div class=\"row\">";
  page += figure(out, a8.overlay_before_png, "Before: the start 2 mm and 1&deg; off (photo green, render magenta).");
  page += figure(out, a8.overlay_after_png, "After the refinement.");
  page += "</div>\n";
  page += "<h2>PIV through the glass (step 9)</h2>\n<div class=\"row\">";
  page += figure(out, p9.distorted_png, "Frame A through the glass.");
  page += figure(out, p9.corrected_png, "Frame A corrected (masked pixels dark).");
  page += "</div>\n<div class=\"row\">";
  page += figure(out, p9.true_field_png, "The true displacement.");
  page += figure(out, p9.measured_field_png, "Measured on the corrected frames.");
  page += "</div>\n<div class=\"row\">";
  page += figure(out, p9.error_corrected_png, "|measured &minus; true|, corrected frames.");
  page += figure(out, p9.error_uncorrected_png, "|measured &minus; true|, uncorrected frames.");
  page += "</div>\n<h3>Run time against error of the correction</h3>\n<div class=\"row\">";
  page += figure(out, p9.pareto_png,
                 "PIV error against correction time per frame, glasspiv correct's defaults and one knob changed per "
                 "setting (red: the Pareto front; ringed: the default; the table on the PIV page).");
  page += "</div>\n<h3>One camera against five, on the sheet grid</h3>\n<div class=\"row\">";
  page += figure(out, p9.sheet.centre.frame_a_png, "Frame A from the centre camera alone (masked cells dark).");
  page += figure(out, p9.sheet.all.frame_a_png, "Frame A from all five cameras.");
  page += "</div>\n<div class=\"row\">";
  page += figure(out, p9.sheet.centre.error_png, "|measured &minus; true|, the centre camera alone.");
  page += figure(out, p9.sheet.all.error_png, "|measured &minus; true|, five cameras.");
  page += "</div>\n</body></html>\n";

  nlohmann::json j = {
      {"binning", d.binning},
      {"seconds", d.seconds},
      {"formats_worst_difference_px", d.formats_worst_px},
      {"calibration", calibration_json(c4)},
      {"render",
       {{"width_px", r5.width}, {"height_px", r5.height}, {"trace_seconds", r5.trace_seconds},
        {"reload_seconds", r5.reload_seconds}, {"render_seconds", r5.render_seconds},
        {"crossings_per_pixel", r5.crossings_per_pixel}, {"closed_form_fraction", r5.closed_form_fraction}}},
      {"correction",
       {{"one_camera_valid_fraction", c6.one_valid_fraction}, {"one_camera_ncc", c6.one_ncc},
        {"one_camera_lsq_ncc", c6.one_lsq_ncc}, {"five_cameras_valid_fraction", c6.five_valid_fraction},
        {"centre_camera_valid_fraction", c6.centre_valid_fraction}, {"accumulation_rms", c6.accumulation_rms},
        {"lsq_rms", c6.lsq_rms}, {"correct_ms", c6.correct_ms}}},
      {"reactor_calibration", calibration_json(c7)},
      {"alignment",
       {{"calibrated_intrinsics", a8.calibrated_intrinsics}, {"pose_error", pose_json(a8.pose_error)},
        {"pinhole_error", pose_json(a8.pinhole_error)}, {"start_error", pose_json(a8.start_error)},
        {"refined_error", pose_json(a8.refined_error)}, {"seconds", a8.seconds}}},
      {"piv",
       {{"no_glass", score_json(p9.no_glass)}, {"corrected", score_json(p9.corrected)},
        {"uncorrected", score_json(p9.uncorrected)},
        {"corrected_own_model", p9.own_model ? score_json(p9.corrected_own_model) : nlohmann::json()},
        {"one_camera_sheet_masked", p9.one_camera_sheet_masked}, {"five_cameras_sheet_masked", p9.sheet.all.masked_fraction},
        {"sheet_grid_rms_px",
         {{"five_cameras", p9.sheet.all.least_squares.rms_px}, {"centre_alone", p9.sheet.centre.least_squares.rms_px}}},
        {"seconds", p9.seconds}}},
  };
  DemoReportFiles files;
  files.html = (out / "index.html").string();
  files.metrics_json = (out / "metrics.json").string();
  write_file_atomically(files.metrics_json, json_text(j));
  write_file_atomically(files.html, page);
  return files;
}

}  // namespace glasspiv
