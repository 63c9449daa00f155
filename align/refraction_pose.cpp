#include "align/refraction_pose.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <variant>

#include "render/trace_scene_builder.h"

namespace glasspiv {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr double kJacobianStepPx = 1e-3;  // central differences: truncation ~h^2, round-off ~1e-16 scale / h
constexpr int kMaxHalvings = 16;

// Where a pixel's refracted path meets the target plane.
enum class EvalKind {
  target,        // on the target rectangle
  beside,        // passed beside it into the background: on its infinite plane, along the last segment
  other_opaque,  // stopped by another opaque solid
  no_path,       // no ray, total internal reflection, cut, or the plane is behind the last segment
};

struct Eval {
  EvalKind kind = EvalKind::no_path;
  Eigen::Vector2d f_mm = Eigen::Vector2d::Zero();  // in-plane (right, up) offset of the path's point from the target

  bool usable() const { return kind == EvalKind::target || kind == EvalKind::beside; }
};

struct Problem {
  const TraceScene& scene;
  const SceneIndex& index;
  const CameraModel& model;
  const RigidTransform& camera_from_world;
  const Eigen::Vector3d& point_mm;
  int target_solid;
  const Rectangle& rect;
  TraceOptions trace;
  Eigen::Vector2d lo_px, hi_px;  // image bounds
};

const Rectangle& target_rectangle(const TraceScene& scene, int target_solid) {
  if (target_solid < 0 || target_solid >= static_cast<int>(scene.solids.size()))
    throw std::invalid_argument("project_through_scene: target_solid " + std::to_string(target_solid) +
                                " is not a solid of the scene");
  const TraceSolid& solid = scene.solids[static_cast<std::size_t>(target_solid)];
  const Rectangle* rect = std::get_if<Rectangle>(&solid.shape);
  if (!rect || solid.material.kind != TraceMaterial::Kind::opaque)
    throw std::invalid_argument("project_through_scene: target_solid " + std::to_string(target_solid) +
                                " is not an opaque rectangle");
  return *rect;
}

Eigen::Vector2d in_plane(const Problem& p, const Eigen::Vector3d& x_mm) {
  const Eigen::Vector3d rel = x_mm - p.point_mm;
  return {rel.dot(p.rect.right), rel.dot(p.rect.up)};
}

Eval evaluate(const Problem& p, const Eigen::Vector2d& pixel, TraceResult* result) {
  Eval e;
  const std::optional<CameraRay> ray = pixel_camera_ray(p.model, p.camera_from_world, pixel);
  if (!ray) return e;
  trace_ray(p.scene, p.index, *ray, p.trace, result);
  // Reflections off: a single path, so at most one terminal event.
  if (!result->opaque_hits.empty()) {
    const OpaqueHit& hit = result->opaque_hits.front();
    if (hit.solid_index != p.target_solid) {
      e.kind = EvalKind::other_opaque;
      return e;
    }
    e.kind = EvalKind::target;
    e.f_mm = in_plane(p, hit.point_mm);
    return e;
  }
  if (!result->background.empty()) {
    const BackgroundRay& bg = result->background.front();
    const Eigen::Vector3d n = p.rect.normal();
    const double dn = bg.direction.dot(n);
    if (dn == 0) return e;
    const double u = (p.point_mm - bg.from_mm).dot(n) / dn;
    if (!(u > 0) || !std::isfinite(u)) return e;
    e.kind = EvalKind::beside;
    e.f_mm = in_plane(p, bg.from_mm + u * bg.direction);
  }
  return e;
}

// dF/dpixel by central differences (one-sided where one side has no usable
// path); false when neither side of a column has one.
bool jacobian(const Problem& p, const Eigen::Vector2d& pixel, const Eval& centre, TraceResult* result,
              Eigen::Matrix2d* j) {
  for (int axis = 0; axis < 2; ++axis) {
    Eigen::Vector2d step = Eigen::Vector2d::Zero();
    step[axis] = kJacobianStepPx;
    const Eval plus = evaluate(p, pixel + step, result);
    const Eval minus = evaluate(p, pixel - step, result);
    if (plus.usable() && minus.usable()) {
      j->col(axis) = (plus.f_mm - minus.f_mm) / (2 * kJacobianStepPx);
    } else if (plus.usable()) {
      j->col(axis) = (plus.f_mm - centre.f_mm) / kJacobianStepPx;
    } else if (minus.usable()) {
      j->col(axis) = (centre.f_mm - minus.f_mm) / kJacobianStepPx;
    } else {
      return false;
    }
  }
  return j->allFinite();
}

// The largest lambda in [0, 1] with pixel + lambda * step inside the bounds.
double step_fraction_inside(const Problem& p, const Eigen::Vector2d& pixel, const Eigen::Vector2d& step) {
  double lambda = 1;
  for (int a = 0; a < 2; ++a) {
    const double target = pixel[a] + step[a];
    if (target > p.hi_px[a]) lambda = std::min(lambda, (p.hi_px[a] - pixel[a]) / step[a]);
    if (target < p.lo_px[a]) lambda = std::min(lambda, (p.lo_px[a] - pixel[a]) / step[a]);
  }
  return std::max(0.0, lambda);
}

TracedProjectionStatus status_of_failure(EvalKind kind) {
  switch (kind) {
    case EvalKind::other_opaque:
      return TracedProjectionStatus::blocked;
    case EvalKind::no_path:
      return TracedProjectionStatus::no_path;
    default:
      return TracedProjectionStatus::not_converged;
  }
}

}  // namespace

