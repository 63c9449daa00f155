#include "render/path_tracer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include "render/optics.h"
#include "render/scene_index.h"

namespace glasspiv {

namespace {

constexpr int kFluid = -1;

using Diff = Eigen::Matrix<double, 3, 2>;  // d(vector)/d(pixel col, row)

// Every field is set where a branch is made (the camera ray, child()): the
// empty constructor keeps the stack's emplace_back from zero-filling it first.
struct Branch {
  Branch() {}
  Eigen::Vector3d anchor;     // exact start of the segment (last hit or camera)
  Eigen::Vector3d origin;     // where the ray is traced from (anchor moved off)
  Eigen::Vector3d direction;  // unit
  Diff danchor, ddirection;   // ray differentials
  double weight;
  std::uint64_t path;  // SheetCrossing::path
  int subtree;         // SheetCrossing::subtree
  int depth;
  int medium;  // kFluid or the index of the solid the branch is in
  // In the fluid: the sphere the branch leaves from its surface, outwards
  // (d . n > 0), which the ray cannot meet again (|f + t d| grows with t > 0
  // for f . d > 0; tests/render/shapes_test.cpp, SpawnOrigin, checks it in
  // double down to grazing rays), so the index does not test it; -1: none.
  int departed;
  bool any_event;
  bool any_reflection;
  bool initial;
};

// The path of a branch that starts at an event on `solid` (refracted or
// reflected there): one splitmix64 step over the parent's path.
constexpr std::uint64_t kCameraPath = 0x243f6a8885a308d3ull;
std::uint64_t extend_path(std::uint64_t path, int solid, bool reflected) {
  std::uint64_t z = path ^ ((static_cast<std::uint64_t>(static_cast<std::uint32_t>(solid)) << 1 | (reflected ? 1 : 0)) +
                            0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

CrossingTag tag_of(const Branch& b) {
  if (!b.any_event) return CrossingTag::direct;
  return b.any_reflection ? CrossingTag::with_reflections : CrossingTag::refracted_only;
}

// Transfer of the differentials from the segment's start to the point at
// distance u along it on a plane of normal n (Igehy 1999, eq. 9-10): the
// footprint of the point where the ray meets that plane.
// Written out by coefficient: Eigen's packets straddle the 3 x 2 matrix's
// columns and stall on the stores just made; the sums keep Eigen's order.
Diff transfer(const Branch& b, double u, const Eigen::Vector3d& n) {
  Diff moved;
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 3; ++i) moved(i, j) = b.danchor(i, j) + u * b.ddirection(i, j);
  const Eigen::Vector3d& d = b.direction;
  const double dn = (d[0] * n[0] + d[1] * n[1]) + d[2] * n[2];
  if (dn == 0) return moved;  // tangent: a miss by convention, never reached with a hit
  Diff out;
  for (int j = 0; j < 2; ++j) {
    const double du = -((n[0] * moved(0, j) + n[1] * moved(1, j)) + n[2] * moved(2, j)) / dn;
    for (int i = 0; i < 3; ++i) out(i, j) = moved(i, j) + d[i] * du;
  }
  return out;
}

// Records the crossing of the sheet by the segment from b.anchor along
// b.direction, to end (a hit point) or to infinity (end == nullopt). A point is
// on the "front" side when its signed distance is >= 0; a segment crosses when
// its two ends are on different sides. Consecutive segments share their end
// points exactly, so a crossing at a vertex is counted once, never twice or not
// at all.
// n is sheet.normal().
void record_crossing(const SheetPlane& sheet, const Eigen::Vector3d& n, const Branch& b, const Eigen::Vector3d* end,
                     std::vector<SheetCrossing>* out) {
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
  const double s_mm = rel.dot(sheet.s_axis), t_mm = rel.dot(sheet.t_axis);
  if (!(std::abs(s_mm) <= 0.5 * sheet.extent_s_mm && std::abs(t_mm) <= 0.5 * sheet.extent_t_mm)) return;
  SheetCrossing& c = out->emplace_back();
  c.s_mm = s_mm;
  c.t_mm = t_mm;
  c.weight = b.weight;
  c.depth = b.depth;
  c.tag = tag_of(b);
  c.path = b.path;
  c.subtree = b.subtree;
  c.point_mm = x;
  c.direction = b.direction;
  const Diff dx = transfer(b, (x - b.anchor).dot(b.direction), n);
  c.dst_dpixel.row(0) = sheet.s_axis.transpose() * dx;
  c.dst_dpixel.row(1) = sheet.t_axis.transpose() * dx;
}

// u . v for 3-vectors, summed in Eigen's order.
double dot3(const double* u, const double* v) { return (u[0] * v[0] + u[1] * v[1]) + u[2] * v[2]; }

// Reflected direction and its differential: r = d - 2 (d.n) n.
// By coefficient, like transfer(), with Eigen's sums and their order.
void reflect_with_differential(const Eigen::Vector3d& d, const Diff& dd, const Eigen::Vector3d& n, const Diff& dn,
                               Eigen::Vector3d* r, Diff* dr) {
  const double a = d.dot(n);
  double da[2];
  for (int j = 0; j < 2; ++j) da[j] = dot3(n.data(), &dd(0, j)) + dot3(d.data(), &dn(0, j));
  *r = (d - 2 * a * n).normalized();
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 3; ++i) (*dr)(i, j) = dd(i, j) - 2 * (a * dn(i, j) + n[i] * da[j]);
}

// Refracted direction's differential (Igehy 1999, eq. 15-17) for
// t = eta d + (eta c - cos_t) m, m the normal facing the ray, c = -d.m, and
// dm = sign_m * dn (sign_m = +-1, exact): the facing normal's differential is
// never stored negated, whose reload across the columns stalls.
Diff refraction_differential(const Eigen::Vector3d& d, const Diff& dd, const Eigen::Vector3d& m, double sign_m,
                             const Diff& dn, const Eigen::Vector3d& t, double eta) {
  const double c = -d.dot(m);
  const double cos_t = -t.dot(m);
  const double k = cos_t > 0 ? eta * eta * c / cos_t : 0.0;
  const double e = eta * c - cos_t;
  Diff out;
  for (int j = 0; j < 2; ++j) {
    double dm[3];
    for (int i = 0; i < 3; ++i) dm[i] = sign_m * dn(i, j);
    const double dc = -(dot3(m.data(), &dd(0, j)) + dot3(d.data(), dm));
    const double f = eta * dc - k * dc;
    for (int i = 0; i < 3; ++i) out(i, j) = (eta * dd(i, j) + m[i] * f) + e * dm[i];
  }
  return out;
}

// The branch being followed lives in one of two slots; its refracted child is
// built in the other and followed next, without a trip through the stack
// (the stack would hand it straight back: it is pushed last).
struct Workspace {
  std::vector<Branch> stack;
  Branch slot[2];
};

}  // namespace

std::unique_ptr<SceneIndex> make_scene_index(const TraceScene& scene) {
  std::vector<Shape> shapes;
  shapes.reserve(scene.solids.size());
  for (const auto& solid : scene.solids) shapes.push_back(solid.shape);
  return make_scene_index(std::move(shapes));
}

void trace_ray(const TraceScene& scene, const SceneIndex& index, const CameraRay& ray, const TraceOptions& options,
               TraceResult* result_out, const DeferredSubtrees& deferred) {
  const double dir_norm = ray.direction.norm();
  if (!ray.origin_mm.allFinite() || !ray.direction.allFinite() || !(dir_norm > 0))
    throw std::invalid_argument("trace_ray: origin and direction must be finite and the direction non-zero");

  TraceResult& result = *result_out;
  result.crossings.clear();
  result.background.clear();
  result.opaque_hits.clear();
  result.counts = TraceCounts{};
  result.background_weight = result.opaque_weight = result.absorbed_weight = 0;
  result.cut_by_weight_weight = result.cut_by_depth_weight = result.skipped_reflection_weight = 0;
  result.subtrees.clear();
  result.deferred.clear();
  result.deferred_weight = 0;
  result.solids_met.clear();

  // The camera ray is not spawned from a hit, so it gets its own guard: a
  // surface closer than this to the origin is not seen (an origin on a surface
  // starts on the side the ray travels into, like a spawned ray).
  const double initial_t_min =
      16 * kHitRelativeError * (ray.origin_mm.cwiseAbs().maxCoeff() + index.max_scale_mm());

  thread_local Workspace ws;
  std::vector<Branch>& stack = ws.stack;
  stack.clear();
  int current = 0;
  bool have_current = true;  // slot[current] holds the next branch to follow
  Branch& first = ws.slot[current];
  first.anchor = first.origin = ray.origin_mm;
  first.direction = ray.direction / dir_norm;
  first.danchor.setZero();
  // d(v/|v|) = (I - u u^T) dv / |v|, by coefficient (Eigen's order) like transfer().
  {
    const Eigen::Vector3d& u = first.direction;
    const Eigen::Matrix3d p = Eigen::Matrix3d::Identity() - u * u.transpose();
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 3; ++i)
        first.ddirection(i, j) = ((p(i, 0) * ray.ddirection_dpixel(0, j) + p(i, 1) * ray.ddirection_dpixel(1, j)) +
                                  p(i, 2) * ray.ddirection_dpixel(2, j)) /
                                 dir_norm;
  }
  first.weight = 1;
  first.path = kCameraPath;
  first.subtree = -1;
  first.depth = 0;
  first.medium = kFluid;
  first.departed = -1;
  first.any_event = first.any_reflection = false;
  first.initial = true;
  const Eigen::Vector3d sheet_normal = scene.sheet.normal();

