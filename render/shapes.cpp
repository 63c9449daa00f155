#include "render/shapes.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

namespace glasspiv {

namespace {

double inf_norm(const Eigen::Vector3d& v) { return v.cwiseAbs().maxCoeff(); }

double error_bound(const Eigen::Vector3d& p, double scale) { return kHitRelativeError * (inf_norm(p) + scale); }

// Roots of |f + u e|^2 = r^2 for unit e, stable for grazing rays and origins
// near the surface:
//  - half-b form: b = f . e, roots u = -b +- sqrt(b^2 - c), c = |f|^2 - r^2;
//  - the discriminant as r^2 - |f - b e|^2 = (r - l)(r + l), l = |f - b e|
//    (the squared distance of the line from the centre; Hearn & Baker), which
//    does not cancel when b^2 ~ c as the naive b^2 - c does;
//  - the "q" trick (Numerical Recipes 5.6, pbrt): q = -(b + sign(b) sqrt(disc)),
//    roots q and c / q, so neither root is a difference of near-equal terms.
// Returns false for disc <= 0: a tangent line or a miss (no NaN: nothing is
// taken of a negative number).
bool sphere_roots(const Eigen::Vector3d& f, const Eigen::Vector3d& e, double r, double* u0, double* u1) {
  const double b = f.dot(e);
  const double l = (f - b * e).norm();
  const double disc = (r - l) * (r + l);
  if (!(disc > 0)) return false;
  const double sq = std::sqrt(disc);
  const double q = -(b + std::copysign(sq, b));
  const double c = f.squaredNorm() - r * r;
  double a0 = q, a1 = (q != 0) ? c / q : -q;
  if (a0 > a1) std::swap(a0, a1);
  *u0 = a0;
  *u1 = a1;
  return true;
}

}  // namespace

Box make_slab(const Eigen::Vector3d& centre_mm, const Eigen::Vector3d& normal, double thickness_mm,
              double half_extent_mm) {
  Box b;
  b.centre_mm = centre_mm;
  b.world_from_box = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), normal.normalized())
                         .toRotationMatrix();
  b.half_extent_mm = Eigen::Vector3d(half_extent_mm, half_extent_mm, 0.5 * thickness_mm);
  return b;
}

std::optional<double> sphere_hit_t(const Sphere& s, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                                   double t_min) {
  const Eigen::Vector3d f = o - s.centre_mm;
  const double r = s.radius_mm;
  // sphere_roots, with its miss decided before the two square roots where the
  // line's distance from the centre clearly exceeds r: with l2 > r^2 (1 + 1e-12)
  // the rounded l = sqrt(l2) is > r (rounding is ~1e-16 relative), so
  // disc = (r - l)(r + l) < 0 there and sphere_roots would miss as well.
  const double b = f.dot(d);
  const Eigen::Vector3d g = f - b * d;
  const double l2 = g.squaredNorm();
  if (!(l2 <= (r * r) * (1 + 1e-12))) return std::nullopt;
  const double l = std::sqrt(l2);  // == g.norm()
  const double disc = (r - l) * (r + l);
  if (!(disc > 0)) return std::nullopt;
  const double sq = std::sqrt(disc);
  const double q = -(b + std::copysign(sq, b));
  const double c = f.squaredNorm() - r * r;
  double t;
  if (t_min >= 0 && ((q > 0 && c <= 0) || (q < 0 && c >= 0))) {
    // The root c / q is <= 0 <= t_min here (its sign is c's times q's), so
    // the answer is q or a miss, as below, without the division: the common
    // case of a ray inside the sphere (c < 0) and of one moving away (q < 0).
    t = q;
  } else {
    double t0 = q, t1 = (q != 0) ? c / q : -q;
    if (t0 > t1) std::swap(t0, t1);
    t = t0 > t_min ? t0 : t1;
  }
  if (!(t > t_min)) return std::nullopt;
  // sphere_hit normalises f + t d: a zero vector (never seen) is a miss.
  if (!((f + t * d).squaredNorm() > 0)) return std::nullopt;
  return t;
}

Hit sphere_hit(const Sphere& s, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t) {
  const Eigen::Vector3d f = o - s.centre_mm;
  Hit h;
  h.t = t;
  Eigen::Vector3d radial = f + t * d;
  const double len = radial.norm();
  h.normal = radial / len;
  h.point = s.centre_mm + s.radius_mm * h.normal;  // back onto the sphere (pbrt's reprojection)
  h.umbilic_curvature_per_mm = 1.0 / s.radius_mm;  // the shape operator I / r
  h.error_mm = error_bound(h.point, inf_norm(s.centre_mm) + s.radius_mm);
  return h;
}

std::optional<Hit> intersect(const Sphere& s, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min) {
  const std::optional<double> t = sphere_hit_t(s, o, d, t_min);
  if (!t) return std::nullopt;
  return sphere_hit(s, o, d, *t);
}

