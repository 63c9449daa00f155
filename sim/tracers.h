#pragma once
// Tracer particles of a simulated PIV experiment: seeded at random in the
// light-sheet slab outside the solids, carried by a Flow with RK4 over the
// pulse separation, and lit by the sheet's Gaussian profile (docs/simulation.md).
// Positions in mm, world frame; times in s; velocities (sim/flows.h) in m/s. No I/O.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "render/scene.h"
#include "sim/flows.h"

namespace glasspiv {

// Where and how densely tracers are seeded: uniformly (a Poisson process of
// per_mm3) in the slab |n . (p - origin)| <= half_depth_sigmas * sheet.sigma_mm()
// over the sheet's extent grown by margin_mm on every side (so that tracers can
// flow into the field of view between the frames), minus the solids' interiors.
struct TracerSeeding {
  double per_mm3 = 0;
  double half_depth_sigmas = 3;  // at 3 sigma the sheet's intensity is exp(-4.5) = 1.1 %
  double margin_mm = 0;
  std::uint64_t seed = 1;
};

// The most tracers one seeding may make (std::invalid_argument beyond).
constexpr double kMaxTracers = 1e8;

// Particles per pixel of an undistorted view of mm_per_pixel (at the sheet),
// counting the tracers in a depth depth_mm of the sheet: ppp = C dz (mm/px)^2.
// The PIV rule of thumb (0.02-0.05 ppp) counts the sheet's thickness
// (Sheet::thickness_mm, 1/e^2 full width = 4 sigma); pass the seeded depth
// (2 half_depth_sigmas sigma) to count every tracer seeded.
double tracers_per_pixel(double per_mm3, double depth_mm, double mm_per_pixel);
// The inverse: per mm^3 from per pixel.
double tracers_per_mm3(double per_pixel, double depth_mm, double mm_per_pixel);

// Seeds tracers as TracerSeeding says (solids may be empty). Reproducible from
// seeding.seed on every platform (sim/random_variates.h): the count is Poisson of
// per_mm3 times the slab's volume, the places uniform, those inside a solid
// dropped. Throws std::invalid_argument for a negative or non-finite density,
// half_depth_sigmas <= 0, margin_mm < 0, or more than kMaxTracers expected.
std::vector<Eigen::Vector3d> seed_tracers_mm(const Sheet& sheet, const TracerSeeding& seeding,
                                             const SolidInteriors& solids);

// The position at time_s + dt_s of the tracer at point_mm at time_s: classical
// fourth-order Runge-Kutta with sub_steps equal steps (dt_s may be negative).
// Global error O((dt / sub_steps)^4) for a smooth flow.
Eigen::Vector3d advect_rk4_mm(const Flow& flow, const Eigen::Vector3d& point_mm, double time_s, double dt_s,
                              int sub_steps);

// Tracers in frames A (time_a_s) and B (time_a_s + dt_s), in the same order; the
// exact displacement is frame_b_mm[i] - frame_a_mm[i], out-of-plane part included
// (tracers that leave the slab are kept: their intensity fades).
struct TracerFrames {
  double time_a_s = 0;
  double dt_s = 0;
  std::vector<Eigen::Vector3d> frame_a_mm;
  std::vector<Eigen::Vector3d> frame_b_mm;
};

// advect_rk4_mm for every tracer. Throws std::invalid_argument for sub_steps < 1
// or a non-finite time.
TracerFrames advect_tracers(const Flow& flow, const std::vector<Eigen::Vector3d>& frame_a_mm, double time_a_s,
                            double dt_s, int sub_steps);

// A tracer's intensity relative to one on the sheet's plane: the Gaussian
// profile exp(-z^2 / (2 sigma^2)), z = (p - origin) . normal, sigma = Sheet::sigma_mm()
// (1/e^2 at z = +-thickness/2). It ignores the sheet's in-plane extent.
double sheet_relative_intensity(const Sheet& sheet, const Eigen::Vector3d& point_mm);
std::vector<double> sheet_relative_intensities(const Sheet& sheet, const std::vector<Eigen::Vector3d>& points_mm);

}  // namespace glasspiv
