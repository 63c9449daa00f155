#pragma once
// Which parts of a measurement survive the model's uncertainty: how far the
// sheet point seen by a pixel, and the image of a sheet point, move when the
// camera pose, the glass positions, the sphere diameters and the refractive
// index vary within their tolerances. Double precision, mm, px. No I/O.
//
// Sampling: a grid of pixels, one per grid_step_px x grid_step_px block (at
// the block's centre). At each, the nominal model's direct crossing (the
// highest-weight crossing of the refracted-only path: reflections are off) is
// held against the perturbed models' crossings of the same pixel:
// - displacement_mm: |(s, t)_perturbed - (s, t)_nominal|, the sheet point a fixed
//   pixel sees moving on the sheet;
// - displacement_px: |dst_dpixel^-1 ((s, t)_perturbed - (s, t)_nominal)|, to
//   first order how far the image of the fixed sheet point moves (the nominal
//   footprint Jacobian from the tracer's ray differentials turns mm into px).
//
// Methods:
// - first_order (default): one parameter at a time, central differences at
//   +-1 sigma, g_k = (X(+sigma_k) - X(-sigma_k)) / 2, combined in quadrature:
//   RMS = sqrt(sum_k |g_k|^2), exact for a model linear in independent Gaussian
//   parameters. Deterministic, 2 traces per parameter and grid point, and the
//   per-parameter contributions come with it. Chosen as the default because
//   the tolerances are small (the maps are close to linear in them) and a
//   caller differentiating or comparing maps wants no sampling noise.
// - monte_carlo: `samples` models with every parameter drawn at once from its
//   Gaussian (Box-Muller on std::mt19937_64, so the draws are the same on every
//   platform for a seed); RMS over the samples. It shows what first order
//   misses where the maps are strongly non-linear (sphere rims). The
//   per-parameter table is still first order.
//
// What is perturbed: glass Spheres, Boxes (slabs) and Cylinders move together;
// glass meshes are not moved (a TriangleMesh is immutable; they are counted in
// skipped_glass_meshes). Sphere diameters: every glass sphere by the same
// amount, centres kept (a touching packing then overlaps or opens by that
// amount; the tracer's geometric medium rule handles the contacts). The index:
// every glass solid by the same amount; the fluid's index is kept. Opaque
// solids and the sheet stay where they are.
#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "calib/camera_model.h"
#include "calib/rigid_transform.h"
#include "render/path_tracer.h"

namespace glasspiv {

// Limits of the tolerances: a 1-sigma camera rotation beyond this is no small
// change (docs/limits.md); the contact overlap a sphere diameter change may
// make between touching spheres, as a fraction of the smallest sphere's
// diameter (see invalid models below).
constexpr double kMaxRotationToleranceDeg = 10;
constexpr double kMaxContactOverlap = 0.01;

// What makes a sensitivity unmeasurable: `tolerance` names the ModelTolerances
// field at fault ("refractive_index", "pose_covariance", ...), or is "" when the
// camera or the tolerances together are (a camera that sees no sheet, a Monte
// Carlo draw, every tolerance 0), so that a command can name its option.
class SensitivityError : public std::invalid_argument {
 public:
  SensitivityError(std::string tolerance, const std::string& problem)
      : std::invalid_argument(problem), tolerance_(std::move(tolerance)) {}
  const std::string& tolerance() const { return tolerance_; }

 private:
  std::string tolerance_;
};

// 1-sigma of independent Gaussian errors. A zero figure leaves its parameter out.
struct ModelTolerances {
  double camera_position_mm = 0.1;    // camera centre, along each world axis
  double camera_rotation_deg = 0.02;  // about each camera axis, around the camera centre
  double glass_position_mm = 0.05;    // every glass solid moved together, along each world axis
  double sphere_diameter_mm = 0.02;   // every glass sphere's diameter, together
  double refractive_index = 5e-4;     // every glass solid's index, together
  // Covariance of (angle-axis rad, translation mm) of camera_from_world, as a
  // pose fit reports it (perturbed as rvec + d_rvec, t + d_t along its
  // eigenvectors); replaces camera_position_mm and camera_rotation_deg.
  std::optional<Eigen::Matrix<double, 6, 6>> pose_covariance;
};

enum class SensitivityMethod { first_order, monte_carlo };

struct SensitivityOptions {
  SensitivityMethod method = SensitivityMethod::first_order;
  int grid_step_px = 8;                  // one sample per block of this many pixels square
  int threads = 0;                       // <= 0: hardware concurrency (render/parallel_rows.h)
  TraceOptions trace{false, 1e-12, 32};  // reflections forced off: the direct crossing only
};

// One parameter's first-order contribution: the displacement for a 1-sigma change.
struct SensitivityParameter {
  std::string name;  // camera_rotation_x|y|z, camera_position_x|y|z, pose_mode_0..5, glass_position_x|y|z,
                     // sphere_diameter, refractive_index
  double sigma = 0;  // its 1-sigma in the unit its name implies (deg, mm, 1; pose modes: 1 = one standard deviation)
  std::vector<float> displacement_px, displacement_mm;          // per grid point (0 where invalid)
  double median_px = 0, p95_px = 0, median_mm = 0, p95_mm = 0;  // over the valid grid points
};

struct SensitivityMap {
  int width = 0, height = 0;  // grid size: floor(image size / grid_step_px), at least 1
  int grid_step_px = 0;
  // RMS displacements per grid point, row-major (index = row * width + col).
  std::vector<float> displacement_px;  // of the image of the sheet point
  std::vector<float> displacement_mm;  // of the sheet point a fixed pixel sees
  // 1 where the nominal and every perturbed model (first_order: all +-1 sigma
  // models; monte_carlo: those too and every sample) have a direct crossing.
  std::vector<unsigned char> valid;
  std::vector<SensitivityParameter> parameters;
  int valid_points = 0;
  double median_px = 0, p95_px = 0, median_mm = 0, p95_mm = 0;  // of the totals, over valid points
  // Solids the glass parameters act on (moved, index changed), spheres resized, glass meshes left alone.
  int glass_solids_moved = 0, spheres_resized = 0, skipped_glass_meshes = 0;

  // The pixel sampled by grid point (col, row): the centre of its block.
  Eigen::Vector2d pixel_px(int col, int row) const {
    return {(col + 0.5) * grid_step_px - 0.5, (row + 0.5) * grid_step_px - 0.5};
  }
};

// samples and seed are used by monte_carlo only (samples >= 2 there). Throws
// std::invalid_argument for grid_step_px < 1 or too few samples, and
// SensitivityError (before any trace) for negative or non-finite tolerances, a
// rotation tolerance over kMaxRotationToleranceDeg, a pose_covariance that is
// not symmetric positive semi-definite, every tolerance 0, and a perturbed
// model (+-1 sigma, or a Monte Carlo draw) that is not a valid scene: a glass
// index outside [kMinRefractiveIndex, kMaxRefractiveIndex], a sphere under
// kMinSceneSize_mm across, the camera or glass beyond kMaxSceneCoordinate_mm,
// solids overlapping (touching spheres grown by at most kMaxContactOverlap of
// the smallest diameter count as touching); and (after the traces) when no
// sample point sees the sheet in the nominal model, or none keeps its view in
// every perturbed one (naming the parameter that loses the most).
SensitivityMap model_sensitivity(const TraceScene& scene, const CameraModel& model,
                                 const RigidTransform& camera_from_world, const ModelTolerances& tol, int samples,
                                 std::uint64_t seed, const SensitivityOptions& options = {});

}  // namespace glasspiv
