#include "align/sensitivity.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <fmt/format.h>
#include <memory>
#include <random>
#include <stdexcept>
#include <type_traits>
#include <utility>
#include <variant>

#include "render/overlap.h"
#include "render/parallel_rows.h"
#include "render/scene.h"
#include "render/trace_scene_builder.h"

namespace glasspiv {

namespace {

constexpr double kPi = 3.14159265358979323846;
using Vector6d = Eigen::Matrix<double, 6, 1>;

// One change of the model; parameters are unit (1-sigma) perturbations, a
// Monte Carlo sample their Gaussian combination.
struct Perturbation {
  Eigen::Vector3d camera_rotation_rad = Eigen::Vector3d::Zero();  // about the camera axes
  Eigen::Vector3d camera_position_mm = Eigen::Vector3d::Zero();   // world axes
  Vector6d pose_delta = Vector6d::Zero();                         // (d rvec, d t) of camera_from_world
  Eigen::Vector3d glass_shift_mm = Eigen::Vector3d::Zero();
  double diameter_change_mm = 0;
  double index_change = 0;

  Perturbation& add(const Perturbation& o, double f) {
    camera_rotation_rad += f * o.camera_rotation_rad;
    camera_position_mm += f * o.camera_position_mm;
    pose_delta += f * o.pose_delta;
    glass_shift_mm += f * o.glass_shift_mm;
    diameter_change_mm += f * o.diameter_change_mm;
    index_change += f * o.index_change;
    return *this;
  }
  bool moves_geometry() const { return !glass_shift_mm.isZero(0) || diameter_change_mm != 0; }
};

struct Parameter {
  std::string name;
  double sigma = 0;
  Perturbation unit;
  std::string tolerance;  // the ModelTolerances field it comes from
};

struct Model {
  std::shared_ptr<const TraceScene> scene;
  std::shared_ptr<const SceneIndex> index;
  RigidTransform camera_from_world;
};

struct Counts {
  int glass = 0, spheres = 0, meshes = 0;
};

Counts count_glass(const TraceScene& scene) {
  Counts c;
  for (const TraceSolid& s : scene.solids) {
    if (s.material.kind != TraceMaterial::Kind::glass) continue;
    if (std::holds_alternative<TriangleMesh>(s.shape)) {
      ++c.meshes;
      continue;
    }
    ++c.glass;
    if (std::holds_alternative<Sphere>(s.shape)) ++c.spheres;
  }
  return c;
}

RigidTransform perturbed_pose(const RigidTransform& nominal, const Perturbation& p) {
  RigidTransform pose = nominal;
  const double angle = p.camera_rotation_rad.norm();
  if (angle > 0) {
    // About the camera centre: R' = dR R, t' = dR t keeps -R'^T t' = -R^T t.
    const Eigen::Matrix3d d_r = Eigen::AngleAxisd(angle, p.camera_rotation_rad / angle).toRotationMatrix();
    pose.rotation = d_r * pose.rotation;
    pose.translation_mm = d_r * pose.translation_mm;
  }
  if (!p.camera_position_mm.isZero(0)) {
    const Eigen::Vector3d centre = -pose.rotation.transpose() * pose.translation_mm + p.camera_position_mm;
    pose.translation_mm = -pose.rotation * centre;
  }
  if (!p.pose_delta.isZero(0))
    pose = RigidTransform::from_rvec_tvec(pose.rvec() + p.pose_delta.head<3>(),
                                          pose.translation_mm + p.pose_delta.tail<3>());
  return pose;
}

// The scene with the glass moved, resized and re-indexed as p says.
Model perturbed_model(const std::shared_ptr<const TraceScene>& nominal_scene,
                      const std::shared_ptr<const SceneIndex>& nominal_index, const RigidTransform& nominal_pose,
                      const Perturbation& p) {
  Model m{nominal_scene, nominal_index, perturbed_pose(nominal_pose, p)};
  if (!p.moves_geometry() && p.index_change == 0) return m;
  auto scene = std::make_shared<TraceScene>(*nominal_scene);
  for (TraceSolid& s : scene->solids) {
    if (s.material.kind != TraceMaterial::Kind::glass) continue;
    s.material.refractive_index += p.index_change;
    std::visit(
        [&](auto& shape) {
          using T = std::decay_t<decltype(shape)>;
          if constexpr (std::is_same_v<T, Sphere>) {
            shape.centre_mm += p.glass_shift_mm;
            shape.radius_mm += 0.5 * p.diameter_change_mm;
          } else if constexpr (std::is_same_v<T, Box> || std::is_same_v<T, Cylinder>) {
            shape.centre_mm += p.glass_shift_mm;
          }
        },
        s.shape);
  }
  m.scene = scene;
  if (p.moves_geometry()) m.index = make_scene_index(*scene);
  return m;
}

// Why a perturbed model is not one the tracer may trace ("" when it is): it
// must be a scene the scene reader would accept. Every glass index within
// [kMinRefractiveIndex, kMaxRefractiveIndex] (the optics need n > 0), every
// sphere at least kMinSceneSize_mm across, the camera and the glass within
// +-kMaxSceneCoordinate_mm, and no two solids overlapping: resizing spheres that
// touch overlaps them by the diameter change, which the tracer's contact rule
// takes as a contact only while it is at most kMaxContactOverlap of the
// smallest sphere's diameter; anything else (glass moved into another solid)
// is an overlap.
std::string invalid_model(const Model& m, const Perturbation& p) {
  const Eigen::Vector3d centre = -(m.camera_from_world.rotation.transpose() * m.camera_from_world.translation_mm);
  if (!centre.allFinite() || centre.cwiseAbs().maxCoeff() > kMaxSceneCoordinate_mm ||
      !m.camera_from_world.rotation.allFinite())
    return fmt::format("puts the camera at ({:.4g}, {:.4g}, {:.4g}) mm, beyond the scene's +-{:g} mm", centre.x(),
                       centre.y(), centre.z(), kMaxSceneCoordinate_mm);
  double smallest_diameter = INFINITY;
  for (const TraceSolid& s : m.scene->solids) {
    if (s.material.kind != TraceMaterial::Kind::glass) continue;
    const double n = s.material.refractive_index;
    if (!(n >= kMinRefractiveIndex && n <= kMaxRefractiveIndex))
      return fmt::format("gives the glass the refractive index {:.6g}, outside [{:g}, {:g}]", n, kMinRefractiveIndex,
                         kMaxRefractiveIndex);
    bool inside = true;
    std::visit(
        [&](const auto& shape) {
          using T = std::decay_t<decltype(shape)>;
          if constexpr (!std::is_same_v<T, TriangleMesh>)
            inside = shape.centre_mm.cwiseAbs().maxCoeff() <= kMaxSceneCoordinate_mm;
        },
        s.shape);
    if (!inside) return fmt::format("moves the glass beyond the scene's +-{:g} mm", kMaxSceneCoordinate_mm);
    if (const Sphere* sphere = std::get_if<Sphere>(&s.shape)) {
      const double d = 2 * sphere->radius_mm;
      if (!(d >= kMinSceneSize_mm))
        return fmt::format("makes a glass sphere {:.6g} mm across, below {:g} mm", d, kMinSceneSize_mm);
      smallest_diameter = std::min(smallest_diameter, d);
    }
  }
  if (!p.moves_geometry()) return "";
  const double growth_mm = std::max(0.0, p.diameter_change_mm);
  const double nominal_smallest_mm = smallest_diameter - p.diameter_change_mm;
  if (growth_mm > kMaxContactOverlap * nominal_smallest_mm)
    return fmt::format("grows the spheres by {:.4g} mm, so that touching ones overlap by more than {:g} of the "
                       "smallest ({:.4g} mm across)",
                       growth_mm, kMaxContactOverlap, nominal_smallest_mm);
  std::vector<Shape> shapes;
  shapes.reserve(m.scene->solids.size());
  for (const TraceSolid& s : m.scene->solids) shapes.push_back(s.shape);
  if (const auto pair = find_overlap(shapes, kSphereOverlapTolerance_mm + growth_mm))
    return fmt::format("makes solid {} overlap solid {} (the tracer needs solids that at most touch)", pair->first,
                       pair->second);
  return "";
}

std::vector<Parameter> parameters_of(const ModelTolerances& tol) {
  std::vector<Parameter> out;
  const char* axes = "xyz";
  auto add = [&](std::string name, double sigma, Perturbation unit, const char* tolerance) {
    if (sigma > 0) out.push_back({std::move(name), sigma, unit, tolerance});
  };
  if (tol.pose_covariance) {
    const Eigen::Matrix<double, 6, 6>& c = *tol.pose_covariance;
    if (!c.allFinite() || (c - c.transpose()).cwiseAbs().maxCoeff() > 1e-12 * std::max(1.0, c.cwiseAbs().maxCoeff()))
      throw SensitivityError("pose_covariance", "must be finite and symmetric");
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eig(c);
    const double largest = eig.eigenvalues().cwiseAbs().maxCoeff();
    for (int i = 0; i < 6; ++i) {
      const double lambda = eig.eigenvalues()[i];
      if (lambda < -1e-12 * largest)
        throw SensitivityError("pose_covariance", "is not positive semi-definite");
      if (!(lambda > 0)) continue;
      Perturbation u;
      u.pose_delta = std::sqrt(lambda) * eig.eigenvectors().col(i);
      add("pose_mode_" + std::to_string(i), 1.0, u, "pose_covariance");
    }
  } else {
    for (int a = 0; a < 3; ++a) {
      Perturbation u;
      u.camera_rotation_rad[a] = tol.camera_rotation_deg * kPi / 180;
      add(std::string("camera_rotation_") + axes[a], tol.camera_rotation_deg, u, "camera_rotation_deg");
    }
    for (int a = 0; a < 3; ++a) {
      Perturbation u;
      u.camera_position_mm[a] = tol.camera_position_mm;
      add(std::string("camera_position_") + axes[a], tol.camera_position_mm, u, "camera_position_mm");
    }
  }
  for (int a = 0; a < 3; ++a) {
    Perturbation u;
    u.glass_shift_mm[a] = tol.glass_position_mm;
    add(std::string("glass_position_") + axes[a], tol.glass_position_mm, u, "glass_position_mm");
  }
  Perturbation d;
  d.diameter_change_mm = tol.sphere_diameter_mm;
  add("sphere_diameter", tol.sphere_diameter_mm, d, "sphere_diameter_mm");
  Perturbation n;
  n.index_change = tol.refractive_index;
  add("refractive_index", tol.refractive_index, n, "refractive_index");
  return out;
}

struct Crossing {
  bool ok = false;
  Eigen::Vector2d st_mm = Eigen::Vector2d::Zero();
  Eigen::Matrix2d dst_dpixel = Eigen::Matrix2d::Zero();
};

// The direct crossing: the highest-weight one of the refracted-only path (the first on a tie).
Crossing direct_crossing(const Model& m, const CameraModel& camera, const Eigen::Vector2d& pixel,
                         const TraceOptions& trace, TraceResult* result) {
  Crossing c;
  const std::optional<CameraRay> ray = pixel_camera_ray(camera, m.camera_from_world, pixel);
  if (!ray) return c;
  trace_ray(*m.scene, *m.index, *ray, trace, result);
  const SheetCrossing* best = nullptr;
  for (const SheetCrossing& x : result->crossings)
    if (x.tag != CrossingTag::with_reflections && (!best || x.weight > best->weight)) best = &x;
  if (!best) return c;
  c.ok = true;
  c.st_mm = Eigen::Vector2d(best->s_mm, best->t_mm);
  c.dst_dpixel = best->dst_dpixel;
  return c;
}

// Linear-interpolated quantile of the values (0 for none).
double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const std::size_t i = static_cast<std::size_t>(pos);
  if (i + 1 >= v.size()) return v.back();
  return v[i] + (pos - static_cast<double>(i)) * (v[i + 1] - v[i]);
}

void summarise(const std::vector<float>& px, const std::vector<float>& mm, const std::vector<unsigned char>& valid,
               double* median_px, double* p95_px, double* median_mm, double* p95_mm) {
  std::vector<double> a, b;
  for (std::size_t i = 0; i < valid.size(); ++i)
    if (valid[i]) {
      a.push_back(px[i]);
      b.push_back(mm[i]);
    }
  *median_px = quantile(a, 0.5);
  *p95_px = quantile(a, 0.95);
  *median_mm = quantile(b, 0.5);
  *p95_mm = quantile(std::move(b), 0.95);
}

// Standard normal draws from mt19937_64 by Box-Muller: the same numbers on every
// platform (std::normal_distribution's algorithm is not specified).
class NormalDraws {
 public:
  explicit NormalDraws(std::uint64_t seed) : rng_(seed) {}
  double next() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    // u1 in (0, 1], u2 in [0, 1) from the top 53 bits.
    const double u1 = (static_cast<double>(rng_() >> 11) + 1.0) * 0x1.0p-53;
    const double u2 = static_cast<double>(rng_() >> 11) * 0x1.0p-53;
    const double r = std::sqrt(-2 * std::log(u1));
    spare_ = r * std::sin(2 * kPi * u2);
    has_spare_ = true;
    return r * std::cos(2 * kPi * u2);
  }