std::optional<Hit> intersect(const Box& b, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min) {
  const Eigen::Matrix3d box_from_world = b.world_from_box.transpose();
  const Eigen::Vector3d lo = box_from_world * (o - b.centre_mm);
  const Eigen::Vector3d ld = box_from_world * d;
  const Eigen::Vector3d& h = b.half_extent_mm;
  double t_near = -std::numeric_limits<double>::infinity(), t_far = std::numeric_limits<double>::infinity();
  int axis_near = -1, axis_far = -1;
  for (int i = 0; i < 3; ++i) {
    if (ld[i] == 0) {
      if (!(std::abs(lo[i]) < h[i])) return std::nullopt;  // parallel, outside or in the face plane
      continue;
    }
    double ta = (-h[i] - lo[i]) / ld[i], tb = (h[i] - lo[i]) / ld[i];
    if (ta > tb) std::swap(ta, tb);
    if (ta > t_near) {
      t_near = ta;
      axis_near = i;
    }
    if (tb < t_far) {
      t_far = tb;
      axis_far = i;
    }
  }
  if (!(t_near < t_far)) return std::nullopt;  // miss, or touching an edge/corner only
  double t;
  int axis;
  double side;
  if (t_near > t_min && axis_near >= 0) {
    t = t_near;
    axis = axis_near;
    side = ld[axis] > 0 ? -1.0 : 1.0;  // entering through the face facing the ray
  } else if (t_far > t_min && axis_far >= 0 && std::isfinite(t_far)) {
    t = t_far;
    axis = axis_far;
    side = ld[axis] > 0 ? 1.0 : -1.0;
  } else {
    return std::nullopt;
  }
  Eigen::Vector3d lp = lo + t * ld;
  lp[axis] = side * h[axis];  // exactly on the face plane
  Eigen::Vector3d ln = Eigen::Vector3d::Zero();
  ln[axis] = side;
  Hit hit;
  hit.t = t;
  hit.point = b.world_from_box * lp + b.centre_mm;
  hit.normal = b.world_from_box * ln;
  // Exact face coordinate in the box frame; rotating back adds ~eps (|p_box| + |centre|) <= eps (|p| + 2 |centre|).
  hit.error_mm = error_bound(hit.point, 2 * inf_norm(b.centre_mm) + h.minCoeff());
  return hit;
}

std::optional<Hit> intersect(const Cylinder& c, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min) {
  const Eigen::Vector3d& a = c.axis;
  const Eigen::Vector3d f = o - c.centre_mm;
  const double fa = f.dot(a), da = d.dot(a);
  const Eigen::Vector3d fp = f - fa * a, dp = d - da * a;
  const double r = c.radius_mm, hl = c.half_length_mm;
  struct Candidate {
    double t;
    int kind;  // 0 side, +1 top cap, -1 bottom cap
  };
  Candidate cand[4];
  int n = 0;
  const double s = dp.norm();
  if (s > 0) {
    const Eigen::Vector3d e = dp / s;  // distances u = s t in the plane normal to the axis
    double u0 = 0, u1 = 0;
    if (sphere_roots(fp, e, r, &u0, &u1)) {
      for (double u : {u0, u1}) {
        const double t = u / s;
        if (std::abs(fa + da * t) <= hl) cand[n++] = {t, 0};
      }
    }
  }
  if (da != 0) {
    for (int side : {1, -1}) {
      const double t = (side * hl - fa) / da;
      if ((fp + t * dp).squaredNorm() < r * r) cand[n++] = {t, side};
    }
  }
  const Candidate* best = nullptr;
  for (int i = 0; i < n; ++i)
    if (cand[i].t > t_min && (!best || cand[i].t < best->t)) best = &cand[i];
  if (!best) return std::nullopt;
  const double t = best->t;
  Hit hit;
  hit.t = t;
  Eigen::Vector3d radial = fp + t * dp;
  if (best->kind == 0) {
    const double len = radial.norm();
    if (!(len > 0)) return std::nullopt;
    hit.normal = radial / len;
    hit.point = c.centre_mm + (fa + da * t) * a + r * hit.normal;
    hit.dnormal_dpoint = (Eigen::Matrix3d::Identity() - a * a.transpose()) / r;
  } else {
    hit.normal = best->kind * a;
    hit.point = c.centre_mm + (best->kind * hl) * a + radial;
  }
  hit.error_mm = error_bound(hit.point, 2 * inf_norm(c.centre_mm) + r);
  return hit;
}

