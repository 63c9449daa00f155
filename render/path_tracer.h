#pragma once
// Exact (analytic-geometry) path tracer with deterministic Fresnel splitting:
// one camera ray in, the tree of its reflected and refracted branches out, with
// every crossing of the light sheet made in the fluid. The model, the rules and
// what is tested are in docs/tracer.md. Double precision, mm. No I/O.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <vector>

#include "render/scene_index.h"
#include "render/shapes.h"

namespace glasspiv {

// Optical behaviour of a solid. Glass: a dielectric of refractive index n
// (absolute, like the fluid's) with Beer-Lambert attenuation alpha (natural
// log, 1/mm). Opaque: ends the branch; albedo is its diffuse reflectance
// (what a render of the setup shows under uniform light).
struct TraceMaterial {
  enum class Kind { glass, opaque };
  Kind kind = Kind::glass;
  double refractive_index = 1.5;
  double absorption_per_mm = 0;
  double albedo = 0;

  static TraceMaterial glass(double n, double absorption_per_mm = 0) { return {Kind::glass, n, absorption_per_mm, 0}; }
  static TraceMaterial opaque(double albedo = 0) { return {Kind::opaque, 1, 0, albedo}; }
};

struct TraceSolid {
  Shape shape;
  TraceMaterial material;
};

// The light sheet: the plane through origin_mm spanned by the orthonormal axes
// s_axis, t_axis. Sheet coordinates of a point p: s = (p - origin) . s_axis,
// t = (p - origin) . t_axis; crossings count where |s| <= extent_s_mm / 2 and
// |t| <= extent_t_mm / 2 (the extent is centred on the origin).
struct SheetPlane {
  Eigen::Vector3d origin_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d s_axis = Eigen::Vector3d::UnitX();
  Eigen::Vector3d t_axis = Eigen::Vector3d::UnitY();
  double extent_s_mm = 100;
  double extent_t_mm = 100;

  Eigen::Vector3d normal() const { return s_axis.cross(t_axis); }
};

// Solids must not overlap (they may touch, as the spheres of a packing do).
struct TraceScene {
  std::vector<TraceSolid> solids;
  double fluid_index = 1.0;  // absolute index of the medium around the solids
  SheetPlane sheet;
};

struct TraceOptions {
  bool reflections = true;  // false: reflected branches are not spawned (their weight is "skipped")
  // A branch whose weight falls below this is cut (its weight recorded). On
  // the reactor 1e-2 renders within 2 % of 1e-3's error in 37 % of its time
  // (bench/RESULTS.md); lower it to follow ghost images of ghost images.
  double min_weight = 1e-2;
  // Branches that have been reflected at least once (ghost light) are cut
  // below this instead where it is higher. A ghost that goes on through
  // sphere after sphere costs most of a render's segments for a few per cent
  // of the light; bench/RESULTS.md tables what a higher cut costs in error.
  // 0 (or anything <= min_weight): min_weight applies to every branch.
  double min_weight_reflected = 0;
  int max_depth = 32;        // most interface events on one path; a deeper branch is cut
  // Read by build_transport_map only (render/reflection_grid.h): with a grid
  // g > 1 the reflected subtrees are traced on every g-th camera sample of
  // each axis and interpolated between four such samples where a subtree
  // agrees among them to within reflection_grid_tolerance (a fraction of a
  // pixel's footprint on the sheet, and of each weight); elsewhere it is
  // traced. 1: every sample traced whole.
  int reflection_grid = 1;
  double reflection_grid_tolerance = 0.1;
  // With a grid g > 1, also interpolate a sample whole (its refracted chain
  // too: no ray traced) where its four anchors agree on everything: their
  // refracted chains as a subtree must, and every subtree. An approximation
  // of the refracted light as well (bench/RESULTS.md tables its error); works
  // with reflections off too. false: each sample's refracted chain is traced.
  bool grid_whole_samples = false;
  // With a grid g > 1: 2 traces the anchors themselves on a coarser grid of
  // 2g only and interpolates each other anchor whole where its 2g cell agrees
  // whole (as grid_whole_samples does for a sample; with or without it), so
  // smooth regions cost one traced sample in (2g)^2; elsewhere the anchor is
  // traced. An approximation (bench/RESULTS.md tables its error). 1: every
  // anchor traced.
  int reflection_grid_levels = 1;
  // Record the solid of every surface event in TraceResult::solids_met (the
  // model fit re-traces only the pixels whose paths meet the part it moves).
  bool record_solids_met = false;
};

// Whether build_transport_map uses the reflection grid: g > 1 and something
// for it to interpolate (reflected subtrees, or whole samples).
inline bool reflection_grid_in_effect(const TraceOptions& o) {
  return o.reflection_grid > 1 && (o.reflections || o.grid_whole_samples);
}

// Interface events on the path before the crossing: none, refractions only,
// at least one reflection (total internal reflection included).
enum class CrossingTag { direct, refracted_only, with_reflections };

struct SheetCrossing {
  double s_mm = 0, t_mm = 0;
  double weight = 0;
  int depth = 0;  // interface events on the path so far
  CrossingTag tag = CrossingTag::direct;
  // The surfaces met before, and how (refracted or reflected), hashed: equal
  // for rays that took the same path.
  std::uint64_t path = 0;
  int subtree = -1;  // index into TraceResult::subtrees; -1 on the camera ray's refracted chain
  Eigen::Vector3d point_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();
  // Footprint Jacobian d(s, t)/d(pixel col, row) in mm per pixel, from the ray
  // differentials (zero when the camera ray carried none).
  Eigen::Matrix2d dst_dpixel = Eigen::Matrix2d::Zero();
};

// A branch that left the scene (hit nothing): the background in `direction`.
struct BackgroundRay {
  Eigen::Vector3d from_mm = Eigen::Vector3d::Zero();  // last surface point (or the ray's origin)
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();
  double weight = 0;
  int depth = 0;
  CrossingTag tag = CrossingTag::direct;
};

struct OpaqueHit {
  int solid_index = -1;
  Eigen::Vector3d point_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  double weight = 0;
  int depth = 0;
  CrossingTag tag = CrossingTag::direct;
};

struct TraceCounts {
  long branches_traced = 0;  // segments followed (the initial ray is one)
  long cut_by_weight = 0;    // branches with 0 < weight < min_weight (min_weight_reflected) not followed
  long cut_by_depth = 0;     // branches beyond max_depth not followed
  long tir_events = 0;       // total internal reflections
  long reflections_skipped = 0;  // reflected branches not spawned (options.reflections = false)
  long medium_corrections = 0;   // a spawned branch found itself in another medium (contacts, edges)
  long closed_form = 0;          // camera rays proven to miss every solid (bounds test): no BVH query
  long shading_fallbacks = 0;    // events where a smooth normal would have sent the ray to the wrong
                                 // side of the surface, so the geometric normal was used
};

// A branch reflected off the camera ray's refracted chain (the chain of
// refractions that carries most of the light), with everything that descends
// from it: the unit the reflection grid interpolates (render/reflection_grid.h).
struct ReflectedSubtree {
  std::uint64_t id = 0;  // the reflected branch's path: equal for rays whose refracted chains met
                         // the same surfaces up to that reflection
  double weight = 0;     // at the reflection
  double background_weight = 0, opaque_weight = 0, cut_weight = 0;  // its shares of TraceResult's
};

// Subtrees (ReflectedSubtree::id) the caller provides otherwise: trace_ray
// does not spawn subtree ids[i] where its weight at the reflection lies in
// [min_weight[i], max_weight[i]] (where it does not, say a total internal
// reflection where the caller's subtrees were partial ones, it is traced),
// and lists the ones it deferred in TraceResult::deferred.
struct DeferredSubtrees {
  const std::uint64_t* ids = nullptr;
  const double* min_weight = nullptr;
  const double* max_weight = nullptr;
  std::size_t count = 0;
};

// Where the unit weight of the camera ray went. Every bit of it ends in exactly
// one of these bins, so terminal_weight_sum() == 1 up to round-off.
struct TraceResult {
  std::vector<SheetCrossing> crossings;
  std::vector<BackgroundRay> background;
  std::vector<OpaqueHit> opaque_hits;
  TraceCounts counts;
  double background_weight = 0;
  double opaque_weight = 0;
  double absorbed_weight = 0;         // Beer-Lambert loss inside glass
  double cut_by_weight_weight = 0;
  double cut_by_depth_weight = 0;
  double skipped_reflection_weight = 0;
  std::vector<ReflectedSubtree> subtrees;  // spawned off the refracted chain, in order
  std::vector<std::uint64_t> deferred;     // ids of the DeferredSubtrees met, in order
  double deferred_weight = 0;              // their weight
  // With TraceOptions::record_solids_met: the solid index of every surface
  // event (and opaque end), in the order traced, repeats kept; else empty.
  std::vector<int> solids_met;

