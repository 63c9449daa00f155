#include "render/triangle_mesh.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "render/embree_device.h"
#include "render/float_outward.h"

namespace glasspiv {

struct TriangleMesh::Data {
  std::vector<Eigen::Vector3d> v;                     // vertices (mm)
  std::vector<MeshTriangle> tri;                      // after orientation
  std::vector<MeshTriangle> adj;                      // adj[k][e]: the triangle across edge e = (tri[k][e], tri[k][e+1])
  std::vector<Eigen::Vector3d> n;                     // outward unit normals
  std::vector<std::array<Eigen::Vector3d, 3>> corner;  // unit shading normals; empty when flat
  MeshShading shading = MeshShading::flat;
  Eigen::AlignedBox3d box;  // of the vertices
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // origin of the float frame Embree works in
  double pad = 0;    // padding of the float boxes and of the clipped ray (mm)
  double scale = 0;  // max |vertex|_inf
  double volume = 0;
  int parts = 0, flipped = 0;
  RTCScene scene = nullptr;

  Data() = default;
  Data(const Data&) = delete;
  Data& operator=(const Data&) = delete;
  ~Data() {
    if (scene) rtcReleaseScene(scene);
  }
};

namespace {

using Data = TriangleMesh::Data;
using Eigen::Vector3d;

double inf_norm(const Vector3d& v) { return v.cwiseAbs().maxCoeff(); }

// A fixed direction far from every axis and diagonal, for parity rays.
const Vector3d kParityDirection = Vector3d(0.5376, 0.3189, 0.7806).normalized();

// ---------------------------------------------------------------------------
// The watertight ray-triangle test (Woop, Benthin, Wald, "Watertight
// Ray/Triangle Intersection", JCGT 2(1), 2013) in double.
//
// The ray is made the z axis of a sheared frame: kz is the axis of the largest
// |d| component, and a vertex v becomes ((v - o)[kx] - sx (v - o)[kz],
// (v - o)[ky] - sy (v - o)[kz], sz (v - o)[kz]). A vertex's sheared coordinates
// depend on the vertex and the ray only, so every triangle sharing it sees the
// same numbers, and the 2D edge functions f(P, Q) = Px Qy - Py Qx of a shared
// edge are the same (up to sign) for both triangles. They are evaluated with
// their exact sign (a floating-point filter, then Kahan's FMA form), so the 2D
// problem is decided exactly for the sheared (rounded) vertices.
//
// The ray meets a triangle where the origin S = (0, 0) lies inside its 2D
// image. Ties (S exactly on an edge or vertex) are broken by a symbolic
// perturbation S -> S + (eps, eps^2): f_PQ(S + (eps, eps^2)) =
// f_PQ(S) + eps (Py - Qy) + eps^2 (Qx - Px), so an edge with f = 0 counts with
// the sign of (Py - Qy), or of (Qx - Px) where Py = Qy. This is the same
// perturbed point for every triangle, which therefore lies inside exactly the
// triangles whose interior a generic ray through it would cross: one of the
// triangles around an edge or vertex where the surface continues, and an even
// number where it folds, so entering and leaving hits keep alternating.
// Where the ray passes exactly through an edge and the surface folds over
// there (both triangles on the same side of the edge in the sheared plane,
// one facing the ray and one facing away), the ray only touches the solid: both
// triangles reject it, so it is a miss like a tangent ray on an analytic shape.

struct Ray {
  Vector3d o, d;
  int kx = 0, ky = 1, kz = 2;
  double sx = 0, sy = 0, sz = 1;
};

bool make_ray(const Vector3d& o, const Vector3d& d, Ray* r) {
  if (!o.allFinite() || !d.allFinite()) return false;
  int kz = 0;
  d.cwiseAbs().maxCoeff(&kz);
  if (d[kz] == 0) return false;
  int kx = (kz + 1) % 3, ky = (kx + 1) % 3;
  if (d[kz] < 0) std::swap(kx, ky);  // keeps the winding (not needed by the sign-free test, kept as in the paper)
  r->o = o;
  r->d = d;
  r->kx = kx;
  r->ky = ky;
  r->kz = kz;
  r->sx = d[kx] / d[kz];
  r->sy = d[ky] / d[kz];
  r->sz = 1.0 / d[kz];
  return true;
}

struct P2 {
  double x, y, z;
};

inline P2 shear(const Ray& r, const Vector3d& v) {
  const double ax = v[r.kx] - r.o[r.kx], ay = v[r.ky] - r.o[r.ky], az = v[r.kz] - r.o[r.kz];
  return {ax - r.sx * az, ay - r.sy * az, r.sz * az};
}

// Px Qy - Py Qx with the sign of its exact value (0 exactly when it is 0).
// Filter: the two products carry a relative error of at most u = 2^-53 each and
// the difference another u, so |f| > 4e-16 (|a| + |b|) decides the sign.
// Otherwise Kahan's algorithm with an FMA, whose relative error is at most 2u
// (Jeannerod, Louvet, Muller, Math. Comp. 82, 2013): the sign is exact and 0
// comes out exactly when the value is 0.
inline double edge(const P2& p, const P2& q) {
  const double a = p.x * q.y, b = p.y * q.x;
  const double f = a - b;
  if (std::fabs(f) > 4e-16 * (std::fabs(a) + std::fabs(b))) return f;
  const double e = std::fma(-p.y, q.x, b);  // b - p.y q.x exactly
  const double g = std::fma(p.x, q.y, -b);
  return g + e;
}

// The sign of f_PQ at the perturbed origin, for an edge with f_PQ(0) = 0.
inline int perturbed_sign(const P2& p, const P2& q) {
  if (p.y != q.y) return p.y > q.y ? 1 : -1;
  if (p.x != q.x) return q.x > p.x ? 1 : -1;
  return 0;  // the edge projects to a point: it has no 2D extent
}

struct TriHit {
  double t = 0;
  std::uint32_t tri = 0;
  double b[3] = {0, 0, 0};
};

// Whether the ray passing exactly through edge e of triangle k (S on the line
// of the edge, strictly between its ends) sees the surface fold there: the
// neighbour's third vertex R on the same side of the edge as this triangle's X.
// With S = 0 on the line through P and Q, the side of a point Y is the sign of
// f(P, Y) (up to the common sign of P along the line), and the neighbour, which
// evaluates f(Q, .) instead with Q = lambda P, reaches the same verdict.
bool is_fold(const Data& m, const Ray& r, std::uint32_t k, int e, const P2 p[3]) {
  const MeshTriangle& t = m.tri[k];
  const std::uint32_t a = t[e], b = t[(e + 1) % 3];
  const MeshTriangle& tn = m.tri[m.adj[k][e]];
  std::uint32_t rv = tn[0];
  for (std::uint32_t c : tn)
    if (c != a && c != b) rv = c;
  const P2 R = shear(r, m.v[rv]);
  const double side_x = edge(p[e], p[(e + 2) % 3]), side_r = edge(p[e], R);
  return side_x != 0 && side_r != 0 && (side_x > 0) == (side_r > 0);
}

bool test_triangle(const Data& m, const Ray& r, std::uint32_t k, TriHit* out) {
  const MeshTriangle& t = m.tri[k];
  P2 p[3];
  for (int c = 0; c < 3; ++c) p[c] = shear(r, m.v[t[c]]);
  double f[3];
  for (int e = 0; e < 3; ++e) f[e] = edge(p[e], p[(e + 1) % 3]);  // f[0]: AB, f[1]: BC, f[2]: CA
  int s = 0;
  for (double fe : f) {
    if (fe == 0) continue;
    const int se = fe > 0 ? 1 : -1;
    if (s == 0) {
      s = se;
    } else if (se != s) {
      return false;
    }
  }
  if (s == 0) return false;  // the ray lies in the triangle's plane
  int zeros = 0, zero_edge = -1;
  for (int e = 0; e < 3; ++e) {
    if (f[e] != 0) continue;
    if (perturbed_sign(p[e], p[(e + 1) % 3]) != s) return false;
    ++zeros;
    zero_edge = e;
  }
  if (zeros == 1 && is_fold(m, r, k, zero_edge, p)) return false;
  const double det = f[0] + f[1] + f[2];  // all terms of sign s: no cancellation
  out->tri = k;
  out->t = (f[1] * p[0].z + f[2] * p[1].z + f[0] * p[2].z) / det;
  out->b[0] = f[1] / det;  // corner A: the 2D area of (S, B, C)
  out->b[1] = f[2] / det;
  out->b[2] = f[0] / det;
  return std::isfinite(out->t);
}

// ---------------------------------------------------------------------------
// Embree: one user primitive per triangle, in a float frame centred on the
// mesh. The ray handed to Embree is a float copy of the double ray, clipped to
// the (padded) mesh box so that its origin is within the box's size of every
// triangle. Its float rounding then moves it by at most ~2e-7 of the box
// diagonal D near the mesh; the triangles' float boxes are padded by 1e-5 D, so
// float traversal never skips a triangle the double test would accept. Every
// candidate is decided by test_triangle on the double ray kept in the context.

struct Query {
  const Data* mesh = nullptr;
  Ray ray;
  double t_min = 0;
  double t0 = 0;  // the float ray's parameter is t - t0
  bool found = false;
  TriHit best;
  std::vector<TriHit>* all = nullptr;  // collect every hit instead of the nearest
};

struct Context {
  RTCIntersectContext base;  // first member: Embree hands this pointer back to the callbacks
  Query* query;
};

void triangle_bounds(const RTCBoundsFunctionArguments* args) {
  const auto* m = static_cast<const Data*>(args->geometryUserPtr);
  const MeshTriangle& t = m->tri[args->primID];
  Vector3d lo = m->v[t[0]], hi = lo;
  for (int c = 1; c < 3; ++c) {
    lo = lo.cwiseMin(m->v[t[c]]);
    hi = hi.cwiseMax(m->v[t[c]]);
  }
  lo -= m->centre + Vector3d::Constant(m->pad);
  hi += Vector3d::Constant(m->pad) - m->centre;
  RTCBounds* b = args->bounds_o;
  b->lower_x = float_down(lo.x());
  b->lower_y = float_down(lo.y());
  b->lower_z = float_down(lo.z());
  b->upper_x = float_up(hi.x());
  b->upper_y = float_up(hi.y());
  b->upper_z = float_up(hi.z());
}

void triangle_intersect(const RTCIntersectFunctionNArguments* args) {
  if (!args->valid[0]) return;  // rtcIntersect1 only: N == 1
  Query& q = *reinterpret_cast<Context*>(args->context)->query;
  TriHit h;
  if (!test_triangle(*q.mesh, q.ray, args->primID, &h) || !(h.t > q.t_min)) return;
  if (q.all) {
    q.all->push_back(h);
    return;
  }
  if (q.found && !(h.t < q.best.t || (h.t == q.best.t && h.tri < q.best.tri))) return;
  q.best = h;
  q.found = true;
  // Let Embree cull what lies beyond, conservatively: past the padded distance.
  RTCRayN* ray = RTCRayHitN_RayN(args->rayhit, args->N);
  RTCHitN* hit = RTCRayHitN_HitN(args->rayhit, args->N);
  float& tfar = RTCRayN_tfar(ray, args->N, 0);
  tfar = std::min(tfar, float_up(h.t - q.t0 + q.mesh->pad));
  RTCHitN_u(hit, args->N, 0) = static_cast<float>(h.b[1]);
  RTCHitN_v(hit, args->N, 0) = static_cast<float>(h.b[2]);
  const Vector3d& n = q.mesh->n.empty() ? Vector3d::UnitZ() : q.mesh->n[h.tri];
  RTCHitN_Ng_x(hit, args->N, 0) = static_cast<float>(n.x());
  RTCHitN_Ng_y(hit, args->N, 0) = static_cast<float>(n.y());
  RTCHitN_Ng_z(hit, args->N, 0) = static_cast<float>(n.z());
  RTCHitN_primID(hit, args->N, 0) = args->primID;
  RTCHitN_geomID(hit, args->N, 0) = args->geomID;
  RTCHitN_instID(hit, args->N, 0, 0) = args->context->instID[0];
}

// The parameter interval of the ray inside box b; false if it misses.
bool clip(const Eigen::AlignedBox3d& b, const Vector3d& o, const Vector3d& d, double* t_enter, double* t_exit) {
  double lo = -std::numeric_limits<double>::infinity(), hi = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    if (d[i] == 0) {
      if (o[i] < b.min()[i] || o[i] > b.max()[i]) return false;
      continue;
    }
    double ta = (b.min()[i] - o[i]) / d[i], tb = (b.max()[i] - o[i]) / d[i];
    if (ta > tb) std::swap(ta, tb);
    lo = std::max(lo, ta);
    hi = std::min(hi, tb);
  }
  *t_enter = lo;
  *t_exit = hi;
  return lo <= hi;
}

// Runs the query through the BVH (nothing to do if the ray misses the mesh box).
void run(const Data& m, Query& q) {
  Eigen::AlignedBox3d padded = m.box;
  padded.min().array() -= 2 * m.pad;
  padded.max().array() += 2 * m.pad;
  double t_enter = 0, t_exit = 0;
  if (!clip(padded, q.ray.o, q.ray.d, &t_enter, &t_exit)) return;
  const double t_start = std::max(t_enter, q.t_min);
  if (!(t_start <= t_exit)) return;
  q.t0 = t_start - m.pad;
  const Vector3d org = q.ray.o + q.t0 * q.ray.d - m.centre;
  Context ctx;
  rtcInitIntersectContext(&ctx.base);
  ctx.query = &q;
  RTCRayHit rh;
  rh.ray.org_x = static_cast<float>(org.x());
  rh.ray.org_y = static_cast<float>(org.y());
  rh.ray.org_z = static_cast<float>(org.z());
  rh.ray.dir_x = static_cast<float>(q.ray.d.x());
  rh.ray.dir_y = static_cast<float>(q.ray.d.y());
  rh.ray.dir_z = static_cast<float>(q.ray.d.z());
  rh.ray.tnear = 0.0f;  // t_min is applied in double by the callback
  rh.ray.tfar = float_up(t_exit - q.t0 + m.pad);
  rh.ray.time = 0.0f;
  rh.ray.mask = 0xFFFFFFFFu;
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(m.scene, &ctx.base, &rh);
}

std::vector<TriHit> all_hits(const Data& m, const Vector3d& o, const Vector3d& d, double t_min) {
  std::vector<TriHit> hits;
  Query q;
  q.mesh = &m;
  q.t_min = t_min;
  q.all = &hits;
  if (!make_ray(o, d, &q.ray)) return hits;
  run(m, q);
  // A triangle is reported once (a BVH may in principle list a primitive twice).
  std::sort(hits.begin(), hits.end(), [](const TriHit& a, const TriHit& b) { return a.tri < b.tri; });
  hits.erase(std::unique(hits.begin(), hits.end(), [](const TriHit& a, const TriHit& b) { return a.tri == b.tri; }),
             hits.end());
  std::sort(hits.begin(), hits.end(),
            [](const TriHit& a, const TriHit& b) { return a.t < b.t || (a.t == b.t && a.tri < b.tri); });
  return hits;
}

MeshHit make_hit(const Data& m, const TriHit& h) {
  const MeshTriangle& t = m.tri[h.tri];
  const Vector3d &a = m.v[t[0]], &b = m.v[t[1]], &c = m.v[t[2]];
  MeshHit out;
  out.triangle = h.tri;
  out.barycentric = Vector3d(h.b[0], h.b[1], h.b[2]);
  out.hit.t = h.t;
  out.hit.point = h.b[0] * a + h.b[1] * b + h.b[2] * c;  // on the triangle, whatever the distance travelled
  out.hit.normal = m.n[h.tri];
  out.hit.error_mm = kHitRelativeError * (inf_norm(out.hit.point) + m.scale);
  if (m.shading == MeshShading::smooth) {
    const auto& cn = m.corner[h.tri];
    const Vector3d ns = h.b[0] * cn[0] + h.b[1] * cn[1] + h.b[2] * cn[2];
    const double len = ns.norm();
    if (len > 0 && std::isfinite(len)) {
      const double side = ns.dot(out.hit.normal) < 0 ? -1.0 : 1.0;
      const Vector3d unit = side * ns / len;
      out.hit.shading_normal = unit;
      // d(ns)/dp = [n1 - n0, n2 - n0] (G^T G)^-1 G^T with G = [b - a, c - a]: the
      // barycentric gradient along the plane; then the derivative of ns / |ns|.
      Eigen::Matrix<double, 3, 2> g, dn;
      g << b - a, c - a;
      dn << cn[1] - cn[0], cn[2] - cn[0];
      const Eigen::Matrix<double, 2, 3> grad = (g.transpose() * g).inverse() * g.transpose();
      const Eigen::Matrix3d project = Eigen::Matrix3d::Identity() - unit * unit.transpose();
      out.hit.dnormal_dpoint = project * (dn * grad) * (side / len);
    } else {
      out.hit.shading_normal = out.hit.normal;
    }
  }
  return out;
}

// Closest distance from p to triangle (a, b, c) (Ericson, Real-Time Collision
// Detection, 5.1.5).
double point_triangle_distance(const Vector3d& p, const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  const Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return ap.norm();
  const Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return bp.norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + d1 / (d1 - d3) * ab)).norm();
  const Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return cp.norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + d2 / (d2 - d6) * ac)).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return (p - (b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b))).norm();
  const double denom = 1 / (va + vb + vc);
  return (p - (a + ab * (vb * denom) + ac * (vc * denom))).norm();
}

