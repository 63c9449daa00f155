#include "apps/calibration_report.h"

#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>

#include <fmt/format.h>
#include <Eigen/Geometry>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "apps/camera_text.h"
#include "apps/html_text.h"
#include "apps/plots.h"
#include "calib/lens_maps.h"
#include "util/json_document.h"
#include "util/atomic_file.h"

namespace glasspiv {
namespace {
namespace fs = std::filesystem;

GridValues coverage_values(const Coverage& c) {
  GridValues g;
  g.grid = c.grid;
  for (int n : c.count) g.vector_px.emplace_back(static_cast<double>(n), 0.0);
  g.summarize();
  return g;
}

// A figure for the page: never "nan" or "inf".
std::string px(double value) { return std::isfinite(value) ? fmt::format("{:.4f} px", value) : "no figure"; }

nlohmann::json number_or_null(double value) { return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr); }

std::string distance_text(double distance_mm) {
  return std::isinf(distance_mm) ? std::string("at infinity") : fmt::format("at {:g} mm", distance_mm);
}

// "centre 0.1353 px; corners 0.31 px (top-left), ..., no figure at the
// bottom-right (the fitted model has no ray through this pixel)".
std::string uncertainty_text(const UncertaintyFigures& u) {
  std::string out = u.centre_status == UncertaintyStatus::ok
                        ? fmt::format("centre {:.4f} px", u.centre_px)
                        : fmt::format("no figure at the centre ({})", to_string(u.centre_status));
  std::vector<std::string> corners, missing;
  for (int i = 0; i < 4; ++i) {
    if (u.corner_status[i] == UncertaintyStatus::ok)
      corners.push_back(fmt::format("{:.4f} px ({})", u.corners_px[i], UncertaintyFigures::kCornerNames[i]));
    else
      missing.push_back(fmt::format("{} ({})", UncertaintyFigures::kCornerNames[i], to_string(u.corner_status[i])));
  }
  if (!corners.empty()) out += "; corners " + fmt::format("{}", fmt::join(corners, ", "));
  if (!missing.empty())
    out += fmt::format("; no figure at {} of the 4 corners: {}", missing.size(), fmt::join(missing, ", "));
  return out;
}

// "12 of 1813 samples have no figure (grey): ..." or "".
std::string missing_samples_text(const GridValues& g, const char* why) {
  const int missing = g.grid.size() - g.valid_count;
  return missing > 0 ? fmt::format(" {} of {} samples have no figure (grey): {}.", missing, g.grid.size(), why) : "";
}

double parameter_sigma(const IntrinsicFit& fit, int index) {
  for (std::size_t k = 0; k < fit.free_intrinsics.size(); ++k)
    if (fit.free_intrinsics[k] == index && fit.intrinsics_covariance.rows() > static_cast<int>(k))
      return std::sqrt(fit.intrinsics_covariance(k, k));
  return std::nan("");
}

}  // namespace

std::vector<std::string> calibration_report_file_paths(const std::string& folder) {
  std::vector<std::string> paths;
  for (const char* name : {"report.html", "metrics.json", "residuals.png", "coverage.png", "uncertainty.png",
                           "distortion.png", "cross_validation.png", "truth_difference.png"})
    paths.push_back((fs::path(folder) / name).string());
  return paths;
}