  // Whether the ray met any solid (a segment after the first, or an opaque end).
  bool met_solid() const { return counts.branches_traced > 1 || !opaque_hits.empty(); }

  double terminal_weight_sum() const {
    return background_weight + opaque_weight + absorbed_weight + cut_by_weight_weight + cut_by_depth_weight +
           skipped_reflection_weight + deferred_weight;
  }
};

// A camera ray with its ray differentials: how the direction changes per pixel
// of the image (col, row); a central camera's origin does not change.
struct CameraRay {
  Eigen::Vector3d origin_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();  // need not be unit; normalised (with its derivative)
  Eigen::Matrix<double, 3, 2> ddirection_dpixel = Eigen::Matrix<double, 3, 2>::Zero();
};

// The nearest-hit index of the scene's solids (Embree for all but tiny scenes).
std::unique_ptr<SceneIndex> make_scene_index(const TraceScene& scene);

// Traces one camera ray through the scene into *result (cleared first; its
// buffers are reused, so a caller tracing many rays allocates once). index must
// have been made from this scene. Ray differentials are carried through every
// transfer, refraction and reflection (Igehy 1999), giving each crossing its
// footprint Jacobian. Throws std::invalid_argument for a zero or non-finite
// direction or origin. Deterministic: the same input gives the same output,
// branch order included (depth first, refracted branch before reflected), so
// the refracted chain's crossings come first and each subtree's are contiguous.
void trace_ray(const TraceScene& scene, const SceneIndex& index, const CameraRay& ray, const TraceOptions& options,
               TraceResult* result, const DeferredSubtrees& deferred = {});

// The same with a linear search over the solids and no differentials: the
// reference tracer of the tests (slow for big scenes; no setup needed).
TraceResult trace_ray(const TraceScene& scene, const Eigen::Vector3d& origin_mm, const Eigen::Vector3d& direction,
                      const TraceOptions& options = {});

}  // namespace glasspiv