const char* to_string(TracedProjectionStatus status) {
  switch (status) {
    case TracedProjectionStatus::ok:
      return "ok";
    case TracedProjectionStatus::not_converged:
      return "not_converged";
    case TracedProjectionStatus::blocked:
      return "blocked";
    case TracedProjectionStatus::left_image:
      return "left_image";
    case TracedProjectionStatus::no_path:
      return "no_path";
  }
  return "unknown";
}

TracedProjection project_through_scene(const TraceScene& scene, const SceneIndex& index, const CameraModel& model,
                                       const RigidTransform& camera_from_world, const Eigen::Vector3d& point_world_mm,
                                       int target_solid, const Eigen::Vector2d& start_px,
                                       const TracedProjectionOptions& options) {
  const Rectangle& rect = target_rectangle(scene, target_solid);
  TraceOptions trace = options.trace;
  trace.reflections = false;
  const Problem p{scene,
                  index,
                  model,
                  camera_from_world,
                  point_world_mm,
                  target_solid,
                  rect,
                  trace,
                  Eigen::Vector2d(-0.5, -0.5),
                  Eigen::Vector2d(model.width_px() - 0.5, model.height_px() - 0.5)};
  thread_local TraceResult result;  // buffers reused across calls

  TracedProjection out;
  out.residual_mm = kInfinity;
  Eigen::Vector2d pixel = start_px.cwiseMax(p.lo_px).cwiseMin(p.hi_px);
  if (!pixel.allFinite()) return out;
  out.pixel_px = pixel;
  Eval e = evaluate(p, pixel, &result);
  if (!e.usable()) {
    out.status = status_of_failure(e.kind);
    return out;
  }
  double r = e.f_mm.norm();
  out.residual_mm = r;

  Eigen::Matrix2d j;
  for (;;) {
    if (r <= options.tolerance_mm) {
      if (e.kind == EvalKind::target) break;
      out.status = TracedProjectionStatus::no_path;  // the point's only image is beside the rectangle: not on it
      return out;
    }
    if (out.iterations >= options.max_iterations) {
      out.status = TracedProjectionStatus::not_converged;
      return out;
    }
    if (!jacobian(p, pixel, e, &result, &j) || !(std::abs(j.determinant()) > 0)) {
      out.status = TracedProjectionStatus::not_converged;
      return out;
    }
    const Eigen::Vector2d step = -j.inverse() * e.f_mm;
    const double lambda_max = step_fraction_inside(p, pixel, step);
    const bool clamped = lambda_max < 1;
    double lambda = lambda_max;
    EvalKind last_failure = EvalKind::target;  // "no decrease"
    bool accepted = false;
    for (int k = 0; k <= kMaxHalvings && lambda > 0; ++k, lambda *= 0.5) {
      const Eigen::Vector2d q = pixel + lambda * step;
      const Eval eq = evaluate(p, q, &result);
      if (eq.usable() && eq.f_mm.norm() < r) {
        pixel = q;
        e = eq;
        r = eq.f_mm.norm();
        accepted = true;
        break;
      }
      last_failure = eq.kind;
    }
    if (!accepted) {
      // A Newton target outside the image: the linear model puts the solution there.
      out.status = clamped ? TracedProjectionStatus::left_image : status_of_failure(last_failure);
      return out;
    }
    ++out.iterations;
    out.pixel_px = pixel;
    out.residual_mm = r;
  }

  // Converged: the Jacobian at the solution, and one more step with it, which
  // takes the residual far below the tolerance (quadratic convergence), so the
  // pixel is a repeatable function of the pose for callers that differentiate.
  if (!jacobian(p, pixel, e, &result, &j) || !(std::abs(j.determinant()) > 0)) {
    out.status = TracedProjectionStatus::not_converged;
    return out;
  }
  if (r > 0) {
    const Eigen::Vector2d q = pixel - j.inverse() * e.f_mm;
    if ((q.array() >= p.lo_px.array()).all() && (q.array() <= p.hi_px.array()).all()) {
      const Eval eq = evaluate(p, q, &result);
      if (eq.kind == EvalKind::target && eq.f_mm.norm() < r) {
        pixel = q;
        r = eq.f_mm.norm();
        ++out.iterations;
      }
    }
  }
  out.status = TracedProjectionStatus::ok;
  out.pixel_px = pixel;
  out.residual_mm = r;
  out.dplane_dpixel = j;
  return out;
}

std::function<bool(const RigidTransform&, int, Eigen::Vector2d*)> traced_point_projector(
    const TraceScene& scene, const SceneIndex& index, const CameraModel& model,
    std::vector<Eigen::Vector3d> points_world_mm, std::vector<int> target_solids,
    const TracedProjectionOptions& options) {
  if (points_world_mm.size() != target_solids.size())
    throw std::invalid_argument("traced_point_projector: " + std::to_string(points_world_mm.size()) + " points but " +
                                std::to_string(target_solids.size()) + " target solids");
  for (int solid : target_solids) target_rectangle(scene, solid);  // throws for a bad one
  return [&scene, &index, model, points = std::move(points_world_mm), targets = std::move(target_solids), options](
             const RigidTransform& camera_from_world, int point_index, Eigen::Vector2d* pixel_px) {
    if (point_index < 0 || point_index >= static_cast<int>(points.size())) return false;
    const Eigen::Vector3d& point = points[static_cast<std::size_t>(point_index)];
    const std::optional<Eigen::Vector2d> pinhole = model.project(camera_from_world.apply(point));
    if (!pinhole) return false;
    const TracedProjection tp =
        project_through_scene(scene, index, model, camera_from_world, point,
                              targets[static_cast<std::size_t>(point_index)], *pinhole, options);
    if (!tp.ok()) return false;
    *pixel_px = tp.pixel_px;
    return true;
  };
}

}  // namespace glasspiv
