// glasspiv calib next: where to put the board next (calib/fit/next_view.h):
// the proposed pose in words and numbers, a picture of the board where it
// should appear, the uncertainty map now and predicted with that view, an HTML
// page and a JSON file with all of it.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "apps/cli_checks.h"
#include "apps/commands.h"
#include "apps/html_text.h"
#include "apps/photo_detection.h"
#include "apps/plots.h"
#include "apps/png_file.h"
#include "calib/fit/multi_start.h"
#include "calib/fit/next_view.h"
#include "calib/io/camera_file.h"
#include "targets/observations_io.h"
#include "targets/target_spec.h"
#include "targets/target_yaml.h"
#include "util/json_document.h"
#include "util/atomic_file.h"
#include "util/input_error.h"
#include "util/progress_bar.h"

namespace glasspiv {
namespace {
namespace fs = std::filesystem;

constexpr int kMaxNextViewGridSamples = 4000;

struct NextCommandOptions {
  std::string observations, target, camera, output_dir;
  std::string lens_model = "opencv5";
  CLI::Option* lens_model_option = nullptr;  // given on the command line?
  double outlier_k = 4.0;
  std::string distance = "session";  // mm, "inf", or "session": the session's median board distance
  double step_px = 0;
  NextViewOptions next;
};

// The observed corners must be the target's: the same id at the same board point.
void check_target_matches(const Observations& observations, const std::vector<BoardCorner>& corners,
                          const std::string& observations_path, const std::string& target_path) {
  std::map<int, Eigen::Vector3d> point_of;
  for (const BoardCorner& c : corners) point_of[c.id] = c.point_mm;
  for (const ViewObservations& view : observations.views)
    for (const CornerObservation& c : view.corners) {
      const auto it = point_of.find(c.id);
      if (it == point_of.end() || (it->second - c.board_point_mm).norm() > 1e-6 * (1 + it->second.norm()))
        throw InputError(observations_path, "target",
                         it == point_of.end()
                             ? fmt::format("corner id {} (view '{}') is not a corner of {}", c.id, view.source,
                                           target_path)
                             : fmt::format("corner id {} (view '{}') lies at ({}, {}) mm, but at ({}, {}) mm on {}",
                                           c.id, view.source, number(c.board_point_mm.x()),
                                           number(c.board_point_mm.y()), number(it->second.x()),
                                           number(it->second.y()), target_path));
    }
}

nlohmann::json number_or_null(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

std::string px(double value) { return std::isfinite(value) ? fmt::format("{:.4f} px", value) : "no figure"; }

// The proposed board over a map: its outline, corners and centre.
void draw_board(HeatMapPicture& p, const CandidateView& view) {
  // Drawn into the map's rectangle only: the outline may leave the image.
  cv::Mat map = p.image(p.plot);
  const auto at = [&](const Eigen::Vector2d& pixel) { return p.at(pixel.x(), pixel.y()) - p.plot.tl(); };
  std::vector<cv::Point> outline;
  for (const Eigen::Vector2d& q : view.outline_px) outline.push_back(at(q));
  if (outline.size() >= 2) {
    cv::polylines(map, outline, true, cv::Scalar(255, 255, 255), 4, cv::LINE_AA);
    cv::polylines(map, outline, true, cv::Scalar(0, 0, 230), 2, cv::LINE_AA);
  }
  for (const Eigen::Vector2d& c : view.corners_px) cv::circle(map, at(c), 3, cv::Scalar(0, 0, 230), cv::FILLED, cv::LINE_AA);
  cv::drawMarker(map, at(view.centre_px), cv::Scalar(255, 255, 255), cv::MARKER_CROSS, 18, 2);
}

nlohmann::json points_json(const std::vector<Eigen::Vector2d>& points) {
  nlohmann::json out = nlohmann::json::array();
  for (const Eigen::Vector2d& p : points) out.push_back({p.x(), p.y()});
  return out;
}

nlohmann::json candidate_json(const CandidateView& c, int w, int h) {
  const Eigen::Vector3d r = c.camera_from_board.rvec(), t = c.camera_from_board.translation_mm;
  return {{"advice", describe_view(c, w, h)},
          {"camera_from_board", {{"rvec", {r.x(), r.y(), r.z()}}, {"tvec_mm", {t.x(), t.y(), t.z()}}}},
          {"distance_mm", c.distance_mm},
          {"tilt_deg", c.tilt_deg},
          {"tilt_axis_deg", c.tilt_axis_deg},
          {"view_angle_deg", c.view_angle_deg},
          {"centre_px", {c.centre_px.x(), c.centre_px.y()}},
          {"visible_corners", c.corners_px.size()},
          {"visible_fraction", c.visible_fraction},
          {"predicted_worst_px", number_or_null(c.predicted_worst_px)}};
}

std::string distance_text(double distance_mm) {
  return std::isinf(distance_mm) ? std::string("at infinity") : fmt::format("at {:.4g} mm", distance_mm);
}

void run_next(const NextCommandOptions& o) {
  const std::string dir = o.output_dir.empty()
                              ? fs::path(o.observations).replace_extension("").string() + "_next"
                              : o.output_dir;
  const fs::path out(dir);
  const std::string html_path = (out / "next_view.html").string(), json_path = (out / "next_view.json").string(),
                    placement_path = (out / "placement.png").string(), before_path = (out / "before.png").string(),
                    after_path = (out / "after.png").string();
  check_calib_outputs({o.observations, o.target, o.camera},
                      {{dir, "-o", OutputKind::folder}, {html_path, "-o"}, {json_path, "-o"}, {placement_path, "-o"},
                       {before_path, "-o"}, {after_path, "-o"}});
  const TargetSpec spec = read_target_yaml(o.target);
  require_target_corners(spec, o.target, "calib next");
  const Observations observations = read_observations(o.observations);
  BoardLayout board;
  for (const BoardCorner& c : board_corners(spec)) board.corners_mm.push_back(c.point_mm);
  board.pattern_size_mm = board_size_mm(spec);
  check_target_matches(observations, board_corners(spec), o.observations, o.target);
  const int w = observations.image_width_px, h = observations.image_height_px;
  NextViewOptions next = o.next;
  next.approx_step_px = o.step_px > 0 ? o.step_px : std::max(w, h) / 16.0;
  check_sample_grid("--step-px", w, h, next.approx_step_px);
  // Every candidate recomputes the whole map (~2 ms for 221 samples and 13
  // views): 4000 samples keep a thousand candidates under a minute.
  const PixelGrid grid = PixelGrid::over_image(w, h, next.approx_step_px);
  if (grid.size() > kMaxNextViewGridSamples)
    throw InputError("", "--step-px",
                     fmt::format("{} px makes {} samples per map; calib next evaluates one map per candidate and "
                                 "allows {}: give a step of {} px or more",
                                 number(next.approx_step_px), grid.size(), kMaxNextViewGridSamples,
                                 number(std::ceil(std::sqrt(static_cast<double>(w) * h / kMaxNextViewGridSamples)) + 1)));

  if (!o.camera.empty() && o.lens_model_option && o.lens_model_option->count() > 0)
    throw InputError(o.camera, "--lens-model", "is the camera's own with --camera (leave --lens-model out)");
  std::string fit_text;
  const IntrinsicFit fit = [&] {
    if (!o.camera.empty()) {
      const Camera camera = read_camera(o.camera);
      if (camera.model.width_px() != w || camera.model.height_px() != h)
        throw InputError(o.camera, "image size",
                         fmt::format("is {}x{} px but the observations' images are {}x{} px", camera.model.width_px(),
                                     camera.model.height_px(), w, h));
      ProgressBar bar("board poses", 1);
      IntrinsicFit held = naming_file(o.observations, [&] { return fit_with_camera_held(camera.model, observations, o.outlier_k); });
      bar.finish();
      fit_text = fmt::format("camera '{}' from {} held ({}); board poses fitted: RMS {} over {} corners, {} views",
                             camera.name, o.camera, lens_model_name(camera.model.lens_model()), px(held.rms_px),
                             held.inlier_count, held.state_covariance.views.size());
      return held;
    }
    IntrinsicFitOptions options;
    options.lens_model = lens_model_from_name(o.lens_model);
    options.outlier_k = o.outlier_k;
    ProgressBar bar("fitting", 1);
    MultiStartFit m = naming_file(o.observations, [&] { return fit_intrinsics_multi_start(observations, options); });
    bar.finish();
    fit_text = fmt::format("fitted {}: RMS {} over {} corners ({} outliers dropped), {} views", o.lens_model,
                           px(m.fit.rms_px), m.fit.inlier_count, m.fit.outlier_count,
                           m.fit.state_covariance.views.size());
    return std::move(m.fit);
  }();
  std::printf("%s\n", fit_text.c_str());

  next.distance_mm = o.distance == "inf"       ? kAtInfinity
                     : o.distance == "session" ? naming_file(o.observations, [&] {
                                                   return session_distances(fit, observations).median_mm;
                                                 })
                                               : std::strtod(o.distance.c_str(), nullptr);
  std::optional<ProgressBar> bar;
  const NextView result = naming_file(o.observations, [&] {
    return propose_next_view(fit, observations, board, next, [&](int done, int total) {
      if (!bar) bar.emplace("candidate views", total);
      bar->set_done(done);
    });
  });
  if (bar) bar->finish();
  const CandidateView& best = result.best;
  const std::string advice = describe_view(best, w, h);
  const double reduction = 1 - result.worst_after_px / result.worst_before_px;
  const std::string kind = fmt::format("board-frames, {}{}", distance_text(next.distance_mm),
                                       o.distance == "session" ? " (the session's median)" : "");
  std::printf("worst projection uncertainty (1 sigma, %s): now %s, predicted %s with the proposed view (%s)\n",
              kind.c_str(), px(result.worst_before_px).c_str(), px(result.worst_after_px).c_str(),
              std::isfinite(reduction) ? fmt::format("{:.0f}% lower", 100 * reduction).c_str() : "no figure");
  std::printf("next view: %s\n", advice.c_str());
  const Eigen::Vector3d r = best.camera_from_board.rvec(), t = best.camera_from_board.translation_mm;
  std::printf("     camera_from_board rvec [%.4f, %.4f, %.4f] rad, tvec [%.1f, %.1f, %.1f] mm; %zu of %zu corners in "
              "view; %zu feasible of %d poses tried\n",
              r.x(), r.y(), r.z(), t.x(), t.y(), t.z(), best.corners_px.size(), board.corners_mm.size(),
              result.candidates.size(), result.poses_tried);

  // Pictures on one colour scale: the map now.
  make_output_folder(dir, "-o");
  const double top = std::isfinite(result.worst_before_px) ? result.worst_before_px : 0;
  // One colour scale [0, top] for the three, so before and after compare by colour.
  const auto map = [&](const GridValues& values, const std::string& title) {
    return draw_magnitude_map(values, w, h, {title, "sigma px"}, top);
  };
  HeatMapPicture placement = map(result.before, "next view: where the board should appear (now: " + kind + ")");
  draw_board(placement, best);
  write_png(placement_path, placement.image);
  write_png(before_path, map(result.before, "projection uncertainty now (" + kind + ")").image);
  HeatMapPicture after = map(result.after, "predicted with the proposed view (" + kind + ")");
  draw_board(after, best);
  write_png(after_path, after.image);

  std::vector<const CandidateView*> ranked;
  for (const CandidateView& c : result.candidates)
    if (std::isfinite(c.predicted_worst_px)) ranked.push_back(&c);
  std::sort(ranked.begin(), ranked.end(),
            [](const CandidateView* a, const CandidateView* b) { return a->predicted_worst_px < b->predicted_worst_px; });
  ranked.resize(std::min<std::size_t>(ranked.size(), 5));

  nlohmann::json j;
  j["observations"] = o.observations;
  j["target"] = o.target;
  j["camera"] = o.camera.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.camera);
  j["fit"] = {{"lens_model", lens_model_name(fit.camera.lens_model())},
              {"source", o.camera.empty() ? "fitted" : "camera held"},
              {"rms_px", fit.rms_px},
              {"views", fit.state_covariance.views.size()},
              {"noise_sigma_px", result.noise_sigma_px}};
  j["uncertainty"] = {{"method", "board-frames"},
                      {"distance_mm", number_or_null(next.distance_mm)},
                      {"at_infinity", std::isinf(next.distance_mm)},
                      {"grid_samples", result.before.grid.size()},
                      {"worst_before_px", number_or_null(result.worst_before_px)},
                      {"worst_after_px", number_or_null(result.worst_after_px)},
                      {"reduction_fraction", number_or_null(reduction)},
                      {"rms_before_px", number_or_null(result.before.rms_px)},
                      {"rms_after_px", number_or_null(result.after.rms_px)}};
  nlohmann::json proposal = candidate_json(best, w, h);
  proposal["corners_px"] = points_json(best.corners_px);
  proposal["outline_px"] = points_json(best.outline_px);
  j["proposal"] = proposal;
  j["session_distances_mm"] = {
      {"min", result.distances.min_mm}, {"median", result.distances.median_mm}, {"max", result.distances.max_mm}};
  nlohmann::json top_five = nlohmann::json::array();
  for (const CandidateView* c : ranked) top_five.push_back(candidate_json(*c, w, h));
  j["candidates"] = {{"tried", result.poses_tried}, {"feasible", result.candidates.size()}, {"best", top_five}};
  j["files"] = {{"placement", "placement.png"}, {"before", "before.png"}, {"after", "after.png"}, {"page", "next_view.html"}};
  write_file_atomically(json_path, json_text(j));

  std::string page = "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n";
  page += "<title>glasspiv: the next calibration view</title>\n";
  page += "<style>body{font-family:sans-serif;max-width:1000px;margin:2em auto;color:#222}"
          "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}"
          "th{background:#f4f4f4}td:first-child,th:first-child{text-align:left}img{max-width:100%;border:1px solid #ddd}"
          "figure{margin:1.5em 0}.advice{font-size:1.2em;font-weight:bold}</style>\n</head><body>\n";
  page += fmt::format("<h1>The next calibration view</h1>\n<p>{} ({} views, {} corners); {}.</p>\n",
                      html_escape(o.observations), observations.views.size(), observations.corner_count(),
                      html_escape(fit_text));
  std::string sentence = advice;
  sentence[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(sentence[0])));
  page += fmt::format("<p class=\"advice\">{}.</p>\n", html_escape(sentence));
  page += "<table>\n";
  page += fmt::format("<tr><td>worst projection uncertainty (1&sigma;, {})</td><td>now {}, predicted {} ({})</td></tr>\n",
                      html_escape(kind), px(result.worst_before_px), px(result.worst_after_px),
                      std::isfinite(reduction) ? fmt::format("{:.0f}% lower", 100 * reduction) : "no figure");
  page += fmt::format("<tr><td>RMS over the image</td><td>now {}, predicted {}</td></tr>\n", px(result.before.rms_px),
                      px(result.after.rms_px));
  page += fmt::format("<tr><td>camera_from_board</td><td>rvec [{:.4f}, {:.4f}, {:.4f}] rad, tvec [{:.1f}, {:.1f}, "
                      "{:.1f}] mm</td></tr>\n",
                      r.x(), r.y(), r.z(), t.x(), t.y(), t.z());
  page += fmt::format("<tr><td>distance, tilt</td><td>{:.0f} mm, {:.0f}&deg; about an axis {:.0f}&deg; from the "
                      "horizontal ({:.0f}&deg; to the line of sight)</td></tr>\n",
                      best.distance_mm, best.tilt_deg, best.tilt_axis_deg, best.view_angle_deg);
  page += fmt::format("<tr><td>corners in view</td><td>{} of {}</td></tr>\n", best.corners_px.size(),
                      board.corners_mm.size());
  page += fmt::format("<tr><td>candidates</td><td>{} feasible of {} poses tried (distances {:.0f}-{:.0f} mm, as the "
                      "session's)</td></tr>\n",
                      result.candidates.size(), result.poses_tried, result.distances.min_mm, result.distances.max_mm);
  page += fmt::format("<tr><td>noise &sigma; (the session's)</td><td>{}</td></tr>\n</table>\n",
                      px(result.noise_sigma_px));
  const auto figure = [&](const std::string& file, const std::string& caption) {
    page += fmt::format("<figure><img src=\"{}\" alt=\"{}\"><figcaption>{}</figcaption></figure>\n", file, file,
                        html_escape(caption));
  };
  figure("placement.png", "Where the board should appear in the image (outline and corners), over the projection "
                          "uncertainty now.");
  figure("before.png", "The projection uncertainty now (1 sigma, worst direction; mrcal's method through the board "
                       "frames).");
  figure("after.png", "Predicted with the proposed view added (a rank update of the fit's normal equations, not a "
                      "refit), on the same colour scale.");
  page += "<h2>The best candidates</h2>\n<table>\n<tr><th>view</th><th>predicted worst</th></tr>\n";
  for (const CandidateView* c : ranked)
    page += fmt::format("<tr><td>{}</td><td>{}</td></tr>\n", html_escape(describe_view(*c, w, h)),
                        px(c->predicted_worst_px));
  page += "</table>\n</body></html>\n";
  write_file_atomically(html_path, page);
  std::printf("wrote %s, %s and %s (with before.png and after.png)\n", html_path.c_str(), json_path.c_str(),
              placement_path.c_str());
}

}  // namespace