struct DistanceQuery {
  const Data* mesh;
  Vector3d p;
  double nearest;
};

bool distance_callback(RTCPointQueryFunctionArguments* args) {
  auto* q = static_cast<DistanceQuery*>(args->userPtr);
  const MeshTriangle& t = q->mesh->tri[args->primID];
  q->nearest = std::min(q->nearest, point_triangle_distance(q->p, q->mesh->v[t[0]], q->mesh->v[t[1]], q->mesh->v[t[2]]));
  return false;  // the query radius is left as it is
}

// Whether some triangle lies within `radius` of p.
bool surface_within(const Data& m, const Vector3d& p, double radius) {
  DistanceQuery dq{&m, p, std::numeric_limits<double>::infinity()};
  const Vector3d local = p - m.centre;
  RTCPointQuery query;
  query.x = static_cast<float>(local.x());
  query.y = static_cast<float>(local.y());
  query.z = static_cast<float>(local.z());
  query.time = 0.0f;
  query.radius = float_up(radius + 2 * m.pad);
  RTCPointQueryContext context;
  rtcInitPointQueryContext(&context);
  rtcPointQuery(m.scene, &query, &context, distance_callback, &dq);
  return dq.nearest <= radius;
}

bool parity_inside(const Data& m, const Vector3d& p) {
  return all_hits(m, p, kParityDirection, 0).size() % 2 == 1;
}

