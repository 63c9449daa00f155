#include "render/path_tracer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include "render/optics.h"

namespace glasspiv {

namespace {

constexpr int kFluid = -1;

struct Branch {
  Eigen::Vector3d anchor = Eigen::Vector3d::Zero();     // exact start of the segment (last hit or camera)
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();     // where the ray is traced from (anchor moved off)
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();  // unit
  double weight = 1;
  int depth = 0;
  int medium = kFluid;  // kFluid or the index of the solid the branch is in
  bool any_event = false;
  bool any_reflection = false;
  bool initial = false;
};

CrossingTag tag_of(const Branch& b) {
  if (!b.any_event) return CrossingTag::direct;
  return b.any_reflection ? CrossingTag::with_reflections : CrossingTag::refracted_only;
}

// Records the crossing of the sheet by the segment from b.anchor along
// b.direction, to end (a hit point) or to infinity (end == nullopt). A point is
// on the "front" side when its signed distance is >= 0; a segment crosses when
// its two ends are on different sides. Consecutive segments share their end
// points exactly, so a crossing at a vertex is counted once, never twice or not
// at all.
void record_crossing(const SheetPlane& sheet, const Branch& b, const std::optional<Eigen::Vector3d>& end,
                     std::vector<SheetCrossing>* out) {
  const Eigen::Vector3d n = sheet.normal();
  const double dist_a = (b.anchor - sheet.origin_mm).dot(n);
  const bool front_a = dist_a >= 0;
  Eigen::Vector3d x;
  if (end) {
    const double dist_e = (*end - sheet.origin_mm).dot(n);
    if ((dist_e >= 0) == front_a) return;
    const double f = dist_a / (dist_a - dist_e);  // denominator != 0: the signs differ
    x = b.anchor + f * (*end - b.anchor);
  } else {
    const double dn = b.direction.dot(n);
    if (dn == 0 || (dn > 0) == front_a) return;
    x = b.anchor + (-dist_a / dn) * b.direction;
  }
  const Eigen::Vector3d rel = x - sheet.origin_mm;
  SheetCrossing c;
  c.s_mm = rel.dot(sheet.s_axis);
  c.t_mm = rel.dot(sheet.t_axis);
  if (!(std::abs(c.s_mm) <= 0.5 * sheet.extent_s_mm && std::abs(c.t_mm) <= 0.5 * sheet.extent_t_mm)) return;
  c.weight = b.weight;
  c.depth = b.depth;
  c.tag = tag_of(b);
  c.point_mm = x;
  c.direction = b.direction;
  out->push_back(c);
}

}  // namespace

TraceResult trace_ray(const TraceScene& scene, const Eigen::Vector3d& origin_mm, const Eigen::Vector3d& direction,
                      const TraceOptions& options) {
  const double dir_norm = direction.norm();
  if (!origin_mm.allFinite() || !direction.allFinite() || !(dir_norm > 0))
    throw std::invalid_argument("trace_ray: origin and direction must be finite and the direction non-zero");

  std::vector<Shape> shapes;
  shapes.reserve(scene.solids.size());
  double scene_scale = 0;
  for (const auto& solid : scene.solids) {
    shapes.push_back(solid.shape);
    scene_scale = std::max(scene_scale, scale_mm(solid.shape));
  }
  // The camera ray is not spawned from a hit, so it gets its own guard: a
  // surface closer than this to the origin is not seen (an origin on a surface
  // starts on the side the ray travels into, like a spawned ray).
  const double initial_t_min = 16 * kHitRelativeError * (origin_mm.cwiseAbs().maxCoeff() + scene_scale);

  TraceResult result;
  std::vector<Branch> stack;
  Branch first;
  first.anchor = first.origin = origin_mm;
  first.direction = direction / dir_norm;
  first.initial = true;
  stack.push_back(first);

  auto push_child = [&](Branch child) {
    if (!(child.weight > 0)) return;  // nothing to follow (R = 0 or R = 1 exactly)
    if (child.depth > options.max_depth) {
      ++result.counts.cut_by_depth;
      result.cut_by_depth_weight += child.weight;
    } else if (child.weight < options.min_weight) {
      ++result.counts.cut_by_weight;
      result.cut_by_weight_weight += child.weight;
    } else {
      stack.push_back(std::move(child));
    }
  };

  while (!stack.empty()) {
    Branch b = std::move(stack.back());
    stack.pop_back();
    ++result.counts.branches_traced;

    const double t_min = b.initial ? initial_t_min : 0.0;
    std::optional<Hit> hit;
    if (b.medium == kFluid) {
      hit = first_hit(shapes, b.origin, b.direction, t_min);
    } else {
      // Solids do not overlap: inside one, the next surface is its own.
      hit = intersect(shapes[b.medium], b.origin, b.direction, t_min);
      if (hit) hit->shape_index = b.medium;
    }

    // The medium of this segment, from the geometry of its end: a ray leaving a
    // solid (d . n > 0) was inside it, a ray entering one (d . n < 0) was in the
    // fluid. Where this disagrees with the tracked medium (a spawned origin
    // that landed in a touching neighbour, or beyond an edge), the geometry wins.
    int seg_medium = b.medium;
    double dn = 0;
    if (hit) {
      dn = b.direction.dot(hit->normal);
      const int geometric = dn > 0 ? hit->shape_index : (dn < 0 ? kFluid : b.medium);
      if (geometric != b.medium && !b.initial) ++result.counts.medium_corrections;
      seg_medium = geometric;
    }

    if (seg_medium == kFluid) {
      record_crossing(scene.sheet, b,
                      hit ? std::optional<Eigen::Vector3d>(hit->point) : std::optional<Eigen::Vector3d>(),
                      &result.crossings);
    } else if (hit) {
      const double alpha = scene.solids[seg_medium].material.absorption_per_mm;
      if (alpha > 0) {
        const double kept = b.weight * beer_lambert_transmittance(alpha, (hit->point - b.anchor).norm());
        result.absorbed_weight += b.weight - kept;
        b.weight = kept;
      }
    }

    if (!hit) {
      BackgroundRay bg;
      bg.from_mm = b.anchor;
      bg.direction = b.direction;
      bg.weight = b.weight;
      bg.depth = b.depth;
      bg.tag = tag_of(b);
      result.background.push_back(bg);
      result.background_weight += b.weight;
      continue;
    }

    const TraceSolid& solid = scene.solids[hit->shape_index];
    if (solid.material.kind == TraceMaterial::Kind::opaque) {
      OpaqueHit oh;
      oh.solid_index = hit->shape_index;
      oh.point_mm = hit->point;
      oh.normal = hit->normal;
      oh.weight = b.weight;
      oh.depth = b.depth;
      oh.tag = tag_of(b);
      result.opaque_hits.push_back(oh);
      result.opaque_weight += b.weight;
      continue;
    }

    // A glass interface between seg_medium and the other side of this surface.
    const bool inside = seg_medium != kFluid;
    const double n_glass = solid.material.refractive_index;
    const double n1 = inside ? n_glass : scene.fluid_index;
    const double n2 = inside ? scene.fluid_index : n_glass;
    const int other_medium = inside ? kFluid : hit->shape_index;

    const FresnelReflectance fr = fresnel_dielectric(std::abs(dn), n1, n2);
    std::optional<Eigen::Vector3d> refracted;
    if (!fr.total_internal_reflection) refracted = refract(b.direction, hit->normal, n1 / n2);
    const bool tir = !refracted;  // refract and fresnel_dielectric share the TIR test
    if (tir) ++result.counts.tir_events;
    const double reflectance = tir ? 1.0 : fr.unpolarized;

    Branch child;
    child.anchor = hit->point;
    child.depth = b.depth + 1;
    child.any_event = true;

    // Reflected branch (pushed first, so that the refracted one is followed first).
    const double w_reflected = b.weight * reflectance;
    if (!options.reflections) {
      if (w_reflected > 0) {
        ++result.counts.reflections_skipped;
        result.skipped_reflection_weight += w_reflected;
      }
    } else {
      Branch r = child;
      r.direction = reflect(b.direction, hit->normal).normalized();
      r.origin = spawn_origin(*hit, r.direction, seg_medium == kFluid);
      r.weight = w_reflected;
      r.medium = seg_medium;
      r.any_reflection = true;
      push_child(std::move(r));
    }
    if (refracted) {
      Branch t = child;
      t.direction = *refracted;
      t.origin = spawn_origin(*hit, t.direction, other_medium == kFluid);
      t.weight = b.weight - w_reflected;  // (1 - R) w, so that the two add up to w exactly
      t.medium = other_medium;
      t.any_reflection = b.any_reflection;
      push_child(std::move(t));
    }
  }
  return result;
}

}  // namespace glasspiv
