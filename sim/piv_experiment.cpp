#include "sim/piv_experiment.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "correct/camera_resampler.h"
#include "render/forward_render.h"
#include "render/parallel_rows.h"
#include "render/sheet_texture.h"
#include "render/trace_scene_builder.h"
#include "sim/tracers.h"

namespace glasspiv {
namespace {

void require(bool ok, const char* field, const std::string& problem) {
  if (!ok) throw std::invalid_argument(fmt::format("piv experiment: {} {}", field, problem));
}

// A setting's (or the flow's) fault: the message names the value, not this code.
void require_setting(bool ok, const char* setting, const std::string& problem) {
  if (!ok) throw ExperimentSettingError(setting, problem);
}

// SplitMix64 (Steele et al. 2014): independent noise seeds per frame from one seed.
std::uint64_t mix_seed(std::uint64_t seed, std::uint64_t stream) {
  std::uint64_t z = seed + 0x9e3779b97f4a7c15ULL * (stream + 1);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

Eigen::Vector3d sheet_point_mm(const SheetPlane& sheet, double s_mm, double t_mm) {
  return sheet.origin_mm + s_mm * sheet.s_axis + t_mm * sheet.t_axis;
}

// Where the pixel's ray (glass removed: straight in the fluid) meets the sheet
// plane within its extent; false if it does not.
bool pixel_sheet_point(const CameraModel& model, const RigidTransform& pose, const SheetPlane& sheet,
                       const Eigen::Vector2d& pixel, Eigen::Vector3d* point_mm) {
  const std::optional<WorldRay> ray = pixel_world_ray(model, pose, pixel);
  if (!ray) return false;
  const Eigen::Vector3d n = sheet.normal();
  const double denom = ray->direction.dot(n);
  if (std::abs(denom) < 1e-12) return false;
  const double along = (sheet.origin_mm - ray->origin_mm).dot(n) / denom;
  if (!(along > 0)) return false;
  const Eigen::Vector3d p = ray->origin_mm + along * ray->direction;
  const double s = (p - sheet.origin_mm).dot(sheet.s_axis), t = (p - sheet.origin_mm).dot(sheet.t_axis);
  if (std::abs(s) > 0.5 * sheet.extent_s_mm || std::abs(t) > 0.5 * sheet.extent_t_mm) return false;
  *point_mm = p;
  return true;
}

// Frames A and B of the tracer on the plane at point_mm at mid-pulse, projected on the plane.
struct CentredPair {
  Eigen::Vector3d a_mm, b_mm;
};
CentredPair centred_pair(const Flow& flow, const SheetPlane& sheet, const Eigen::Vector3d& point_mm, double mid_s,
                         double dt_s, int sub_steps) {
  const Eigen::Vector3d n = sheet.normal();
  Eigen::Vector3d a = advect_rk4_mm(flow, point_mm, mid_s, -0.5 * dt_s, sub_steps);
  Eigen::Vector3d b = advect_rk4_mm(flow, point_mm, mid_s, 0.5 * dt_s, sub_steps);
  a -= (a - sheet.origin_mm).dot(n) * n;
  b -= (b - sheet.origin_mm).dot(n) * n;
  return {a, b};
}

// Per texel i of a row (cell [i - 1/2, i + 1/2] texels), the mean over the
// texel of the unit Gaussian exp(-(x - centre)^2 / (2 sigma^2)) (x in mm): the
// texel-integrated particle image, so a few texels per particle keep its centroid.
void texel_means(double centre, double sigma, int first, int last, double texel, std::vector<double>* out) {
  const double k = 1.0 / (std::sqrt(2.0) * sigma);
  const double scale = sigma * std::sqrt(M_PI / 2) / texel;
  out->resize(static_cast<std::size_t>(std::max(0, last - first + 1)));
  for (int i = first; i <= last; ++i) {
    const double lo = (i - 0.5) * texel - centre, hi = (i + 0.5) * texel - centre;
    (*out)[static_cast<std::size_t>(i - first)] = scale * (std::erf(hi * k) - std::erf(lo * k));
  }
}

// The tracers as a sheet picture on grid (cell centres = texel centres): each a
// Gaussian of 1/e^2 diameter diameter_mm (sigma = d / 4) and peak
// peak * sheet_relative_intensity, at its (s, t) on the plane.
std::vector<float> draw_tracers(const std::vector<Eigen::Vector3d>& tracers_mm, const Sheet& sheet_profile,
                                const SheetPlane& plane, const SheetGrid& grid, double diameter_mm, double peak) {
  std::vector<float> texels(grid.cell_count(), 0.0f);
  const double sigma = 0.25 * diameter_mm, reach = 3 * diameter_mm / 2;  // 6 sigma: 1.5e-8 of the peak
  std::vector<double> along_col, along_row;
  for (const Eigen::Vector3d& p : tracers_mm) {
    const double w = peak * sheet_relative_intensity(sheet_profile, p);
    if (w < 1e-6 * peak) continue;
    const double s = (p - plane.origin_mm).dot(plane.s_axis), t = (p - plane.origin_mm).dot(plane.t_axis);
    const double col = grid.col(s), row = grid.row(t);
    const int c0 = std::max(0, static_cast<int>(std::floor(grid.col(s - reach))));
    const int c1 = std::min(grid.cols - 1, static_cast<int>(std::ceil(grid.col(s + reach))));
    const int r0 = std::max(0, static_cast<int>(std::floor(grid.row(t + reach))));
    const int r1 = std::min(grid.rows - 1, static_cast<int>(std::ceil(grid.row(t - reach))));
    if (c0 > c1 || r0 > r1) continue;
    texel_means(col * grid.mm_per_px, sigma, c0, c1, grid.mm_per_px, &along_col);
    texel_means(row * grid.mm_per_px, sigma, r0, r1, grid.mm_per_px, &along_row);
    for (int r = r0; r <= r1; ++r) {
      float* line = texels.data() + static_cast<std::size_t>(r) * grid.cols;
      const double wr = w * along_row[static_cast<std::size_t>(r - r0)];
      for (int c = c0; c <= c1; ++c) line[c] += static_cast<float>(wr * along_col[static_cast<std::size_t>(c - c0)]);
    }
  }
  return texels;
}

cv::Mat as_mat(const std::vector<float>& v, int width, int height) {
  cv::Mat m(height, width, CV_32F);
  std::copy(v.begin(), v.end(), m.ptr<float>(0));
  return m;
}

// The largest |s| and |t| any crossing of the maps reaches (0, 0 for none).
void crossing_reach(const TransportMap& map, double* s_mm, double* t_mm) {
  for (std::size_t i = 0; i < map.crossing_count(); ++i) {
    *s_mm = std::max(*s_mm, std::abs(double(map.s_mm[i])));
    *t_mm = std::max(*t_mm, std::abs(double(map.t_mm[i])));
  }
}

}  // namespace

void PivExperimentSettings::check() const {
  require_setting(std::isfinite(dt_s) && dt_s > 0, "dt_s", fmt::format("{} s must be a positive number of seconds", dt_s));
  require_setting(std::isfinite(time_a_s), "time_a_s", "must be finite");
  require_setting(std::isfinite(density_ppp) && density_ppp > 0, "density_ppp", "must be positive");
  require_setting(std::isfinite(particle_px) && particle_px > 0, "particle_px", "must be positive");
  require_setting(std::isfinite(peak_radiance) && peak_radiance > 0, "peak_radiance", "must be positive");
  require_setting(rk4_sub_steps >= 1, "rk4_sub_steps", "must be at least 1");
  require_setting(std::isfinite(texels_per_px) && texels_per_px >= 1, "texels_per_px", "must be at least 1");
  require_setting(std::isfinite(max_texels) && max_texels >= 1, "max_texels", "must be at least 1");
  require_setting(samples_per_axis >= 1, "samples_per_axis", "must be at least 1");
  require_setting(std::isfinite(sheet_truth_step_px) && sheet_truth_step_px > 0, "sheet_truth_step_px",
                  "must be positive");
  sensor.check();
}

std::string quarter_rule_warning(double max_displacement_px) {
  const double limit = kQuarterRuleWindowPx / 4;
  if (!(max_displacement_px > limit)) return "";
  return fmt::format("the largest displacement, {:.3g} px, exceeds a quarter of a {:g} px window ({:g} px): "
                     "the one-quarter rule (Keane & Adrian 1990) is broken, shorten dt or use larger windows",
                     max_displacement_px, kQuarterRuleWindowPx, limit);
}

PivExperiment simulate_piv_experiment(const TraceScene& scene, const Sheet& sheet,
                                      const std::vector<ExperimentCamera>& cameras, const Flow& raw_flow,
                                      const PivExperimentSettings& settings,
                                      const std::function<void(double)>& progress) {
  settings.check();
  require(!cameras.empty(), "cameras", "must not be empty");
  const auto report = [&](double f) {
    if (progress) progress(std::clamp(f, 0.0, 1.0));
  };
  const SheetPlane& plane = scene.sheet;
  const SolidInteriors solids(scene.solids);
  const FlowOutsideSolids flow(std::shared_ptr<const Flow>(&raw_flow, [](const Flow*) {}), solids);
  const double mid_s = settings.time_a_s + 0.5 * settings.dt_s;
  const int n_cam = static_cast<int>(cameras.size());
  // Progress shares: maps 50 %, truth 20 %, tracers and renders 30 %.
  const double per_map = 0.5 / (2 * n_cam);

  PivExperiment out;
  out.cameras.resize(cameras.size());
  std::vector<TransportMap> maps(cameras.size()), direct_maps(cameras.size());
  double reach_s = 0, reach_t = 0;
  for (int k = 0; k < n_cam; ++k) {
    const ExperimentCamera& cam = cameras[static_cast<std::size_t>(k)];
    ExperimentCameraResult& r = out.cameras[static_cast<std::size_t>(k)];
    r.name = cam.name;
    r.width = cam.model.width_px();
    r.height = cam.model.height_px();
    direct_maps[k] = glass_removed_map(scene, cam.model, cam.camera_from_world, settings.samples_per_axis, settings.threads);
    r.mm_per_px = median_footprint_mm(direct_maps[k]);
    require(k > 0 || r.mm_per_px > 0, "cameras", fmt::format("'{}' sees none of the sheet", cam.name));
    report((2 * k + 1) * per_map);
    maps[k] = build_transport_map(scene, cam.model, cam.camera_from_world, settings.trace, settings.samples_per_axis,
                                  settings.threads, [&](int done, int rows) {
                                    report((2 * k + 1 + double(done) / std::max(rows, 1)) * per_map);
                                  });
    crossing_reach(maps[k], &reach_s, &reach_t);
    crossing_reach(direct_maps[k], &reach_s, &reach_t);
  }

  // Tracers: density and image size from the first camera's glass-removed pixel.
  const double px_mm = out.cameras.front().mm_per_px;
  out.tracers_per_mm3 = tracers_per_mm3(settings.density_ppp, sheet.thickness_mm, px_mm);
  out.particle_diameter_mm = settings.particle_px * px_mm;
  // Margin: how far a tracer can come from between the frames (speed sampled over the sheet).
  double top_speed = 0;
  for (int i = 0; i <= 20; ++i)
    for (int j = 0; j <= 20; ++j) {
      const Eigen::Vector3d p =
          sheet_point_mm(plane, (i / 20.0 - 0.5) * plane.extent_s_mm, (j / 20.0 - 0.5) * plane.extent_t_mm);
      top_speed = std::max(top_speed, flow.velocity_m_per_s(p, mid_s).stableNorm());  // 1e300 m/s does not overflow
    }
  // A flow and pulse separation that carry tracers across the whole sheet
  // between the frames make no PIV pair (and a seeding slab beyond any scene).
  require_setting(std::isfinite(top_speed), "flow", "the flow's speed on the sheet is not finite");
  const double reach_mm = 1000 * top_speed * settings.dt_s;
  const double sheet_mm = std::max(plane.extent_s_mm, plane.extent_t_mm);
  require_setting(reach_mm <= sheet_mm, "dt_s",
                  fmt::format("with the flow's top speed on the sheet, {:.4g} m/s, tracers move {:.4g} mm in {:.4g} s, "
                              "more than the sheet's extent ({:.4g} mm): shorten the pulse separation or check the flow",
                              top_speed, reach_mm, settings.dt_s, sheet_mm));
  TracerSeeding seeding;
  seeding.per_mm3 = out.tracers_per_mm3;
  seeding.margin_mm = 1.5 * reach_mm + 2 * out.particle_diameter_mm;
  seeding.seed = settings.seed;
  {
    const double volume_mm3 = (sheet.extent_mm[0] + 2 * seeding.margin_mm) * (sheet.extent_mm[1] + 2 * seeding.margin_mm) *
                              2 * seeding.half_depth_sigmas * sheet.sigma_mm();
    const double expected = seeding.per_mm3 * volume_mm3;
    require_setting(std::isfinite(expected) && expected <= kMaxTracers, "density_ppp",
                    fmt::format("{:.4g} tracers per px ask for {:.4g} tracers in the sheet's slab, over the limit of "
                                "{:.4g}", settings.density_ppp, expected, kMaxTracers));
  }
  const TracerFrames frames = advect_tracers(flow, seed_tracers_mm(sheet, seeding, solids), settings.time_a_s,
                                             settings.dt_s, settings.rk4_sub_steps);
  for (const Eigen::Vector3d& p : frames.frame_b_mm)
    require_setting(p.allFinite(), "flow", "carries a tracer to a non-finite position between the frames");
  out.tracers = frames.frame_a_mm.size();
  report(0.55);

  // The texture covers what the cameras see (centred on the sheet origin, as SheetTexture lays it).
  SheetPlane seen = plane;
  const double pad = 2 * out.particle_diameter_mm;
  seen.extent_s_mm = std::min(plane.extent_s_mm, 2 * (reach_s + pad));
  seen.extent_t_mm = std::min(plane.extent_t_mm, 2 * (reach_t + pad));
  double texel_mm = px_mm / settings.texels_per_px;
  const double area = seen.extent_s_mm * seen.extent_t_mm;
  if (area / (texel_mm * texel_mm) > settings.max_texels) texel_mm = std::sqrt(area / settings.max_texels);
  const SheetGrid texture_grid = sheet_grid_covering(seen, texel_mm);
  out.mm_per_texel = texel_mm;
  out.texels_per_px = px_mm / texel_mm;

  for (int frame = 0; frame < 2; ++frame) {
    const std::vector<Eigen::Vector3d>& where = frame == 0 ? frames.frame_a_mm : frames.frame_b_mm;
    const SheetTexture texture = [&] {
      const std::vector<float> texels =
          draw_tracers(where, sheet, plane, texture_grid, out.particle_diameter_mm, settings.peak_radiance);
      return SheetTexture(texels.data(), texture_grid.rows, texture_grid.cols, texture_grid.mm_per_px);
    }();
    for (int k = 0; k < n_cam; ++k) {
      ExperimentCameraResult& r = out.cameras[static_cast<std::size_t>(k)];
      const cv::Mat through = as_mat(forward_render_values(maps[k], texture), r.width, r.height);
      const cv::Mat direct = as_mat(forward_render_values(direct_maps[k], texture), r.width, r.height);
      const std::uint64_t stream = 4 * static_cast<std::uint64_t>(k) + 2 * frame;
      (frame == 0 ? r.frame_a : r.frame_b) = sensor_image(through, settings.sensor, mix_seed(settings.seed, stream));
      (frame == 0 ? r.frame_a_ref : r.frame_b_ref) =
          sensor_image(direct, settings.sensor, mix_seed(settings.seed, stream + 1));
      (frame == 0 ? r.radiance_a : r.radiance_b) = through;
      (frame == 0 ? r.radiance_a_ref : r.radiance_b_ref) = direct;
      report(0.55 + 0.25 * (frame * n_cam + k + 1) / (2.0 * n_cam));
    }
  }

  // Truth on each camera's glass-removed view.
  for (int k = 0; k < n_cam; ++k) {
    const ExperimentCamera& cam = cameras[static_cast<std::size_t>(k)];
    ExperimentCameraResult& r = out.cameras[static_cast<std::size_t>(k)];
    CameraTruth& truth = r.truth;
    if (static_cast<std::size_t>(k) < settings.truth_grids.size()) {
      truth.x_px = settings.truth_grids[static_cast<std::size_t>(k)].x_px;
      truth.y_px = settings.truth_grids[static_cast<std::size_t>(k)].y_px;
    }
    if (truth.x_px.empty() || truth.y_px.empty()) {
      truth.x_px.resize(static_cast<std::size_t>(r.width));
      truth.y_px.resize(static_cast<std::size_t>(r.height));
      for (int c = 0; c < r.width; ++c) truth.x_px[static_cast<std::size_t>(c)] = c;
      for (int y = 0; y < r.height; ++y) truth.y_px[static_cast<std::size_t>(y)] = y;
    }
    const std::size_t cols = truth.x_px.size(), rows = truth.y_px.size();
    truth.u_px.assign(cols * rows, std::nan(""));
    truth.v_px.assign(cols * rows, std::nan(""));
    parallel_rows(static_cast<int>(rows), settings.threads, [&](int row) {
      for (std::size_t c = 0; c < cols; ++c) {
        const Eigen::Vector2d pixel(truth.x_px[c], truth.y_px[static_cast<std::size_t>(row)]);
        Eigen::Vector3d p;
        if (!pixel_sheet_point(cam.model, cam.camera_from_world, plane, pixel, &p) || solids.inside(p)) continue;
        const CentredPair pair = centred_pair(flow, plane, p, mid_s, settings.dt_s, settings.rk4_sub_steps);
        const auto a = cam.model.project(cam.camera_from_world.apply(pair.a_mm));
        const auto b = cam.model.project(cam.camera_from_world.apply(pair.b_mm));
        if (!a || !b) continue;
        const std::size_t i = static_cast<std::size_t>(row) * cols + c;
        truth.u_px[i] = (*b - *a).x();
        truth.v_px[i] = (*b - *a).y();
      }
    });
    for (std::size_t i = 0; i < truth.u_px.size(); ++i)
      if (std::isfinite(truth.u_px[i]))
        truth.max_displacement_px = std::max(truth.max_displacement_px, std::hypot(truth.u_px[i], truth.v_px[i]));
    out.max_displacement_px = std::max(out.max_displacement_px, truth.max_displacement_px);
    report(0.8 + 0.15 * (k + 1) / n_cam);
  }

  // Truth on the rectified sheet grid.
  SheetTruth& st = out.sheet_truth;
  st.grid = sheet_grid_covering(plane, px_mm * settings.sheet_truth_step_px);
  const std::size_t cells = st.grid.cell_count();
  for (auto* v : {&st.ds_mm, &st.dt_mm, &st.velocity_s_m_per_s, &st.velocity_t_m_per_s, &st.velocity_n_m_per_s})
    v->assign(cells, std::nan(""));
  parallel_rows(st.grid.rows, settings.threads, [&](int row) {
    for (int c = 0; c < st.grid.cols; ++c) {
      const Eigen::Vector3d p = sheet_point_mm(plane, st.grid.s_mm(c), st.grid.t_mm(row));
      if (solids.inside(p)) continue;
      const CentredPair pair = centred_pair(flow, plane, p, mid_s, settings.dt_s, settings.rk4_sub_steps);
      const Eigen::Vector3d d = pair.b_mm - pair.a_mm, u = flow.velocity_m_per_s(p, mid_s);
      const std::size_t i = static_cast<std::size_t>(row) * st.grid.cols + c;
      st.ds_mm[i] = d.dot(plane.s_axis);
      st.dt_mm[i] = d.dot(plane.t_axis);
      st.velocity_s_m_per_s[i] = u.dot(plane.s_axis);
      st.velocity_t_m_per_s[i] = u.dot(plane.t_axis);
      st.velocity_n_m_per_s[i] = u.dot(plane.normal());
    }
  });

  // The design rules (DESIGN.md section 4).
  if (std::string w = quarter_rule_warning(out.max_displacement_px); !w.empty()) out.warnings.push_back(w);
  if (settings.density_ppp < 0.02 || settings.density_ppp > 0.05)
    out.warnings.push_back(fmt::format("{:g} particles per pixel is outside the 0.02-0.05 of the PIV rule of thumb",
                                       settings.density_ppp));
  if (settings.particle_px < 2 || settings.particle_px > 3)
    out.warnings.push_back(fmt::format("{:g} px particle images are outside 2-3 px: peak locking below 2 px, "
                                       "larger random error above 3 px (Raffel et al. 2018, 6.1)",
                                       settings.particle_px));
  if (settings.keep_maps)
    for (int k = 0; k < n_cam; ++k) {
      out.cameras[static_cast<std::size_t>(k)].map = std::move(maps[k]);
      out.cameras[static_cast<std::size_t>(k)].glass_removed_map = std::move(direct_maps[k]);
    }
  report(1);
  return out;
}

}  // namespace glasspiv