// ---------------------------------------------------------------------------
// Building.

[[noreturn]] void refuse(const std::string& reason) { throw std::invalid_argument(reason); }

std::string point_text(const Vector3d& p) { return fmt::format("({:.9g}, {:.9g}, {:.9g})", p.x(), p.y(), p.z()); }

// Unit normal of (a, b, c) by the cross product of the two edges at the corner
// opposite the longest edge (the most accurate pair); zero if degenerate.
Vector3d triangle_normal(const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  const Vector3d ab = b - a, bc = c - b, ca = a - c;
  const double lab = ab.squaredNorm(), lbc = bc.squaredNorm(), lca = ca.squaredNorm();
  Vector3d cross;
  if (lab >= lbc && lab >= lca) {
    cross = bc.cross(ca);  // at c
  } else if (lbc >= lca) {
    cross = ca.cross(ab);  // at a
  } else {
    cross = ab.cross(bc);  // at b
  }
  const double len = cross.norm();
  // Degenerate: the sine of every angle at the rounding level.
  const double longest = std::sqrt(std::max({lab, lbc, lca}));
  if (!(len > 1e-13 * longest * longest)) return Vector3d::Zero();
  return cross / len;
}

void check_and_link(const std::vector<Eigen::Vector3d>& v, const std::vector<MeshTriangle>& tri,
                    std::vector<MeshTriangle>* adj) {
  struct HalfEdge {
    std::uint64_t key;  // (min vertex, max vertex)
    std::uint32_t tri;
    std::uint8_t edge;
    bool forward;  // runs from the lower vertex index to the higher
  };
  std::vector<HalfEdge> half;
  half.reserve(3 * tri.size());
  for (std::size_t k = 0; k < tri.size(); ++k)
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t a = tri[k][e], b = tri[k][(e + 1) % 3];
      const std::uint64_t lo = std::min(a, b), hi = std::max(a, b);
      half.push_back({lo << 32 | hi, static_cast<std::uint32_t>(k), static_cast<std::uint8_t>(e), a < b});
    }
  std::sort(half.begin(), half.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return x.key < y.key || (x.key == y.key && x.tri < y.tri);
  });
  adj->assign(tri.size(), MeshTriangle{0, 0, 0});
  std::size_t open = 0;
  std::string first_open;
  for (std::size_t i = 0; i < half.size();) {
    std::size_t j = i;
    while (j < half.size() && half[j].key == half[i].key) ++j;
    const std::uint32_t a = static_cast<std::uint32_t>(half[i].key >> 32), b = static_cast<std::uint32_t>(half[i].key);
    const std::size_t count = j - i;
    if (count == 1) {
      if (open++ == 0)
        first_open = fmt::format("the edge between vertices {} {} and {} {} belongs to triangle {} only", a,
                                 point_text(v[a]), b, point_text(v[b]), half[i].tri);
    } else if (count > 2) {
      refuse(fmt::format("the edge between vertices {} and {} is shared by {} triangles ({}, {}, {}{}): the surface "
                         "is not a manifold",
                         a, b, count, half[i].tri, half[i + 1].tri, half[i + 2].tri, count > 3 ? ", ..." : ""));
    } else {
      if (half[i].forward == half[i + 1].forward)
        refuse(fmt::format("inconsistent orientation: triangles {} and {} run through the edge between vertices {} "
                           "and {} in the same direction",
                           half[i].tri, half[i + 1].tri, a, b));
      (*adj)[half[i].tri][half[i].edge] = half[i + 1].tri;
      (*adj)[half[i + 1].tri][half[i + 1].edge] = half[i].tri;
    }
    i = j;
  }
  if (open > 0)
    refuse(fmt::format("the mesh is open: {} ({} edge{} of a single triangle); open meshes are refused", first_open,
                       open, open == 1 ? "" : "s"));
}