  // Whether a child of this weight and depth is followed; the bookkeeping of
  // the ones that are not. Decided before the child is built, so cut branches
  // cost no differentials.
  const double min_weight_reflected = std::max(options.min_weight, options.min_weight_reflected);
  // subtree: the subtree the cut weight belongs to (-1: the refracted chain's).
  auto admit = [&](double weight, int depth, bool reflected, int subtree) {
    if (!(weight > 0)) return false;  // nothing to follow (R = 0 or R = 1 exactly)
    if (depth > options.max_depth) {
      ++result.counts.cut_by_depth;
      result.cut_by_depth_weight += weight;
      if (subtree >= 0) result.subtrees[static_cast<std::size_t>(subtree)].cut_weight += weight;
      return false;
    }
    if (weight < (reflected ? min_weight_reflected : options.min_weight)) {
      ++result.counts.cut_by_weight;
      result.cut_by_weight_weight += weight;
      if (subtree >= 0) result.subtrees[static_cast<std::size_t>(subtree)].cut_weight += weight;
      return false;
    }
    return true;
  };
  auto is_deferred = [&](std::uint64_t id, double weight) {
    const std::uint64_t* found = std::find(deferred.ids, deferred.ids + deferred.count, id);
    if (found == deferred.ids + deferred.count) return false;
    const std::size_t i = static_cast<std::size_t>(found - deferred.ids);
    return weight >= deferred.min_weight[i] && weight <= deferred.max_weight[i];
  };