 private:
  std::mt19937_64 rng_;
  double spare_ = 0;
  bool has_spare_ = false;
};

}  // namespace

SensitivityMap model_sensitivity(const TraceScene& scene, const CameraModel& model,
                                 const RigidTransform& camera_from_world, const ModelTolerances& tol, int samples,
                                 std::uint64_t seed, const SensitivityOptions& options) {
  if (options.grid_step_px < 1) throw std::invalid_argument("model_sensitivity: grid_step_px must be at least 1");
  const std::pair<const char*, double> tolerances[] = {
      {"camera_position_mm", tol.camera_position_mm}, {"camera_rotation_deg", tol.camera_rotation_deg},
      {"glass_position_mm", tol.glass_position_mm},   {"sphere_diameter_mm", tol.sphere_diameter_mm},
      {"refractive_index", tol.refractive_index}};
  for (const auto& [name, v] : tolerances)
    if (!(v >= 0) || !std::isfinite(v)) throw SensitivityError(name, "must be finite and >= 0");
  if (!(tol.camera_rotation_deg <= kMaxRotationToleranceDeg))
    throw SensitivityError("camera_rotation_deg",
                           fmt::format("{:g} deg is over {:g} deg: a first-order estimate needs small changes",
                                       tol.camera_rotation_deg, kMaxRotationToleranceDeg));
  const bool monte_carlo = options.method == SensitivityMethod::monte_carlo;
  if (monte_carlo && samples < 2) throw std::invalid_argument("model_sensitivity: monte_carlo needs samples >= 2");

  TraceOptions trace = options.trace;
  trace.reflections = false;
  const std::vector<Parameter> params = parameters_of(tol);
  const int k_count = static_cast<int>(params.size());
  if (k_count == 0) throw SensitivityError("", "every tolerance is 0: nothing to perturb");

  const std::shared_ptr<const TraceScene> nominal_scene(&scene, [](const TraceScene*) {});
  const std::shared_ptr<const SceneIndex> nominal_index(make_scene_index(scene));
  const Model nominal{nominal_scene, nominal_index, camera_from_world};
  // Every perturbed model is checked before it is traced (invalid_model).
  const auto checked = [&](const Perturbation& p, const std::string& tolerance, const std::string& what) {
    Model m = perturbed_model(nominal_scene, nominal_index, camera_from_world, p);
    const std::string why = invalid_model(m, p);
    if (!why.empty()) throw SensitivityError(tolerance, what + " " + why);
    return m;
  };
  std::vector<Model> plus_minus;  // 2k: +sigma_k, 2k + 1: -sigma_k
  for (const Parameter& p : params)
    for (double sign : {1.0, -1.0})
      plus_minus.push_back(checked(Perturbation{}.add(p.unit, sign), p.tolerance,
                                   fmt::format("{}1 sigma of {} ({:g})", sign > 0 ? "+" : "-", p.name, p.sigma)));
  std::vector<Model> draws;
  if (monte_carlo) {
    NormalDraws normal(seed);
    for (int s = 0; s < samples; ++s) {
      Perturbation p;
      for (const Parameter& q : params) p.add(q.unit, normal.next());
      draws.push_back(checked(p, "", fmt::format("Monte Carlo draw {} of {}", s + 1, samples)));
    }
  }

  SensitivityMap out;
  out.grid_step_px = options.grid_step_px;
  out.width = std::max(1, model.width_px() / options.grid_step_px);
  out.height = std::max(1, model.height_px() / options.grid_step_px);
  const std::size_t n = static_cast<std::size_t>(out.width) * static_cast<std::size_t>(out.height);
  out.displacement_px.assign(n, 0.f);
  out.displacement_mm.assign(n, 0.f);
  out.valid.assign(n, 0);
  out.parameters.resize(params.size());
  for (int k = 0; k < k_count; ++k) {
    out.parameters[k].name = params[k].name;
    out.parameters[k].sigma = params[k].sigma;
    out.parameters[k].displacement_px.assign(n, 0.f);
    out.parameters[k].displacement_mm.assign(n, 0.f);
  }
  const Counts counts = count_glass(scene);
  out.glass_solids_moved = counts.glass;
  out.spheres_resized = counts.spheres;
  out.skipped_glass_meshes = counts.meshes;

  // Grid points where the nominal model sees the sheet, and per parameter where
  // its +-1 sigma models lose that view: what a refusal names.
  std::atomic<int> nominal_points{0};
  std::vector<std::atomic<int>> lost(params.size());
  parallel_rows(out.height, options.threads, [&](int row) {
    thread_local TraceResult result;
    std::vector<float> g_px(params.size()), g_mm(params.size());
    for (int col = 0; col < out.width; ++col) {
      const std::size_t idx = static_cast<std::size_t>(row) * out.width + col;
      const Eigen::Vector2d pixel = out.pixel_px(col, row);
      const Crossing c0 = direct_crossing(nominal, model, pixel, trace, &result);
      if (!c0.ok || !(std::abs(c0.dst_dpixel.determinant()) > 0)) continue;
      nominal_points.fetch_add(1);
      const Eigen::Matrix2d dpixel_dst = c0.dst_dpixel.inverse();
      bool all = true;
      double sum_mm2 = 0, sum_px2 = 0;
      for (int k = 0; k < k_count && all; ++k) {
        const Crossing plus = direct_crossing(plus_minus[2 * k], model, pixel, trace, &result);
        const Crossing minus = direct_crossing(plus_minus[2 * k + 1], model, pixel, trace, &result);
        all = plus.ok && minus.ok;
        if (!all) lost[static_cast<std::size_t>(k)].fetch_add(1);
        const Eigen::Vector2d g_st = 0.5 * (plus.st_mm - minus.st_mm);
        const Eigen::Vector2d g_pixel = dpixel_dst * g_st;
        g_mm[k] = static_cast<float>(g_st.norm());
        g_px[k] = static_cast<float>(g_pixel.norm());
        sum_mm2 += g_st.squaredNorm();
        sum_px2 += g_pixel.squaredNorm();
      }
      if (monte_carlo && all) {
        sum_mm2 = sum_px2 = 0;
        for (const Model& m : draws) {
          const Crossing c = direct_crossing(m, model, pixel, trace, &result);
          if (!(all = c.ok)) break;
          const Eigen::Vector2d d_st = c.st_mm - c0.st_mm;
          sum_mm2 += d_st.squaredNorm();
          sum_px2 += (dpixel_dst * d_st).squaredNorm();
        }
        sum_mm2 /= static_cast<double>(draws.size());
        sum_px2 /= static_cast<double>(draws.size());
      }
      if (!all) continue;
      out.valid[idx] = 1;
      out.displacement_mm[idx] = static_cast<float>(std::sqrt(sum_mm2));
      out.displacement_px[idx] = static_cast<float>(std::sqrt(sum_px2));
      for (int k = 0; k < k_count; ++k) {
        out.parameters[k].displacement_mm[idx] = g_mm[k];
        out.parameters[k].displacement_px[idx] = g_px[k];
      }
    }
  });

  out.valid_points = static_cast<int>(std::count(out.valid.begin(), out.valid.end(), 1));
  // Nothing measured is no result: a table of zeros would read as "no sensitivity".
  if (nominal_points.load() == 0)
    throw SensitivityError("", fmt::format("the camera sees the sheet directly (through the glass, no reflection) at "
                                           "none of its {} x {} sample points",
                                           out.width, out.height));
  if (out.valid_points == 0) {
    std::size_t worst = 0;
    for (std::size_t k = 1; k < lost.size(); ++k)
      if (lost[k].load() > lost[worst].load()) worst = k;
    throw SensitivityError(params[worst].tolerance,
                           fmt::format("of the {} sample points that see the sheet, none keeps its view in every "
                                       "perturbed model ({} at +-1 sigma = {:g} loses {}): the tolerances are too "
                                       "large to measure",
                                       nominal_points.load(), params[worst].name, params[worst].sigma,
                                       lost[worst].load()));
  }
  summarise(out.displacement_px, out.displacement_mm, out.valid, &out.median_px, &out.p95_px, &out.median_mm,
            &out.p95_mm);
  for (SensitivityParameter& p : out.parameters)
    summarise(p.displacement_px, p.displacement_mm, out.valid, &p.median_px, &p.p95_px, &p.median_mm, &p.p95_mm);
  return out;
}

}  // namespace glasspiv