// Reverses triangle k: (a, b, c) -> (a, c, b); its edges become (a, c) = old
// edge 2, (c, b) = old edge 1, (b, a) = old edge 0.
void reverse(Data& m, std::size_t k, std::vector<std::array<Vector3d, 3>>* corner) {
  std::swap(m.tri[k][1], m.tri[k][2]);
  std::swap(m.adj[k][0], m.adj[k][2]);
  if (corner && !corner->empty()) std::swap((*corner)[k][1], (*corner)[k][2]);
}

void build_bvh(Data& m) {
  RTCDevice device = embree_device();
  m.scene = rtcNewScene(device);
  rtcSetSceneFlags(m.scene, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(m.scene, RTC_BUILD_QUALITY_HIGH);
  RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
  rtcSetGeometryUserPrimitiveCount(geometry, static_cast<unsigned>(m.tri.size()));
  rtcSetGeometryUserData(geometry, &m);
  rtcSetGeometryBoundsFunction(geometry, triangle_bounds, nullptr);
  rtcSetGeometryIntersectFunction(geometry, triangle_intersect);
  rtcSetGeometryBuildQuality(geometry, RTC_BUILD_QUALITY_HIGH);
  rtcCommitGeometry(geometry);
  rtcAttachGeometry(m.scene, geometry);
  rtcReleaseGeometry(geometry);
  rtcCommitScene(m.scene);
  check_embree("building a triangle-mesh BVH");
}

std::vector<std::array<Vector3d, 3>> given_normals(const MeshArrays& in) {
  const std::size_t nt = in.triangles.size();
  std::vector<MeshTriangle> index = in.normal_triangles;
  if (index.empty()) {
    if (in.normals.size() != in.vertices_mm.size())
      refuse(fmt::format("{} vertex normals for {} vertices (give one per vertex, or normal_triangles)",
                         in.normals.size(), in.vertices_mm.size()));
    index = in.triangles;
  } else if (index.size() != nt) {
    refuse(fmt::format("normal_triangles has {} entries for {} triangles", index.size(), nt));
  }
  std::vector<std::array<Vector3d, 3>> corner(nt);
  for (std::size_t k = 0; k < nt; ++k)
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t i = index[k][c];
      if (i >= in.normals.size())
        refuse(fmt::format("triangle {} refers to normal {}, but there are {} normals", k, i, in.normals.size()));
      const double len = in.normals[i].norm();
      if (!std::isfinite(len) || len == 0) refuse(fmt::format("normal {} is zero or not finite", i));
      corner[k][c] = in.normals[i] / len;
    }
  return corner;
}

