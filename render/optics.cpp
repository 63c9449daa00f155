#include "render/optics.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace glasspiv {

namespace {

double clamp01(double x) { return std::clamp(x, 0.0, 1.0); }

// sin^2 of the refraction angle from cos_i in [0, 1] (Snell's law).
double sin2_transmitted(double cos_i, double eta) { return eta * eta * clamp01(1.0 - cos_i * cos_i); }

// cos_t where sin2_t <= 1.
double cos_transmitted(double sin2_t) { return std::sqrt(clamp01(1.0 - sin2_t)); }

// The Fresnel equations without total internal reflection.
FresnelReflectance fresnel_of_cosines(double cos_i, double cos_t, double n_i, double n_t) {
  FresnelReflectance r;
  if (n_i == n_t) {  // index matched: no interface, nothing is reflected
    r.rs = r.rp = 0.0;
    r.unpolarized = 0.0;
    return r;
  }
  const double s_num = n_i * cos_i - n_t * cos_t, s_den = n_i * cos_i + n_t * cos_t;
  const double p_num = n_t * cos_i - n_i * cos_t, p_den = n_t * cos_i + n_i * cos_t;
  // With n_i != n_t and no TIR, cos_i and cos_t are never both 0, so the
  // denominators are > 0 (grazing incidence from the rarer side gives R = 1).
  r.rs = (s_num / s_den) * (s_num / s_den);
  r.rp = (p_num / p_den) * (p_num / p_den);
  r.unpolarized = 0.5 * (r.rs + r.rp);
  return r;
}

// The normal turned to face the incoming ray (against d), and cos_i = -d . m
// clamped to [0, 1].
struct Incidence {
  Eigen::Vector3d m;
  double cos_i;
};
Incidence incidence(const Eigen::Vector3d& d, const Eigen::Vector3d& n) {
  const double cos_i = -d.dot(n);
  return {cos_i >= 0 ? n : Eigen::Vector3d(-n), std::min(std::abs(cos_i), 1.0)};
}

// The unit refracted direction, m the normal facing the ray.
Eigen::Vector3d refracted_direction(const Eigen::Vector3d& d, const Eigen::Vector3d& m, double eta, double cos_i,
                                    double cos_t) {
  const Eigen::Vector3d t = eta * d + (eta * cos_i - cos_t) * m;
  const double norm = t.norm();
  assert(norm > 0.0);
  return t / norm;
}

}  // namespace

Eigen::Vector3d reflect(const Eigen::Vector3d& d, const Eigen::Vector3d& n) { return d - 2.0 * d.dot(n) * n; }

std::optional<Eigen::Vector3d> refract(const Eigen::Vector3d& d, const Eigen::Vector3d& n, double eta_ratio) {
  const Incidence in = incidence(d, n);
  const double sin2_t = sin2_transmitted(in.cos_i, eta_ratio);
  if (sin2_t > 1.0) return std::nullopt;  // total internal reflection
  return refracted_direction(d, in.m, eta_ratio, in.cos_i, cos_transmitted(sin2_t));
}

FresnelReflectance fresnel_dielectric(double cos_incident, double n_i, double n_t) {
  assert(n_i > 0.0 && n_t > 0.0);
  const double cos_i = clamp01(std::abs(cos_incident));
  const double sin2_t = sin2_transmitted(cos_i, n_i / n_t);
  if (sin2_t > 1.0) {
    FresnelReflectance r;
    r.total_internal_reflection = true;
    return r;
  }
  return fresnel_of_cosines(cos_i, cos_transmitted(sin2_t), n_i, n_t);
}

Refraction refract_with_fresnel(const Eigen::Vector3d& d, const Eigen::Vector3d& n, double n_i, double n_t) {
  assert(n_i > 0.0 && n_t > 0.0);
  const Incidence in = incidence(d, n);
  const double eta = n_i / n_t;
  const double sin2_t = sin2_transmitted(in.cos_i, eta);
  Refraction out;
  if (sin2_t > 1.0) {
    out.reflectance.total_internal_reflection = true;
    return out;
  }
  const double cos_t = cos_transmitted(sin2_t);
  out.reflectance = fresnel_of_cosines(in.cos_i, cos_t, n_i, n_t);
  out.direction = refracted_direction(d, in.m, eta, in.cos_i, cos_t);
  return out;
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
