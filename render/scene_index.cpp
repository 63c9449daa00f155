#include "render/scene_index.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "render/embree_device.h"
#include "render/float_outward.h"

namespace glasspiv {

namespace {

Eigen::AlignedBox3d union_bounds(const std::vector<Shape>& shapes) {
  Eigen::AlignedBox3d box;  // empty
  for (const Shape& s : shapes) box.extend(bounds_mm(s));
  return box;
}

}  // namespace

SceneIndex::SceneIndex(const std::vector<Shape>& shapes) : bounds_(union_bounds(shapes)) {
  for (const Shape& s : shapes) max_scale_ = std::max(max_scale_, scale_mm(s));
}

bool SceneIndex::may_hit(const Eigen::Vector3d& o, const Eigen::Vector3d& d) const {
  if (bounds_.isEmpty()) return false;
  // A generous margin: the test must never reject what an exact intersect
  // would accept (a grazing ray on the box's face).
  const double margin = 1e-6 * (bounds_.max().cwiseAbs().maxCoeff() + bounds_.min().cwiseAbs().maxCoeff() + 1.0);
  double t_near = -std::numeric_limits<double>::infinity(), t_far = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    const double lo = bounds_.min()[i] - margin, hi = bounds_.max()[i] + margin;
    if (d[i] == 0) {
      if (o[i] < lo || o[i] > hi) return false;
      continue;
    }
    double ta = (lo - o[i]) / d[i], tb = (hi - o[i]) / d[i];
    if (ta > tb) std::swap(ta, tb);
    t_near = std::max(t_near, ta);
    t_far = std::min(t_far, tb);
  }
  return t_near <= t_far && t_far >= 0;
}

LinearSceneIndex::LinearSceneIndex(std::vector<Shape> shapes) : SceneIndex(shapes), shapes_(std::move(shapes)) {}

std::optional<Hit> LinearSceneIndex::first_hit(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min,
                                               int skip_index) const {
  return glasspiv::first_hit(shapes_, o, d, t_min, skip_index);  // nearest, ties to the lower index
}

// ---------------------------------------------------------------------------
// Embree: one user geometry, one primitive per solid. Embree traverses its BVH
// with a float copy of the ray; the primitive callback runs the exact double
// intersect on the double ray carried in the context. Boxes are padded so that
// the float traversal never skips a solid the double ray meets.

struct EmbreeSceneIndex::Impl {
  RTCScene scene = nullptr;
  std::vector<Shape> shapes;
  std::vector<Eigen::AlignedBox3d> padded;
  // Per solid: its sphere, compact (the common candidate), or nullptr.
  std::vector<Sphere> spheres;
  std::vector<const Sphere*> sphere_of;
};

namespace {

// The nearest candidate so far, (t, index) lexicographically smallest like
// keep_nearest. A sphere's full hit is built once, for the winner, after the
// traversal; any other solid's hit is kept as it comes.
struct QueryContext {
  RTCIntersectContext base;  // first member: Embree hands back a pointer to it
  const std::vector<Shape>* shapes;
  const std::vector<const Sphere*>* sphere_of;  // per solid: its sphere, or nullptr
  const Eigen::Vector3d* o;
  const Eigen::Vector3d* d;
  double t_min;
  int skip_index;
  bool have_best = false;
  double best_t = 0;
  int best_index = -1;
  std::optional<Hit> best_other;  // the hit of best_index when it is not a sphere
};

void solid_bounds(const RTCBoundsFunctionArguments* args) {
  const auto* boxes = static_cast<const std::vector<Eigen::AlignedBox3d>*>(args->geometryUserPtr);
  const Eigen::AlignedBox3d& b = (*boxes)[args->primID];
  RTCBounds* out = args->bounds_o;
  // Rounded outwards so the float box contains the double one.
  out->lower_x = float_down(b.min().x());
  out->lower_y = float_down(b.min().y());
  out->lower_z = float_down(b.min().z());
  out->upper_x = float_up(b.max().x());
  out->upper_y = float_up(b.max().y());
  out->upper_z = float_up(b.max().z());
}

void solid_intersect(const RTCIntersectFunctionNArguments* args) {
  if (!args->valid[0]) return;
  auto* q = reinterpret_cast<QueryContext*>(args->context);
  const int index = static_cast<int>(args->primID);
  if (index == q->skip_index) return;
  // Whether t (of this candidate) is the best so far; if so it is kept, and
  // Embree culls candidates beyond it, conservatively (next float up).
  const auto keep = [&](double t) {
    if (q->have_best && !(t < q->best_t || (t == q->best_t && index < q->best_index))) return false;
    q->have_best = true;
    q->best_t = t;
    q->best_index = index;
    float& tfar = RTCRayN_tfar(RTCRayHitN_RayN(args->rayhit, args->N), args->N, 0);
    tfar = std::min(tfar, float_up(t));
    return true;
  };
  if (const Sphere* sphere = (*q->sphere_of)[args->primID]) {
    // Its hit is built after the traversal, for the winner only (best_other is
    // then not read). No optional<Hit> here: making one zero-fills it.
    const std::optional<double> t = sphere_hit_t(*sphere, *q->o, *q->d, q->t_min);
    if (t) keep(*t);
    return;
  }
  std::optional<Hit> other = intersect((*q->shapes)[args->primID], *q->o, *q->d, q->t_min);
  if (other && keep(other->t)) q->best_other = std::move(other);
}

}  // namespace