// Corner normals from the facet normals around the vertex, smoothing only across
// triangles whose normals lie within the crease angle of the corner's own
// triangle. Weights of Max ("Weights for computing vertex normals from facet
// normals", J. Graphics Tools 4(2), 1999): sin(corner angle) / (|e1| |e2|), i.e.
// |e1 x e2| / (|e1|^2 |e2|^2), which give the exact normal for vertices on a
// sphere and second-order accuracy on smooth surfaces; angle weights are only
// first order on irregular meshes (1.6e-3 against 5.6e-4 rad at level 5 of the
// icosphere test, halving rather than quartering per level).
std::vector<std::array<Vector3d, 3>> computed_normals(const Data& m, double crease_angle_deg) {
  const std::size_t nt = m.tri.size(), nv = m.v.size();
  std::vector<std::array<double, 3>> weight(nt);
  for (std::size_t k = 0; k < nt; ++k)
    for (int c = 0; c < 3; ++c) {
      const Vector3d& p = m.v[m.tri[k][c]];
      const Vector3d e1 = m.v[m.tri[k][(c + 1) % 3]] - p, e2 = m.v[m.tri[k][(c + 2) % 3]] - p;
      weight[k][c] = e1.cross(e2).norm() / (e1.squaredNorm() * e2.squaredNorm());
    }
  // Corners around each vertex (CSR).
  std::vector<std::uint32_t> start(nv + 1, 0);
  for (const MeshTriangle& t : m.tri)
    for (std::uint32_t i : t) ++start[i + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<std::uint32_t> fill(start.begin(), start.end() - 1), corner_of(3 * nt);
  for (std::size_t k = 0; k < nt; ++k)
    for (int c = 0; c < 3; ++c) corner_of[fill[m.tri[k][c]]++] = static_cast<std::uint32_t>(3 * k + c);
  const double cos_crease = std::cos(crease_angle_deg * M_PI / 180) - 1e-12;
  std::vector<std::array<Vector3d, 3>> out(nt);
  for (std::size_t k = 0; k < nt; ++k)
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t vi = m.tri[k][c];
      Vector3d sum = Vector3d::Zero();
      for (std::uint32_t q = start[vi]; q < start[vi + 1]; ++q) {
        const std::uint32_t j = corner_of[q] / 3, cj = corner_of[q] % 3;
        if (j == k || m.n[j].dot(m.n[k]) >= cos_crease) sum += weight[j][cj] * m.n[j];
      }
      const double len = sum.norm();
      out[k][c] = len > 0 ? Vector3d(sum / len) : m.n[k];
    }
  return out;
}

}  // namespace