  while (true) {
    if (!have_current) {
      if (stack.empty()) break;
      ws.slot[current] = stack.back();
      stack.pop_back();
    }
    have_current = false;
    Branch& b = ws.slot[current];
    ++result.counts.branches_traced;

    std::optional<Hit> hit = [&]() -> std::optional<Hit> {
      if (b.medium == kFluid) {
        if (b.initial && !index.may_hit(b.origin, b.direction)) {
          ++result.counts.closed_form;  // nothing to meet: straight to the sheet and the background
          return std::nullopt;
        }
        return index.first_hit(b.origin, b.direction, b.initial ? initial_t_min : 0.0, b.departed);
      }
      // Solids do not overlap: inside one, the next surface is its own.
      std::optional<Hit> h =
          intersect(scene.solids[static_cast<std::size_t>(b.medium)].shape, b.origin, b.direction, 0.0);
      if (h) h->shape_index = b.medium;
      return h;
    }();

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
      record_crossing(scene.sheet, sheet_normal, b, hit ? &hit->point : nullptr, &result.crossings);
    } else if (hit) {
      const double alpha = scene.solids[static_cast<std::size_t>(seg_medium)].material.absorption_per_mm;
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
      if (b.subtree >= 0) result.subtrees[static_cast<std::size_t>(b.subtree)].background_weight += b.weight;
      continue;
    }