CalibrationReportFiles write_calibration_report(const std::string& folder, const CalibrationReportInputs& in) {
  const fs::path dir(folder);
  const CameraModel& model = in.fit.camera;
  const int w = model.width_px(), h = model.height_px();
  const double step = std::max(w, h) / 48.0;

  struct Picture {
    std::string file, caption;
  };
  std::vector<Picture> pictures;
  const auto add = [&](const std::string& file, const std::string& caption) {
    pictures.push_back({file, caption});
    return (dir / file).string();
  };

  const GridValues residuals = residual_field(in.fit, in.observations, step);
  write_vector_field_png(residuals, w, h, {"mean residual per cell (projected - observed)", "|residual| px"},
                         add("residuals.png", "Mean residual per cell. A systematic pattern (swirls, a radial trend) "
                                              "means the lens model cannot follow the lens."));
  // Cells of about a twelfth of the sensor: fine enough to show an empty corner
  // of the image, coarse enough that a covered region reads as one.
  const Coverage cover = coverage(in.observations, w, h, std::max(w, h) / 12.0);
  write_magnitude_png(coverage_values(cover), w, h,
                      {fmt::format("observed corners per cell ({:.0f}% of cells covered)", 100 * cover.covered_fraction),
                       "corners", "corners", true},
                      add("coverage.png", "Corners per cell. Grey or dark regions are extrapolated by the model, "
                                          "not measured: photograph the board there too."));
  std::optional<UncertaintyFigures> uncertainty;
  std::optional<GridValues> sigma;
  const std::string uncertainty_kind =
      fmt::format("{}, {}", uncertainty_method_name(in.uncertainty_method), distance_text(in.uncertainty_distance_mm));
  if (in.fit.intrinsics_covariance.size() > 0) {
    sigma = projection_uncertainty(in.fit, in.uncertainty_distance_mm, step, in.uncertainty_method);
    uncertainty = uncertainty_figures(in.fit, in.uncertainty_distance_mm, in.uncertainty_method);
    const std::string how =
        in.uncertainty_method == UncertaintyMethod::board_frames
            ? "propagated through the intrinsics and the board poses to a point defined through the board frames "
              "(mrcal's method)"
            : "from the covariance of the intrinsics alone, the point held fixed in the camera frame";
    write_magnitude_png(*sigma, w, h,
                        {fmt::format("projection uncertainty (1 sigma, worst direction; {})", uncertainty_kind),
                         "sigma px"},
                        add("uncertainty.png",
                            "How far a projected point can move given the observation noise (1 sigma, worst "
                            "direction), " +
                                how + "." +
                                missing_samples_text(*sigma, "the fitted model has no ray through those pixels")));
  }
  const GridValues distortion = distortion_field(model, step);
  write_vector_field_png(distortion, w, h, {"distortion of the fitted model (distorted - pinhole pixel)", "|distortion| px"},
                         add("distortion.png", "The fitted lens distortion."));
  if (in.cross_validation) {
    const bool rotated = in.cross_validation->method == UncertaintyMethod::board_frames;
    write_magnitude_png(in.cross_validation->difference, w, h,
                        {std::string("cross-validation: even views vs odd views") +
                             (rotated ? " after the implied rotation" : ""),
                         "|difference| px"},
                        add("cross_validation.png",
                            std::string("Projection difference of the models fitted to the even- and the "
                                        "odd-numbered views") +
                                (rotated ? ", after the camera rotation implied between them" : "") +
                                ". Much larger than expected from the noise means the lens model or the data "
                                "are not good enough." +
                                missing_samples_text(in.cross_validation->difference,
                                                     "one of the two models has no ray through those pixels")));
  }
  std::optional<GridValues> truth_diff, truth_diff_rotated;
  if (in.truth) {
    truth_diff = projection_difference(in.truth->model, model, in.uncertainty_distance_mm, step);
    // A principal-point error is nearly the same as a small camera rotation; as
    // mrcal does, also compare after the best-fitting rotation between the two.
    truth_diff_rotated = projection_difference(in.truth->model, model, in.uncertainty_distance_mm, step,
                                               implied_rotation(in.truth->model, model, step));
    write_magnitude_png(*truth_diff, w, h, {"fitted model vs the true camera", "|difference| px"},
                        add("truth_difference.png", "Projection difference between the fitted and the true camera "
                                                    "(synthetic session)."));
  }

  // Metrics JSON: everything a script would want.
  nlohmann::json j;
  j["camera"] = {{"name", in.camera_name},
                 {"lens_model", lens_model_name(model.lens_model())},
                 {"image_size_px", {w, h}},
                 {"intrinsics", std::vector<double>(model.intrinsics().begin(),
                                                    model.intrinsics().begin() + 4 + model.distortion_count())}};
  j["fit"] = {{"rms_px", in.fit.rms_px},
              {"sigma_px", in.fit.sigma_px},
              {"inliers", in.fit.inlier_count},
              {"outliers", in.fit.outlier_count},
              {"rounds", in.fit.rounds},
              {"iterations", in.fit.iterations},
              {"solver_time_s", in.fit.solver_time_s},
              {"total_time_s", in.fit.total_time_s},
              {"termination", in.fit.termination}};
  nlohmann::json params = nlohmann::json::array();
  for (int i = 0; i < 4 + model.distortion_count(); ++i) {
    const double sigma = parameter_sigma(in.fit, i);
    params.push_back({{"name", intrinsic_name(i)},
                      {"value", model.intrinsics()[i]},
                      {"sigma", std::isfinite(sigma) ? nlohmann::json(sigma) : nlohmann::json(nullptr)}});
  }
  j["parameters"] = params;
  if (uncertainty) {
    nlohmann::json corners = nlohmann::json::object(), undefined = nlohmann::json::array();
    if (uncertainty->centre_status != UncertaintyStatus::ok)
      undefined.push_back({{"pixel", "centre"}, {"reason", to_string(uncertainty->centre_status)}});
    for (int i = 0; i < 4; ++i) {
      corners[UncertaintyFigures::kCornerNames[i]] = number_or_null(uncertainty->corners_px[i]);
      if (uncertainty->corner_status[i] != UncertaintyStatus::ok)
        undefined.push_back(
            {{"pixel", UncertaintyFigures::kCornerNames[i]}, {"reason", to_string(uncertainty->corner_status[i])}});
    }
    j["projection_uncertainty_px"] = {
        {"method", uncertainty_method_name(in.uncertainty_method)},
        {"distance_mm", number_or_null(in.uncertainty_distance_mm)},
        {"at_infinity", std::isinf(in.uncertainty_distance_mm)},
        {"noise_sigma_px",
         in.uncertainty_method == UncertaintyMethod::board_frames ? in.fit.residual_std_px : in.fit.sigma_px},
        {"centre", number_or_null(uncertainty->centre_px)},
        {"corners", corners},
        {"without_figure", undefined},
        {"map", {{"rms", number_or_null(sigma->rms_px)},
                 {"max", number_or_null(sigma->max_px)},
                 {"samples", sigma->grid.size()},
                 {"samples_without_figure", sigma->grid.size() - sigma->valid_count}}}};
  }
  if (in.cross_validation)
    j["cross_validation"] = {
        {"method", uncertainty_method_name(in.cross_validation->method)},
        {"implied_rotation_mrad",
         1e3 * Eigen::AngleAxisd(in.cross_validation->odd_from_even.rotation).angle()},
        {"difference_rms_px", number_or_null(in.cross_validation->difference.rms_px)},
        {"difference_max_px", number_or_null(in.cross_validation->difference.max_px)},
        {"expected_rms_px", number_or_null(in.cross_validation->expected.rms_px)},
        {"ratio", number_or_null(in.cross_validation->ratio)},
        {"samples_without_figure",
         in.cross_validation->difference.grid.size() - in.cross_validation->difference.valid_count}};
  if (truth_diff)
    j["truth"] = {{"projection_difference_rms_px", number_or_null(truth_diff->rms_px)},
                  {"projection_difference_max_px", number_or_null(truth_diff->max_px)},
                  {"projection_difference_after_implied_rotation_rms_px", number_or_null(truth_diff_rotated->rms_px)},
                  {"projection_difference_after_implied_rotation_max_px", number_or_null(truth_diff_rotated->max_px)}};
  nlohmann::json views = nlohmann::json::array();
  for (std::size_t v = 0; v < in.observations.views.size(); ++v)
    views.push_back({{"source", in.observations.views[v].source},
                     {"corners", in.observations.views[v].corners.size()},
                     {"rms_px", std::isfinite(in.fit.view_rms_px[v]) ? nlohmann::json(in.fit.view_rms_px[v])
                                                                      : nlohmann::json(nullptr)}});
  j["views"] = views;
  const std::string json_path = (dir / "metrics.json").string();
  write_file_atomically(json_path, json_text(j));

  // The page.
  std::string page;
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  char date[64];
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
  page += "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n";
  page += fmt::format("<title>glasspiv calibration: {}</title>\n", html_escape(in.camera_name));
  page += "<style>body{font-family:sans-serif;max-width:1000px;margin:2em auto;color:#222}"
          "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}"
          "th{background:#f4f4f4}td:first-child,th:first-child{text-align:left}img{max-width:100%;border:1px solid #ddd}"
          "figure{margin:1.5em 0}pre{background:#f7f7f7;padding:1em;overflow-x:auto}.bad{color:#b00}</style>\n";
  page += "</head><body>\n";
  page += fmt::format("<h1>Calibration of '{}'</h1>\n<p>glasspiv, {}. {} views, {} corners, target '{}'.</p>\n",
                      html_escape(in.camera_name), date, in.observations.views.size(),
                      in.observations.corner_count(), html_escape(in.observations.target_name));
  Camera camera{in.camera_name, model, std::nullopt, in.pixel_pitch_um};
  page += "<h2>Camera</h2>\n<pre>" + html_escape(describe_camera(camera)) + "</pre>\n";

  page += "<h2>Fit</h2>\n<table>\n";
  page += fmt::format("<tr><td>RMS residual (inliers)</td><td>{}</td></tr>\n", px(in.fit.rms_px));
  page += fmt::format("<tr><td>noise estimate &sigma; per axis</td><td>{}</td></tr>\n", px(in.fit.sigma_px));
  page += fmt::format("<tr><td>corners used / dropped as outliers</td><td>{} / {}</td></tr>\n", in.fit.inlier_count,
                      in.fit.outlier_count);
  page += fmt::format("<tr><td>outlier threshold</td><td>{} &sigma;</td></tr>\n", in.options.outlier_k);
  page += fmt::format("<tr><td>solver</td><td>{} rounds, {} iterations, {:.3f} s, {}</td></tr>\n", in.fit.rounds,
                      in.fit.iterations, in.fit.total_time_s, html_escape(in.fit.termination));
  if (uncertainty)
    page += fmt::format("<tr><td>projection uncertainty (1&sigma;, worst direction; {})</td><td>{}</td></tr>\n",
                        html_escape(uncertainty_kind), html_escape(uncertainty_text(*uncertainty)));
  if (in.cross_validation) {
    const CrossValidation& cv = *in.cross_validation;
    const std::string rotation =
        cv.method == UncertaintyMethod::board_frames
            ? fmt::format(" after the implied rotation ({:.3f} mrad)",
                          1e3 * Eigen::AngleAxisd(cv.odd_from_even.rotation).angle())
            : std::string(" (intrinsics only)");
    page += fmt::format(
        "<tr><td>cross-validation (even vs odd views{})</td><td>RMS {}, max {}; expected from noise "
        "{}; ratio <span class=\"{}\">{}</span></td></tr>\n",
        html_escape(rotation), px(cv.difference.rms_px), px(cv.difference.max_px), px(cv.expected.rms_px),
        cv.ratio > 3 ? "bad" : "", std::isfinite(cv.ratio) ? fmt::format("{:.2f}", cv.ratio) : "no figure");
  }
  if (truth_diff)
    page += fmt::format(
        "<tr><td>projection difference to the true camera</td><td>RMS {}, max {}; after the implied "
        "rotation RMS {}, max {}</td></tr>\n",
        px(truth_diff->rms_px), px(truth_diff->max_px), px(truth_diff_rotated->rms_px), px(truth_diff_rotated->max_px));
  page += "</table>\n";

  page += "<h2>Parameters</h2>\n<table>\n<tr><th>parameter</th><th>value</th><th>1&sigma;</th>";
  if (in.truth) page += "<th>true</th><th>error</th>";
  page += "</tr>\n";
  for (int i = 0; i < 4 + model.distortion_count(); ++i) {
    const double sigma = parameter_sigma(in.fit, i);
    page += fmt::format("<tr><td>{}</td><td>{:.8g}</td><td>{}</td>", intrinsic_name(i), model.intrinsics()[i],
                        std::isfinite(sigma) ? fmt::format("{:.3g}", sigma) : "fixed");
    if (in.truth) {
      const double t = in.truth->model.intrinsics()[i];
      page += fmt::format("<td>{:.8g}</td><td>{:+.3g}</td>", t, model.intrinsics()[i] - t);
    }
    page += "</tr>\n";
  }
  page += "</table>\n";

  for (const Picture& p : pictures)
    page += fmt::format("<figure><img src=\"{}\" alt=\"{}\"><figcaption>{}</figcaption></figure>\n", p.file, p.file,
                        html_escape(p.caption));

  page += "<h2>Views</h2>\n<table>\n<tr><th>view</th><th>corners</th><th>RMS px</th></tr>\n";
  for (std::size_t v = 0; v < in.observations.views.size(); ++v) {
    const double rms = in.fit.view_rms_px[v];
    page += fmt::format("<tr><td>{}</td><td>{}</td><td>{}</td></tr>\n", html_escape(in.observations.views[v].source),
                        in.observations.views[v].corners.size(), std::isfinite(rms) ? fmt::format("{:.4f}", rms) : "skipped");
  }
  page += "</table>\n";
  for (const SkippedView& s : in.fit.skipped_views)
    page += fmt::format("<p>View {} skipped: {}</p>\n", s.view, html_escape(s.reason));
  page += "</body></html>\n";
  const std::string html_path = (dir / "report.html").string();
  write_file_atomically(html_path, page);
  return {html_path, json_path};
}

}  // namespace glasspiv