// ---------------------------------------------------------------------------

TriangleMesh build_triangle_mesh(MeshArrays in, const MeshBuildOptions& options) {
  const std::size_t nv = in.vertices_mm.size(), nt = in.triangles.size();
  if (nt == 0) refuse("the mesh has no triangles");
  if (nv > std::numeric_limits<std::uint32_t>::max() || nt > std::numeric_limits<std::uint32_t>::max() / 2)
    refuse("the mesh is too large (more than 2^31 triangles or 2^32 vertices)");
  if (!(options.crease_angle_deg > 0 && options.crease_angle_deg <= 180))
    refuse(fmt::format("the crease angle must lie in (0, 180] degrees, got {}", options.crease_angle_deg));
  for (std::size_t i = 0; i < nv; ++i)
    if (!in.vertices_mm[i].allFinite()) refuse(fmt::format("vertex {} is not finite", i));
  for (std::size_t k = 0; k < nt; ++k)
    for (std::uint32_t i : in.triangles[k])
      if (i >= nv) refuse(fmt::format("triangle {} refers to vertex {}, but there are {} vertices", k, i, nv));

  std::vector<std::array<Vector3d, 3>> corner;
  const bool normals_given = !in.normals.empty() || !in.normal_triangles.empty();
  if (options.shading == MeshShading::smooth && normals_given) corner = given_normals(in);

  auto data = std::make_shared<Data>();
  Data& m = *data;
  m.v = std::move(in.vertices_mm);
  m.tri = in.triangles;
  m.shading = options.shading;
  m.n.resize(nt);
  for (std::size_t k = 0; k < nt; ++k) {
    const MeshTriangle& t = m.tri[k];
    m.n[k] = (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) ? Vector3d::Zero()
                                                           : triangle_normal(m.v[t[0]], m.v[t[1]], m.v[t[2]]);
    if (m.n[k].isZero())
      refuse(fmt::format("triangle {} (vertices {}, {}, {}) is degenerate: zero area", k, t[0], t[1], t[2]));
  }
  check_and_link(m.v, m.tri, &m.adj);

  for (const MeshTriangle& t : m.tri)
    for (std::uint32_t i : t) m.box.extend(m.v[i]);
  m.centre = m.box.center();
  m.pad = 1e-5 * m.box.diagonal().norm();
  for (const MeshTriangle& t : m.tri)
    for (std::uint32_t i : t) m.scale = std::max(m.scale, inf_norm(m.v[i]));

  // Parts (connected through edges) and their signed volumes, about the box
  // centre to keep the terms small.
  std::vector<int> part(nt, -1);
  std::vector<double> part_volume;
  std::vector<Eigen::AlignedBox3d> part_box;
  std::vector<std::uint32_t> part_first;
  for (std::size_t seed = 0; seed < nt; ++seed) {
    if (part[seed] >= 0) continue;
    const int id = static_cast<int>(part_volume.size());
    double volume = 0;
    Eigen::AlignedBox3d box;
    std::vector<std::uint32_t> stack{static_cast<std::uint32_t>(seed)};
    part[seed] = id;
    while (!stack.empty()) {
      const std::uint32_t k = stack.back();
      stack.pop_back();
      const Vector3d a = m.v[m.tri[k][0]] - m.centre, b = m.v[m.tri[k][1]] - m.centre, c = m.v[m.tri[k][2]] - m.centre;
      volume += a.dot(b.cross(c)) / 6;
      for (std::uint32_t i : m.tri[k]) box.extend(m.v[i]);
      for (std::uint32_t j : m.adj[k])
        if (part[j] < 0) {
          part[j] = id;
          stack.push_back(j);
        }
    }
    const double size = box.diagonal().norm();
    if (!(std::fabs(volume) > 1e-9 * size * size * size))
      refuse(fmt::format("the closed part containing triangle {} encloses no volume", seed));
    part_volume.push_back(volume);
    part_box.push_back(box);
    part_first.push_back(static_cast<std::uint32_t>(seed));
  }
  m.parts = static_cast<int>(part_volume.size());

  build_bvh(m);

  // Orientation: a part nested in an odd number of others bounds a cavity and
  // must enclose negative volume; every other part positive volume. Nesting is
  // found by ray parity from a point on each part (the centroid of one of its
  // triangles) against the other parts.
  std::vector<int> depth(m.parts, 0);
  if (m.parts > 1) {
    for (int a = 0; a < m.parts; ++a) {
      const MeshTriangle& t = m.tri[part_first[a]];
      const Vector3d p = (m.v[t[0]] + m.v[t[1]] + m.v[t[2]]) / 3;
      std::vector<int> crossings(m.parts, 0);
      for (const TriHit& h : all_hits(m, p, kParityDirection, 0)) ++crossings[part[h.tri]];
      for (int b = 0; b < m.parts; ++b)
        if (b != a && crossings[b] % 2 == 1) ++depth[a];
    }
  }
  std::vector<bool> flip(m.parts);
  for (int a = 0; a < m.parts; ++a) {
    flip[a] = (part_volume[a] > 0) == (depth[a] % 2 == 1);
    if (flip[a]) ++m.flipped;
    m.volume += flip[a] ? -part_volume[a] : part_volume[a];
  }
  for (std::size_t k = 0; k < nt; ++k)
    if (flip[part[k]]) {
      reverse(m, k, &corner);
      m.n[k] = -m.n[k];
    }
  if (!(m.volume > 0)) refuse("the nested parts of the mesh enclose no volume (cavities larger than their shells)");

  if (options.shading == MeshShading::smooth && normals_given) {
    // Given normals go with the outward side, whichever way the input was wound.
    for (std::size_t k = 0; k < nt; ++k)
      for (Vector3d& c : corner[k])
        if (c.dot(m.n[k]) < 0) c = -c;
    m.corner = std::move(corner);
  } else if (options.shading == MeshShading::smooth) {
    m.corner = computed_normals(m, options.crease_angle_deg);
  }

  TriangleMesh mesh;
  mesh.data_ = std::move(data);
  return mesh;
}

