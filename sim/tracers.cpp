#include "sim/tracers.h"

#include <cmath>
#include <stdexcept>

#include "sim/random_variates.h"

namespace glasspiv {
namespace {

constexpr double kMmPerM = 1000.0;

void require(bool ok, const char* what) {
  if (!ok) throw std::invalid_argument(what);
}

}  // namespace

double tracers_per_pixel(double per_mm3, double depth_mm, double mm_per_pixel) {
  return per_mm3 * depth_mm * mm_per_pixel * mm_per_pixel;
}

double tracers_per_mm3(double per_pixel, double depth_mm, double mm_per_pixel) {
  require(depth_mm > 0 && mm_per_pixel > 0, "tracers_per_mm3: depth and pixel size must be > 0");
  return per_pixel / (depth_mm * mm_per_pixel * mm_per_pixel);
}

std::vector<Eigen::Vector3d> seed_tracers_mm(const Sheet& sheet, const TracerSeeding& seeding,
                                             const SolidInteriors& solids) {
  require(std::isfinite(seeding.per_mm3) && seeding.per_mm3 >= 0, "seed_tracers_mm: per_mm3 must be finite and >= 0");
  require(std::isfinite(seeding.half_depth_sigmas) && seeding.half_depth_sigmas > 0,
          "seed_tracers_mm: half_depth_sigmas must be > 0");
  require(std::isfinite(seeding.margin_mm) && seeding.margin_mm >= 0, "seed_tracers_mm: margin_mm must be >= 0");
  const double half_s_mm = sheet.extent_mm[0] / 2 + seeding.margin_mm;
  const double half_t_mm = sheet.extent_mm[1] / 2 + seeding.margin_mm;
  const double half_n_mm = seeding.half_depth_sigmas * sheet.sigma_mm();
  const double volume_mm3 = 8 * half_s_mm * half_t_mm * half_n_mm;
  const double expected = seeding.per_mm3 * volume_mm3;
  require(std::isfinite(expected) && expected <= kMaxTracers, "seed_tracers_mm: more tracers than kMaxTracers");
  const Eigen::Vector3d normal = sheet.normal();

  RandomVariates random(seeding.seed);
  const std::uint64_t count = random.poisson(expected);
  std::vector<Eigen::Vector3d> tracers_mm;
  tracers_mm.reserve(static_cast<std::size_t>(count));
  for (std::uint64_t i = 0; i < count; ++i) {
    // Three draws per candidate whatever happens to it, so the candidates do
    // not depend on the solids.
    const double s = random.uniform(-half_s_mm, half_s_mm);
    const double t = random.uniform(-half_t_mm, half_t_mm);
    const double n = random.uniform(-half_n_mm, half_n_mm);
    const Eigen::Vector3d p = sheet.origin_mm + s * sheet.s_axis + t * sheet.t_axis + n * normal;
    if (!solids.inside(p)) tracers_mm.push_back(p);
  }
  return tracers_mm;
}

Eigen::Vector3d advect_rk4_mm(const Flow& flow, const Eigen::Vector3d& point_mm, double time_s, double dt_s,
                              int sub_steps) {
  require(sub_steps >= 1, "advect_rk4_mm: sub_steps must be >= 1");
  require(std::isfinite(time_s) && std::isfinite(dt_s), "advect_rk4_mm: times must be finite");
  // dx/dt in mm/s = 1000 u (m/s).
  const auto rate_mm_per_s = [&](const Eigen::Vector3d& p_mm, double t_s) -> Eigen::Vector3d {
    return kMmPerM * flow.velocity_m_per_s(p_mm, t_s);
  };
  const double h_s = dt_s / sub_steps;
  Eigen::Vector3d p_mm = point_mm;
  for (int k = 0; k < sub_steps; ++k) {
    const double t_s = time_s + k * h_s;
    const Eigen::Vector3d k1 = rate_mm_per_s(p_mm, t_s);
    const Eigen::Vector3d k2 = rate_mm_per_s(p_mm + 0.5 * h_s * k1, t_s + 0.5 * h_s);
    const Eigen::Vector3d k3 = rate_mm_per_s(p_mm + 0.5 * h_s * k2, t_s + 0.5 * h_s);
    const Eigen::Vector3d k4 = rate_mm_per_s(p_mm + h_s * k3, t_s + h_s);
    p_mm += (h_s / 6) * (k1 + 2 * k2 + 2 * k3 + k4);
  }
  return p_mm;
}

TracerFrames advect_tracers(const Flow& flow, const std::vector<Eigen::Vector3d>& frame_a_mm, double time_a_s,
                            double dt_s, int sub_steps) {
  require(sub_steps >= 1, "advect_tracers: sub_steps must be >= 1");
  require(std::isfinite(time_a_s) && std::isfinite(dt_s), "advect_tracers: times must be finite");
  TracerFrames frames;
  frames.time_a_s = time_a_s;
  frames.dt_s = dt_s;
  frames.frame_a_mm = frame_a_mm;
  frames.frame_b_mm.reserve(frame_a_mm.size());
  for (const Eigen::Vector3d& p : frame_a_mm)
    frames.frame_b_mm.push_back(advect_rk4_mm(flow, p, time_a_s, dt_s, sub_steps));
  return frames;
}

double sheet_relative_intensity(const Sheet& sheet, const Eigen::Vector3d& point_mm) {
  const double z_mm = (point_mm - sheet.origin_mm).dot(sheet.normal());
  const double sigma_mm = sheet.sigma_mm();
  return std::exp(-(z_mm * z_mm) / (2 * sigma_mm * sigma_mm));
}

std::vector<double> sheet_relative_intensities(const Sheet& sheet, const std::vector<Eigen::Vector3d>& points_mm) {
  std::vector<double> out;
  out.reserve(points_mm.size());
  for (const Eigen::Vector3d& p : points_mm) out.push_back(sheet_relative_intensity(sheet, p));
  return out;
}

}  // namespace glasspiv
