#pragma once
// Geometric optics at a smooth interface between two dielectrics: mirror
// reflection, Snell refraction, Fresnel power reflectances, the critical angle
// and Beer-Lambert absorption. Pure functions in double precision.
//
// Conventions (see docs/materials.md):
// - Directions are unit vectors along the propagation of light: `d` points
//   *towards* the surface, the returned direction points away from it.
// - A surface normal `n` is a unit vector and may face either way: the
//   functions use the side the ray comes from, so a caller need not orient it.
// - `eta_ratio` = n_incident / n_transmitted, where "incident" is the medium the
//   ray travels in before the interface, whatever the normal's orientation.
// - Angles are measured from the normal, 0 = normal incidence, pi/2 = grazing.
#include <Eigen/Core>
#include <optional>

namespace glasspiv {

// Law of reflection: the angle of reflection equals the angle of incidence and
// the tangential component is kept, r = d - 2 (d . n) n. Valid for either
// orientation of n (the formula is even in n). |r| = |d|.
Eigen::Vector3d reflect(const Eigen::Vector3d& d, const Eigen::Vector3d& n);

// Snell's law in vector form, n_i sin(theta_i) = n_t sin(theta_t), with the
// refracted ray in the plane of d and n. With m the normal turned to face the
// incoming ray (m = n if d . n < 0, else -n), cos_i = -d . m, eta = eta_ratio:
//   sin^2(theta_t) = eta^2 (1 - cos_i^2)
//   t = eta d + (eta cos_i - cos_t) m,   cos_t = sqrt(1 - sin^2(theta_t)).
// Returns std::nullopt on total internal reflection, sin^2(theta_t) > 1. At
// exactly sin^2(theta_t) = 1 it returns the grazing (tangential) direction.
// cos_i^2 and cos_t^2 are clamped to [0, 1], so grazing incidence and the
// critical angle give finite unit vectors, never NaN. The result is
// renormalised to unit length.
std::optional<Eigen::Vector3d> refract(const Eigen::Vector3d& d, const Eigen::Vector3d& n, double eta_ratio);

struct FresnelReflectance {
  double rs = 1;           // power reflectance, s polarisation (E perpendicular to the plane of incidence)
  double rp = 1;           // power reflectance, p polarisation (E in the plane of incidence)
  double unpolarized = 1;  // (rs + rp) / 2, natural (unpolarised) light
  bool total_internal_reflection = false;
};

// Fresnel equations for a smooth dielectric interface (no absorption), power
// reflectances as the squares of the amplitude coefficients:
//   rs = ((n_i cos_i - n_t cos_t) / (n_i cos_i + n_t cos_t))^2
//   rp = ((n_t cos_i - n_i cos_t) / (n_t cos_i + n_i cos_t))^2
// with cos_t from Snell's law. The transmitted power fraction is 1 - R (energy
// conservation). cos_incident is the cosine of the angle of incidence; its sign
// is ignored (n_i names the incident side explicitly) and it is clamped to
// [0, 1]. Total internal reflection (sin^2(theta_t) > 1, the same test refract
// uses) gives rs = rp = 1 with the flag set; n_i == n_t (index matched, no
// interface) gives 0.
FresnelReflectance fresnel_dielectric(double cos_incident, double n_i, double n_t);

// Both at one interface, sharing the cosine of refraction: to the bit
// fresnel_dielectric(d . n, n_i, n_t) and refract(d, n, n_i / n_t), the
// direction empty on total internal reflection (the tracer's one call per
// interface).
struct Refraction {
  FresnelReflectance reflectance;
  std::optional<Eigen::Vector3d> direction;
};
Refraction refract_with_fresnel(const Eigen::Vector3d& d, const Eigen::Vector3d& n, double n_i, double n_t);

// Critical angle of total internal reflection, theta_c = asin(n_t / n_i), for
// light going from the denser medium n_i into n_t. std::nullopt when
// n_i <= n_t: no angle of incidence is totally reflected.
std::optional<double> critical_angle_rad(double n_i, double n_t);

// Beer-Lambert law, T = exp(-alpha L): the fraction of power left after a path
// of L mm through a medium with the (natural-log, not decadic) attenuation
// coefficient alpha in 1/mm. Both must be >= 0.
double beer_lambert_transmittance(double absorption_per_mm, double path_mm);

}  // namespace glasspiv