const std::vector<Eigen::Vector3d>& TriangleMesh::vertices_mm() const {
  static const std::vector<Eigen::Vector3d> none;
  return data_ ? data_->v : none;
}
const std::vector<MeshTriangle>& TriangleMesh::triangles() const {
  static const std::vector<MeshTriangle> none;
  return data_ ? data_->tri : none;
}
const Eigen::Vector3d& TriangleMesh::triangle_normal(std::size_t k) const {
  if (!data_) throw std::out_of_range("triangle_normal of an empty mesh");
  return data_->n.at(k);
}
std::array<Eigen::Vector3d, 3> TriangleMesh::corner_normals(std::size_t k) const {
  if (!data_) throw std::out_of_range("corner_normals of an empty mesh");
  if (data_->shading == MeshShading::smooth) return data_->corner.at(k);
  const Vector3d& n = data_->n.at(k);
  return {n, n, n};
}
MeshShading TriangleMesh::shading() const { return data_ ? data_->shading : MeshShading::flat; }
double TriangleMesh::volume_mm3() const { return data_ ? data_->volume : 0; }
int TriangleMesh::part_count() const { return data_ ? data_->parts : 0; }
int TriangleMesh::flipped_part_count() const { return data_ ? data_->flipped : 0; }

std::optional<MeshHit> intersect_mesh(const TriangleMesh& mesh, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                                      double t_min) {
  const Data* m = mesh.data();
  if (!m) return std::nullopt;
  Query q;
  q.mesh = m;
  q.t_min = t_min;
  if (!make_ray(o, d, &q.ray)) return std::nullopt;
  run(*m, q);
  if (!q.found) return std::nullopt;
  return make_hit(*m, q.best);
}