void register_calib_next_command(CLI::App& calib) {
  auto o = std::make_shared<NextCommandOptions>();
  CLI::App* c = calib.add_subcommand(
      "next", "Propose the board pose whose view would most reduce the worst projection uncertainty over the image");
  c->add_option("observations", o->observations, "Observations file (.yaml/.json) from calib detect")
      ->required()
      ->check(CLI::ExistingFile);
  c->add_option("--target", o->target, "Target spec YAML the observations were detected with")
      ->required()
      ->check(CLI::ExistingFile);
  c->add_option("--camera", o->camera,
                "A camera already fitted to these observations (held; only the board poses are fitted)")
      ->check(CLI::ExistingFile);
  c->add_option("-o,--output", o->output_dir, "Folder for next_view.html/.json and the pictures "
                                              "(default: OBSERVATIONS without extension + _next)");
  o->lens_model_option = c->add_option("--lens-model", o->lens_model, "Without --camera: pinhole, opencv4, opencv5, opencv8, opencv12 or opencv14")
      ->check(CLI::IsMember({"pinhole", "opencv4", "opencv5", "opencv8", "opencv12", "opencv14"}))
      ->capture_default_str();
  c->add_option("--outlier-k", o->outlier_k, "Drop corners beyond k sigma (1 to 1000); 0 keeps all")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            char* end = nullptr;
            const double value = std::strtod(text.c_str(), &end);
            if (text.empty() || end == text.c_str() || *end != '\0') return "'" + text + "' is not a number";
            return value == 0 || (value >= 1 && value <= 1000) ? "" : "'" + text + "' is not 0 or in [1, 1000]";
          },
          "0 or NUMBER in [1, 1000]"))
      ->capture_default_str();
  c->add_option("--uncertainty-distance-mm", o->distance,
                "Distance of the point whose projection uncertainty counts (mm, 1e-3 to 1e12), inf, or session "
                "(the session's median board distance)")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            if (text == "inf" || text == "session") return "";
            char* end = nullptr;
            const double value = std::strtod(text.c_str(), &end);
            if (text.empty() || end == text.c_str() || *end != '\0' || !std::isfinite(value))
              return "'" + text + "' is not a finite number, inf or session";
            if (!(value >= 1e-3 && value <= 1e12)) return "'" + text + "' is outside [0.001, 1e+12]";
            return "";
          },
          "NUMBER in [0.001, 1e+12], inf or session"))
      ->capture_default_str();
  c->add_option("--step-px", o->step_px, "Uncertainty grid spacing in px (default: the image's longer side / 16)")
      ->check(CLI::PositiveNumber);
  c->add_option("--position-cols", o->next.position_cols, "Candidate board centres across the image (1 to 20)")
      ->check(CLI::Range(1, 20))
      ->capture_default_str();
  c->add_option("--position-rows", o->next.position_rows, "Candidate board centres down the image (1 to 20)")
      ->check(CLI::Range(1, 20))
      ->capture_default_str();
  c->add_option("--distance-steps", o->next.distance_steps,
                "Candidate distances from the session's nearest to its farthest board (1 to 10)")
      ->check(CLI::Range(1, 10))
      ->capture_default_str();
  c->add_option("--max-tilt-deg", o->next.max_tilt_deg, "Largest candidate tilt from facing the sensor (deg, 0 to 80)")
      ->check(CLI::Range(0.0, 80.0))
      ->capture_default_str();
  c->add_option("--tilt-steps", o->next.tilt_steps, "Tilts per sign between 0 and --max-tilt-deg (1 to 10)")
      ->check(CLI::Range(1, 10))
      ->capture_default_str();
  c->add_option("--tilt-axes", o->next.tilt_axes, "Tilt axes in the sensor plane, evenly from the horizontal (1 to 12)")
      ->check(CLI::Range(1, 12))
      ->capture_default_str();
  c->add_option("--min-visible", o->next.min_visible_fraction,
                "Least fraction of the board's corners inside the image (0.1 to 1)")
      ->check(CLI::Range(0.1, 1.0))
      ->capture_default_str();
  c->add_option("--max-view-angle-deg", o->next.max_view_angle_deg,
                "Steepest board normal to line of sight a detector still reads (deg, 1 to 89)")
      ->check(CLI::Range(1.0, 89.0))
      ->capture_default_str();
  c->callback([o] { run_next(*o); });
}

}  // namespace glasspiv