std::optional<Hit> intersect(const Rectangle& r, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min) {
  const Eigen::Vector3d n = r.normal();
  const double dn = d.dot(n);
  if (dn == 0) return std::nullopt;  // in the plane: tangent, a miss
  const Eigen::Vector3d f = r.centre_mm - o;
  const double t = f.dot(n) / dn;
  if (!(t > t_min)) return std::nullopt;
  const Eigen::Vector3d rel = o + t * d - r.centre_mm;
  const double u = rel.dot(r.right), v = rel.dot(r.up);
  if (!(std::abs(u) <= r.half_width_mm && std::abs(v) <= r.half_height_mm)) return std::nullopt;
  Hit hit;
  hit.t = t;
  hit.point = r.centre_mm + u * r.right + v * r.up;  // exactly in the plane
  hit.normal = dn < 0 ? n : Eigen::Vector3d(-n);       // faces the ray: it is entered
  hit.error_mm = error_bound(hit.point, 2 * inf_norm(r.centre_mm));
  return hit;
}

std::optional<Hit> intersect(const Shape& s, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min) {
  return std::visit([&](const auto& shape) { return intersect(shape, o, d, t_min); }, s);
}

std::optional<Hit> first_hit(const std::vector<Shape>& shapes, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                             double t_min, int skip_index) {
  std::optional<Hit> best;
  for (std::size_t i = 0; i < shapes.size(); ++i) {
    if (static_cast<int>(i) == skip_index) continue;
    auto h = intersect(shapes[i], o, d, t_min);
    if (h && (!best || h->t < best->t)) {
      h->shape_index = static_cast<int>(i);
      best = h;
    }
  }
  return best;
}

Eigen::AlignedBox3d bounds_mm(const Shape& shape) {
  if (const auto* m = std::get_if<TriangleMesh>(&shape)) return bounds_mm(*m);
  if (const auto* s = std::get_if<Sphere>(&shape))
    return {s->centre_mm.array() - s->radius_mm, s->centre_mm.array() + s->radius_mm};
  if (const auto* b = std::get_if<Box>(&shape)) {
    const Eigen::Vector3d half = b->world_from_box.cwiseAbs() * b->half_extent_mm;
    return {b->centre_mm - half, b->centre_mm + half};
  }
  if (const auto* r = std::get_if<Rectangle>(&shape)) {
    const Eigen::Vector3d half = r->half_width_mm * r->right.cwiseAbs() + r->half_height_mm * r->up.cwiseAbs();
    return {r->centre_mm - half, r->centre_mm + half};
  }
  const auto& c = std::get<Cylinder>(shape);
  // Each cap disc spans r sqrt(1 - a_i^2) along axis i.
  const Eigen::Vector3d disc = c.radius_mm * (Eigen::Vector3d::Ones() - c.axis.cwiseAbs2()).cwiseMax(0.0).cwiseSqrt();
  const Eigen::Vector3d half = c.half_length_mm * c.axis.cwiseAbs() + disc;
  return {c.centre_mm - half, c.centre_mm + half};
}

bool contains(const Shape& shape, const Eigen::Vector3d& p, double margin_mm) {
  if (std::holds_alternative<Rectangle>(shape)) return false;  // no inside
  if (const auto* m = std::get_if<TriangleMesh>(&shape)) return contains(*m, p, margin_mm);
  if (const auto* s = std::get_if<Sphere>(&shape)) return (p - s->centre_mm).norm() < s->radius_mm - margin_mm;
  if (const auto* b = std::get_if<Box>(&shape)) {
    const Eigen::Vector3d lp = b->world_from_box.transpose() * (p - b->centre_mm);
    return ((b->half_extent_mm - lp.cwiseAbs()).array() > margin_mm).all();
  }
  const auto& c = std::get<Cylinder>(shape);
  const Eigen::Vector3d f = p - c.centre_mm;
  const double fa = f.dot(c.axis);
  return std::abs(fa) < c.half_length_mm - margin_mm && (f - fa * c.axis).norm() < c.radius_mm - margin_mm;
}

double scale_mm(const Shape& shape) {
  if (const auto* s = std::get_if<Sphere>(&shape)) return inf_norm(s->centre_mm) + s->radius_mm;
  if (const auto* b = std::get_if<Box>(&shape)) return 2 * inf_norm(b->centre_mm) + b->half_extent_mm.minCoeff();
  if (const auto* r = std::get_if<Rectangle>(&shape)) return 2 * inf_norm(r->centre_mm);
  if (const auto* m = std::get_if<TriangleMesh>(&shape)) return scale_mm(*m);
  const auto& c = std::get<Cylinder>(shape);
  return 2 * inf_norm(c.centre_mm) + c.radius_mm;
}

Eigen::Vector3d spawn_origin(const Hit& hit, const Eigen::Vector3d& direction, bool tangent_outward) {
  const double dn = direction.dot(hit.normal);
  const double side = dn > 0 ? 1.0 : (dn < 0 ? -1.0 : (tangent_outward ? 1.0 : -1.0));
  return hit.point + (side * 2.0 * hit.error_mm) * hit.normal;
}

}  // namespace glasspiv