    const TraceSolid& solid = scene.solids[static_cast<std::size_t>(hit->shape_index)];
    if (options.record_solids_met) result.solids_met.push_back(hit->shape_index);
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
      if (b.subtree >= 0) result.subtrees[static_cast<std::size_t>(b.subtree)].opaque_weight += b.weight;
      continue;
    }

    // A glass interface between seg_medium and the other side of this surface.
    const bool inside = seg_medium != kFluid;
    const double n_glass = solid.material.refractive_index;
    const double n1 = inside ? n_glass : scene.fluid_index;
    const double n2 = inside ? scene.fluid_index : n_glass;
    const int other_medium = inside ? kFluid : hit->shape_index;

    // Differentials at the hit (transfer onto the tangent plane), and of the normal.
    const Diff dpoint = transfer(b, (hit->point - b.anchor).dot(b.direction), hit->normal);
    // Interaction normal: the smooth one where it keeps both branches on their
    // geometric sides, else the geometric one.
    Eigen::Vector3d normal = hit->normal;
    if (hit->shading_normal) {
      const Eigen::Vector3d& sn = *hit->shading_normal;
      const double sdn = b.direction.dot(sn);
      const bool same_side = (sdn > 0) == (dn > 0) && sdn != 0;
      const std::optional<Eigen::Vector3d> t_try = refract(b.direction, sn, n1 / n2);
      const bool t_ok = !t_try || (t_try->dot(hit->normal) > 0) == (dn > 0);
      const bool r_ok = (reflect(b.direction, sn).dot(hit->normal) > 0) != (dn > 0);
      if (same_side && t_ok && r_ok) {
        normal = sn;
      } else {
        ++result.counts.shading_fallbacks;
      }
    }
    // The shape operator describes the normal the shape reports (the smooth one
    // where there is one); a fallback to a flat face's normal has none.
    const bool fell_back = hit->shading_normal && normal != *hit->shading_normal;
    const Diff dnormal = fell_back ? Diff::Zero() : hit->dnormal(dpoint);
    const double ndn = b.direction.dot(normal);

    const Refraction split = refract_with_fresnel(b.direction, normal, n1, n2);
    const std::optional<Eigen::Vector3d>& refracted = split.direction;
    const bool tir = !refracted;
    if (tir) ++result.counts.tir_events;
    const double reflectance = tir ? 1.0 : split.reflectance.unpolarized;

    const bool sphere = std::holds_alternative<Sphere>(solid.shape);
    // The solid a child leaves, or -1 (Branch::departed).
    auto departs = [&](const Eigen::Vector3d& direction, int medium) {
      return sphere && medium == kFluid && direction.dot(hit->normal) > 0 ? hit->shape_index : -1;
    };
    auto child = [&](Branch& c) -> Branch& {  // direction, origin, weight, medium, departed, any_reflection: by the caller
      c.anchor = hit->point;
      c.danchor = dpoint;
      c.depth = b.depth + 1;
      c.any_event = true;
      c.initial = false;
      return c;
    };

    // Reflected branch (pushed first, so that the refracted one is followed first).
    const double w_reflected = b.weight * reflectance;
    const double w_refracted = b.weight - w_reflected;  // (1 - R) w, so that the two add up to w exactly
    if (!options.reflections) {
      if (w_reflected > 0) {
        ++result.counts.reflections_skipped;
        result.skipped_reflection_weight += w_reflected;
      }
    } else {
      const std::uint64_t r_path = extend_path(b.path, hit->shape_index, true);
      if (b.subtree < 0 && deferred.count > 0 && w_reflected > 0 && is_deferred(r_path, w_reflected)) {
        result.deferred.push_back(r_path);
        result.deferred_weight += w_reflected;
      } else if (admit(w_reflected, b.depth + 1, true, b.subtree)) {
        Branch& r = child(stack.emplace_back());
        reflect_with_differential(b.direction, b.ddirection, normal, dnormal, &r.direction, &r.ddirection);
        r.origin = spawn_origin(*hit, r.direction, seg_medium == kFluid);
        r.weight = w_reflected;
        r.path = r_path;
        r.subtree = b.subtree;
        if (b.subtree < 0) {  // off the refracted chain: a new subtree
          r.subtree = static_cast<int>(result.subtrees.size());
          ReflectedSubtree& st = result.subtrees.emplace_back();
          st.id = r_path;
          st.weight = w_reflected;
        }
        r.medium = seg_medium;
        r.departed = departs(r.direction, r.medium);
        r.any_reflection = true;
      }
    }
    if (refracted && admit(w_refracted, b.depth + 1, b.any_reflection, b.subtree)) {
      Branch& t = child(ws.slot[1 - current]);
      t.direction = *refracted;
      const Eigen::Vector3d facing = ndn < 0 ? normal : Eigen::Vector3d(-normal);
      t.ddirection =
          refraction_differential(b.direction, b.ddirection, facing, ndn < 0 ? 1.0 : -1.0, dnormal, t.direction, n1 / n2);
      t.origin = spawn_origin(*hit, t.direction, other_medium == kFluid);
      t.weight = w_refracted;
      t.path = extend_path(b.path, hit->shape_index, false);
      t.subtree = b.subtree;
      t.medium = other_medium;
      t.departed = departs(t.direction, t.medium);
      t.any_reflection = b.any_reflection;
      current = 1 - current;
      have_current = true;
    }
  }
}

TraceResult trace_ray(const TraceScene& scene, const Eigen::Vector3d& origin_mm, const Eigen::Vector3d& direction,
                      const TraceOptions& options) {
  std::vector<Shape> shapes;
  shapes.reserve(scene.solids.size());
  for (const auto& solid : scene.solids) shapes.push_back(solid.shape);
  const LinearSceneIndex index(std::move(shapes));
  CameraRay ray;
  ray.origin_mm = origin_mm;
  ray.direction = direction;
  TraceResult result;
  trace_ray(scene, index, ray, options, &result);
  return result;
}

}  // namespace glasspiv