EmbreeSceneIndex::EmbreeSceneIndex(std::vector<Shape> shapes) : SceneIndex(shapes), impl_(std::make_unique<Impl>()) {
  impl_->shapes = std::move(shapes);
  // Float traversal error: about 1.2e-7 of (|origin| + distance travelled);
  // 1e-4 of the scene's size covers origins up to ~100 scene sizes away.
  const double magnitude = bounds_.isEmpty() ? 1.0
                                             : std::max({bounds_.min().cwiseAbs().maxCoeff(),
                                                         bounds_.max().cwiseAbs().maxCoeff(), 1.0});
  const double pad = 1e-4 * magnitude;
  for (const Shape& s : impl_->shapes) {
    Eigen::AlignedBox3d b = glasspiv::bounds_mm(s);
    b.min().array() -= pad;
    b.max().array() += pad;
    impl_->padded.push_back(b);
  }
  for (const Shape& s : impl_->shapes)
    if (const auto* sphere = std::get_if<Sphere>(&s)) impl_->spheres.push_back(*sphere);
  std::size_t next_sphere = 0;
  for (const Shape& s : impl_->shapes)
    impl_->sphere_of.push_back(std::holds_alternative<Sphere>(s) ? &impl_->spheres[next_sphere++] : nullptr);
  RTCDevice device = embree_device();
  impl_->scene = rtcNewScene(device);
  rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_HIGH);
  if (!impl_->shapes.empty()) {
    RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(geometry, static_cast<unsigned>(impl_->shapes.size()));
    rtcSetGeometryUserData(geometry, &impl_->padded);
    rtcSetGeometryBoundsFunction(geometry, solid_bounds, nullptr);
    rtcSetGeometryIntersectFunction(geometry, solid_intersect);
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(impl_->scene, geometry);
    rtcReleaseGeometry(geometry);
  }
  rtcCommitScene(impl_->scene);
  check_embree("building the scene BVH");
}

EmbreeSceneIndex::~EmbreeSceneIndex() {
  if (impl_ && impl_->scene) rtcReleaseScene(impl_->scene);
}

std::optional<Hit> EmbreeSceneIndex::first_hit(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min,
                                               int skip_index) const {
  QueryContext q;
  rtcInitIntersectContext(&q.base);
  q.shapes = &impl_->shapes;
  q.sphere_of = &impl_->sphere_of;
  q.o = &o;
  q.d = &d;
  q.t_min = t_min;
  q.skip_index = skip_index;
  RTCRayHit rh;
  rh.ray.org_x = static_cast<float>(o.x());
  rh.ray.org_y = static_cast<float>(o.y());
  rh.ray.org_z = static_cast<float>(o.z());
  rh.ray.dir_x = static_cast<float>(d.x());
  rh.ray.dir_y = static_cast<float>(d.y());
  rh.ray.dir_z = static_cast<float>(d.z());
  rh.ray.tnear = 0.0f;  // t_min is applied in double by the callback
  rh.ray.tfar = INFINITY;
  rh.ray.time = 0.0f;
  rh.ray.mask = 0xFFFFFFFFu;
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(impl_->scene, &q.base, &rh);
  if (!q.have_best) return std::nullopt;
  std::optional<Hit> best;
  if (const Sphere* sphere = impl_->sphere_of[static_cast<std::size_t>(q.best_index)])
    best = sphere_hit(*sphere, o, d, q.best_t);
  else
    best = std::move(q.best_other);
  best->shape_index = q.best_index;
  return best;
}

std::unique_ptr<SceneIndex> make_scene_index(std::vector<Shape> shapes) {
  if (shapes.size() < 4) return std::make_unique<LinearSceneIndex>(std::move(shapes));
  return std::make_unique<EmbreeSceneIndex>(std::move(shapes));
}

}  // namespace glasspiv