std::optional<Hit> intersect(const TriangleMesh& m, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min) {
  auto h = intersect_mesh(m, o, d, t_min);
  if (!h) return std::nullopt;
  return std::move(h->hit);
}

std::vector<MeshHit> intersect_all(const TriangleMesh& mesh, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                                   double t_min) {
  std::vector<MeshHit> out;
  const Data* m = mesh.data();
  if (!m) return out;
  for (const TriHit& h : all_hits(*m, o, d, t_min)) out.push_back(make_hit(*m, h));
  return out;
}

std::optional<MeshHit> intersect_triangle(const TriangleMesh& mesh, std::uint32_t triangle, const Eigen::Vector3d& o,
                                          const Eigen::Vector3d& d, double t_min) {
  const Data* m = mesh.data();
  if (!m || triangle >= m->tri.size()) return std::nullopt;
  Ray r;
  TriHit h;
  if (!make_ray(o, d, &r) || !test_triangle(*m, r, triangle, &h) || !(h.t > t_min)) return std::nullopt;
  return make_hit(*m, h);
}

bool contains(const TriangleMesh& mesh, const Eigen::Vector3d& p, double margin_mm) {
  const Data* m = mesh.data();
  if (!m || !p.allFinite() || !std::isfinite(margin_mm)) return false;
  const bool inside = m->box.contains(p) && parity_inside(*m, p);
  if (margin_mm >= 0) return inside && !surface_within(*m, p, margin_mm);
  if (inside) return true;
  Eigen::AlignedBox3d grown = m->box;
  grown.min().array() += margin_mm;
  grown.max().array() -= margin_mm;
  return grown.contains(p) && surface_within(*m, p, -margin_mm);
}

double scale_mm(const TriangleMesh& m) { return m.data() ? m.data()->scale : 0; }

Eigen::AlignedBox3d bounds_mm(const TriangleMesh& m) { return m.data() ? m.data()->box : Eigen::AlignedBox3d(); }

}  // namespace glasspiv
