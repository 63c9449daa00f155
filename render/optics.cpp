#include "render/optics.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace glasspiv {

namespace {
double clamp01(double x) { return std::clamp(x, 0.0, 1.0); }
}  // namespace

Eigen::Vector3d reflect(const Eigen::Vector3d& d, const Eigen::Vector3d& n) { return d - 2.0 * d.dot(n) * n; }

std::optional<Eigen::Vector3d> refract(const Eigen::Vector3d& d, const Eigen::Vector3d& n, double eta_ratio) {
  // Turn the normal to face the incoming ray (against d).
  double cos_i = -d.dot(n);
  const Eigen::Vector3d m = cos_i >= 0 ? n : Eigen::Vector3d(-n);
  cos_i = std::min(std::abs(cos_i), 1.0);
  const double sin2_i = clamp01(1.0 - cos_i * cos_i);
  const double sin2_t = eta_ratio * eta_ratio * sin2_i;
  if (sin2_t > 1.0) return std::nullopt;  // total internal reflection
  const double cos_t = std::sqrt(clamp01(1.0 - sin2_t));
  const Eigen::Vector3d t = eta_ratio * d + (eta_ratio * cos_i - cos_t) * m;
  const double norm = t.norm();
  assert(norm > 0.0);
  return Eigen::Vector3d(t / norm);
}

FresnelReflectance fresnel_dielectric(double cos_incident, double n_i, double n_t) {
  assert(n_i > 0.0 && n_t > 0.0);
  const double cos_i = clamp01(std::abs(cos_incident));
  const double eta = n_i / n_t;
  const double sin2_t = eta * eta * clamp01(1.0 - cos_i * cos_i);
  FresnelReflectance r;
  if (sin2_t > 1.0) {
    r.total_internal_reflection = true;
    return r;
  }
  if (n_i == n_t) {  // index matched: no interface, nothing is reflected
    r.rs = r.rp = 0.0;
    r.unpolarized = 0.0;
    return r;
  }
  const double cos_t = std::sqrt(clamp01(1.0 - sin2_t));
  const double s_num = n_i * cos_i - n_t * cos_t, s_den = n_i * cos_i + n_t * cos_t;
  const double p_num = n_t * cos_i - n_i * cos_t, p_den = n_t * cos_i + n_i * cos_t;
  // With n_i != n_t and no TIR, cos_i and cos_t are never both 0, so the
  // denominators are > 0 (grazing incidence from the rarer side gives R = 1).
  r.rs = (s_num / s_den) * (s_num / s_den);
  r.rp = (p_num / p_den) * (p_num / p_den);
  r.unpolarized = 0.5 * (r.rs + r.rp);
  return r;
}

std::optional<double> critical_angle_rad(double n_i, double n_t) {
  if (!(n_i > n_t)) return std::nullopt;
  return std::asin(n_t / n_i);
}

double beer_lambert_transmittance(double absorption_per_mm, double path_mm) {
  assert(absorption_per_mm >= 0.0 && path_mm >= 0.0);
  return std::exp(-absorption_per_mm * path_mm);
}

}  // namespace glasspiv
