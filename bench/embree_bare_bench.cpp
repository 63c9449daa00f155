// embree_bare_bench: the same-run reference for the tracer's speed. A bare
// Embree 3 float tracer follows refraction-only paths through the glass spheres
// of data/scenes/reactor.yaml, on the same camera rays as glasspiv's own tracer
// (build_transport_map), and the two are timed alternately in one run.
//   embree_bare_bench [--size N] [--reps R] [--threads T] [--user-geometry]
// Camera: the scene's camera, whole (2560 x 2160, the default) or resampled to
// N x N px like render_bench (the central square of the sensor, fx, fy, cx, cy
// scaled by N / 2160).
//
// The bare tracer:
// - one Embree scene; the spheres as Embree's own float geometry
//   (RTC_GEOMETRY_TYPE_SPHERE_POINT, x y z r per vertex) when the installed
//   Embree supports points, else (or with --user-geometry) a float user geometry
//   with the plain quadratic; build quality high, no robust flag;
// - camera rays: glasspiv's pixel_world_ray (double) for every pixel, computed
//   once up front into float arrays, not timed with the trace (the ray setup is
//   timed and printed on its own);
// - one rtcIntersect1 per segment (the first one included), every segment
//   counted; Snell refraction with the solid's glass index and the fluid index,
//   the side from the sign of d . Ng; total internal reflection ends the path
//   (counted), as in glasspiv's refraction-only mode; at most 32 interface
//   events per path, like TraceOptions::max_depth (counted); a path ends when
//   its ray meets nothing;
// - the next ray starts at the hit point with tnear = 1e-3 mm (float hit points
//   err by ~1e-4 mm at this scene's scale; inside chords are >= 30 mm);
// - no differentials, no sheet crossings, no Fresnel weights, nothing stored:
//   traversal + intersection + refraction;
// - threads: std::threads over rows (glasspiv's parallel_rows, rows handed out
//   dynamically), 2 by default.
// glasspiv: build_transport_map with TraceOptions{reflections = false} and with
// the default options (reflections on, min_weight 1e-2), and with the
// correction's (correct/correction_defaults.h: reflections on, min_weight 0.1,
// what glasspiv correct traces), and glasspiv render's default
// (render/render_defaults.h: the reflection grid 2 with whole samples, the
// default's map with its agreeing reflected subtrees and samples interpolated:
// fewer segments, so compare its s per MP, not its rate); segments =
// map.stats.branches_traced (its closed-form camera rays and its in-glass
// segments need no BVH query but count as segments).
#include <embree3/rtcore.h>
#include <sys/resource.h>
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>
#include <thread>
#include <variant>
#include <vector>

#include "bench/bench_common.h"
#include "correct/correction_defaults.h"
#include "render/parallel_rows.h"
#include "render/path_tracer.h"
#include "render/render_defaults.h"
#include "render/row_camera_rays.h"
#include "render/scene_yaml.h"
#include "render/trace_scene_builder.h"
#include "render/transport_map.h"
#include "util/stopwatch.h"

using namespace glasspiv;
using bench::peak_rss_mib;
using bench::square;
using bench::median;

namespace {

// CPU seconds of the whole process (all threads): on a machine shared with
// other work this moves less than the wall clock.
double process_cpu_s() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

// ---------------------------------------------------------------------------
// The bare tracer.

struct Sphere4 {
  float x, y, z, r;
};

// Float user geometry (the fallback): the plain quadratic, nearest root in
// (tnear, tfar), the outward normal p - c.
void user_sphere_bounds(const RTCBoundsFunctionArguments* args) {
  const Sphere4& s = static_cast<const Sphere4*>(args->geometryUserPtr)[args->primID];
  RTCBounds* b = args->bounds_o;
  b->lower_x = s.x - s.r;
  b->lower_y = s.y - s.r;
  b->lower_z = s.z - s.r;
  b->upper_x = s.x + s.r;
  b->upper_y = s.y + s.r;
  b->upper_z = s.z + s.r;
}

void user_sphere_intersect(const RTCIntersectFunctionNArguments* args) {
  if (!args->valid[0]) return;
  const Sphere4& s = static_cast<const Sphere4*>(args->geometryUserPtr)[args->primID];
  RTCRayN* ray = RTCRayHitN_RayN(args->rayhit, args->N);
  RTCHitN* hit = RTCRayHitN_HitN(args->rayhit, args->N);
  const float ox = RTCRayN_org_x(ray, args->N, 0) - s.x, oy = RTCRayN_org_y(ray, args->N, 0) - s.y,
              oz = RTCRayN_org_z(ray, args->N, 0) - s.z;
  const float dx = RTCRayN_dir_x(ray, args->N, 0), dy = RTCRayN_dir_y(ray, args->N, 0),
              dz = RTCRayN_dir_z(ray, args->N, 0);
  // |o + t d - c|^2 = r^2 with the discriminant written as r^2 - (squared
  // distance of the line from the centre): the textbook b^2 - a c loses all
  // digits in float for an origin 600 mm away from a 20 mm sphere.
  const float a = dx * dx + dy * dy + dz * dz;
  const float tm = -(ox * dx + oy * dy + oz * dz) / a;  // closest approach
  const float px = ox + tm * dx, py = oy + tm * dy, pz = oz + tm * dz;
  const float disc = s.r * s.r - (px * px + py * py + pz * pz);
  if (!(disc > 0)) return;
  const float q = std::sqrt(disc / a);
  const float tnear = RTCRayN_tnear(ray, args->N, 0);
  float& tfar = RTCRayN_tfar(ray, args->N, 0);
  float t = tm - q;
  if (!(t > tnear && t < tfar)) {
    t = tm + q;
    if (!(t > tnear && t < tfar)) return;
  }
  tfar = t;
  RTCHitN_Ng_x(hit, args->N, 0) = ox + t * dx;
  RTCHitN_Ng_y(hit, args->N, 0) = oy + t * dy;
  RTCHitN_Ng_z(hit, args->N, 0) = oz + t * dz;
  RTCHitN_u(hit, args->N, 0) = 0;
  RTCHitN_v(hit, args->N, 0) = 0;
  RTCHitN_primID(hit, args->N, 0) = args->primID;
  RTCHitN_geomID(hit, args->N, 0) = args->geomID;
  RTCHitN_instID(hit, args->N, 0, 0) = args->context->instID[0];
}

struct BareCounts {
  long camera_rays = 0, segments = 0, escaped = 0, tir = 0, cut_by_depth = 0;
  void add(const BareCounts& o) {
    camera_rays += o.camera_rays;
    segments += o.segments;
    escaped += o.escaped;
    tir += o.tir;
    cut_by_depth += o.cut_by_depth;
  }
};

class BareTracer {
 public:
  BareTracer(const std::vector<Sphere4>& spheres, std::vector<float> glass_index, float fluid_index,
             bool force_user_geometry)
      : spheres_(spheres), glass_index_(std::move(glass_index)), fluid_index_(fluid_index) {
    device_ = rtcNewDevice(nullptr);
    if (!device_) throw std::runtime_error("Embree: cannot create a device");
    native_ = !force_user_geometry && rtcGetDeviceProperty(device_, RTC_DEVICE_PROPERTY_POINT_GEOMETRY_SUPPORTED) != 0;
    scene_ = rtcNewScene(device_);
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
    RTCGeometry g;
    if (native_) {
      g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_SPHERE_POINT);
      auto* v = static_cast<Sphere4*>(
          rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, sizeof(Sphere4), spheres_.size()));
      std::copy(spheres_.begin(), spheres_.end(), v);
    } else {
      g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_USER);
      rtcSetGeometryUserPrimitiveCount(g, static_cast<unsigned>(spheres_.size()));
      rtcSetGeometryUserData(g, spheres_.data());
      rtcSetGeometryBoundsFunction(g, user_sphere_bounds, nullptr);
      rtcSetGeometryIntersectFunction(g, user_sphere_intersect);
    }
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene_, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(scene_);
    if (rtcGetDeviceError(device_) != RTC_ERROR_NONE) throw std::runtime_error("Embree: building the bare scene failed");
  }
  ~BareTracer() {
    rtcReleaseScene(scene_);
    rtcReleaseDevice(device_);
  }
  BareTracer(const BareTracer&) = delete;
  BareTracer& operator=(const BareTracer&) = delete;

  bool native() const { return native_; }

  // Follows the refraction-only path of the ray (o, d), d unit.
  void trace(const float o_in[3], const float d_in[3], RTCIntersectContext* context, BareCounts* counts) const {
    constexpr int kMaxEvents = 32;        // as TraceOptions::max_depth
    constexpr float kSpawnTnear = 1e-3f;  // mm
    float o[3] = {o_in[0], o_in[1], o_in[2]};
    float d[3] = {d_in[0], d_in[1], d_in[2]};
    float tnear = 0;
    ++counts->camera_rays;
    for (int events = 0;; ++events) {
      RTCRayHit rh;
      rh.ray.org_x = o[0];
      rh.ray.org_y = o[1];
      rh.ray.org_z = o[2];
      rh.ray.tnear = tnear;
      rh.ray.dir_x = d[0];
      rh.ray.dir_y = d[1];
      rh.ray.dir_z = d[2];
      rh.ray.time = 0;
      rh.ray.tfar = INFINITY;
      rh.ray.mask = 0xFFFFFFFFu;
      rh.ray.id = 0;
      rh.ray.flags = 0;
      rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(scene_, context, &rh);
      ++counts->segments;
      if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
        ++counts->escaped;
        return;
      }
      if (events == kMaxEvents) {
        ++counts->cut_by_depth;
        return;
      }
      const float t = rh.ray.tfar;
      for (int i = 0; i < 3; ++i) o[i] += t * d[i];
      float n[3] = {rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z};
      const float inv_len = 1.0f / std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      for (float& c : n) c *= inv_len;
      float dn = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
      const float ng = glass_index_[rh.hit.primID];
      float eta;
      if (dn < 0) {  // entering the glass
        eta = fluid_index_ / ng;
        dn = -dn;
      } else {  // leaving it: face the normal to the incoming ray
        eta = ng / fluid_index_;
        for (float& c : n) c = -c;
      }
      const float k = 1.0f - eta * eta * (1.0f - dn * dn);  // cos^2 of the refraction angle
      if (k < 0) {
        ++counts->tir;
        return;
      }
      const float m = eta * dn - std::sqrt(k);
      float len2 = 0;
      for (int i = 0; i < 3; ++i) {
        d[i] = eta * d[i] + m * n[i];
        len2 += d[i] * d[i];
      }
      const float inv = 1.0f / std::sqrt(len2);
      for (float& c : d) c *= inv;
      tnear = kSpawnTnear;
    }
  }

 private:
  std::vector<Sphere4> spheres_;
  std::vector<float> glass_index_;
  float fluid_index_;
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  bool native_ = false;
};

// Camera rays, float, computed once from pixel_world_ray.
struct CameraRays {
  int width = 0, height = 0;
  float origin[3] = {0, 0, 0};
  std::vector<float> dir;      // 3 per pixel, row-major
  std::vector<unsigned char> ok;  // 0 where the pixel cannot be unprojected
  long failures = 0;
};

CameraRays make_camera_rays(const CameraModel& cam, const RigidTransform& pose, int threads) {
  CameraRays r;
  r.width = cam.width_px();
  r.height = cam.height_px();
  const std::size_t n = static_cast<std::size_t>(r.width) * r.height;
  r.dir.assign(3 * n, 0.0f);
  r.ok.assign(n, 0);
  parallel_rows(r.height, threads, [&](int row) {
    for (int col = 0; col < r.width; ++col) {
      const std::size_t p = static_cast<std::size_t>(row) * r.width + col;
      const auto ray = pixel_world_ray(cam, pose, Eigen::Vector2d(col, row));
      if (!ray) continue;
      for (int i = 0; i < 3; ++i) r.dir[3 * p + i] = static_cast<float>(ray->direction[i]);
      r.ok[p] = 1;
    }
  });
  bool have_origin = false;
  for (std::size_t p = 0; p < n; ++p) {
    if (!r.ok[p]) {
      ++r.failures;
      continue;
    }
    if (!have_origin) {  // a central camera: one origin for every pixel
      const auto ray = pixel_world_ray(cam, pose, Eigen::Vector2d(double(p % r.width), double(p / r.width)));
      for (int i = 0; i < 3; ++i) r.origin[i] = static_cast<float>(ray->origin_mm[i]);
      have_origin = true;
    }
  }
  return r;
}

// glasspiv's own camera rays alone: RowCameraRays (the unprojection, the
// world ray and its differentials) for every pixel centre, as
// build_transport_map's rows make them, nothing traced. Its time is what
// build_transport_map spends per ray before the first segment; the bare
// tracer's rays come precomputed.
double camera_ray_pass(const CameraModel& cam, const RigidTransform& pose, int threads) {
  std::vector<double> per_row(static_cast<std::size_t>(cam.height_px()), 0.0);
  parallel_rows(cam.height_px(), threads, [&](int row) {
    double sum = 0;  // kept, so the rays are not optimised away
    RowCameraRays rays(cam, pose, row, 1);
    for (int col = 0; col < cam.width_px(); ++col)
      if (const std::optional<CameraRay>& ray = rays.next()) sum += ray->direction.x() + ray->ddirection_dpixel(0, 0);
    per_row[static_cast<std::size_t>(row)] = sum;
  });
  double total = 0;
  for (double v : per_row) total += v;
  return total;
}

BareCounts run_bare(const BareTracer& tracer, const CameraRays& rays, int threads) {
  std::vector<BareCounts> per_row(static_cast<std::size_t>(rays.height));
  parallel_rows(rays.height, threads, [&](int row) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    BareCounts c;
    for (int col = 0; col < rays.width; ++col) {
      const std::size_t p = static_cast<std::size_t>(row) * rays.width + col;
      if (!rays.ok[p]) continue;
      tracer.trace(rays.origin, &rays.dir[3 * p], &context, &c);
    }
    per_row[static_cast<std::size_t>(row)] = c;
  });
  BareCounts total;
  for (const BareCounts& c : per_row) total.add(c);
  return total;
}

}  // namespace

int main(int argc, char** argv) {
  int size = 0, reps = 3, threads = 2;
  bool force_user = false;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--size") && i + 1 < argc) size = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) reps = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--threads") && i + 1 < argc) threads = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--user-geometry")) force_user = true;
    else {
      std::fprintf(stderr, "usage: embree_bare_bench [--size N] [--reps R] [--threads T] [--user-geometry]\n");
      return 2;
    }
  }
  if (reps < 1) reps = 1;
  if (threads <= 0) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));

  const Scene scene = read_scene(GLASSPIV_SOURCE_DIR "/data/scenes/reactor.yaml");
  TraceSceneBuildInfo info;
  const TraceScene ts = build_trace_scene(scene, &info);
  const Camera& camera = scene.cameras.at(0).camera;
  const RigidTransform& pose = *camera.camera_from_world;
  const CameraModel cam = size > 0 ? square(camera.model, size) : camera.model;
  const double mp = cam.width_px() * static_cast<double>(cam.height_px()) / 1e6;

  // The bare scene: every solid must be a glass sphere.
  std::vector<Sphere4> spheres;
  std::vector<float> glass_index;
  for (const TraceSolid& s : ts.solids) {
    const Sphere* sp = std::get_if<Sphere>(&s.shape);
    if (!sp || s.material.kind != TraceMaterial::Kind::glass) {
      std::fprintf(stderr, "embree_bare_bench: the bare tracer handles glass spheres only\n");
      return 1;
    }
    spheres.push_back({static_cast<float>(sp->centre_mm.x()), static_cast<float>(sp->centre_mm.y()),
                       static_cast<float>(sp->centre_mm.z()), static_cast<float>(sp->radius_mm)});
    glass_index.push_back(static_cast<float>(s.material.refractive_index));
  }
  const Stopwatch build_clock;
  const BareTracer bare(spheres, glass_index, static_cast<float>(ts.fluid_index), force_user);
  const double build_s = build_clock.seconds();

  std::printf("reactor.yaml: %zu solids (%d spheres), n_glass %.5f, n_fluid %.5f; camera %s %s %dx%d (%.2f MP); "
              "%d threads; Embree %s\n",
              ts.solids.size(), info.spheres, glass_index.empty() ? 0.0 : glass_index[0], ts.fluid_index,
              scene.cameras[0].name.c_str(), size > 0 ? "resampled to" : "whole,", cam.width_px(), cam.height_px(), mp,
              threads, RTC_VERSION_STRING);
  std::printf("bare tracer: %s, BVH build %.2f ms\n",
              bare.native() ? "RTC_GEOMETRY_TYPE_SPHERE_POINT (Embree's float spheres)"
                            : "float user geometry (plain quadratic)",
              1e3 * build_s);

  const Stopwatch ray_clock;
  const CameraRays rays = make_camera_rays(cam, pose, threads);
  const double ray_s = ray_clock.seconds();
  std::printf("camera rays (pixel_world_ray, double -> float, up front, not in the bare time): %.3f s "
              "(%.3f s per MP), %ld pixels not unprojected\n",
              ray_s, ray_s / mp, rays.failures);

  TraceOptions refraction_only;
  refraction_only.reflections = false;
  const TraceOptions defaults;
  const TraceOptions correction = correction_trace_options();  // glasspiv correct's maps: reflections, cut at 0.1
  // glasspiv render's default: the default's map with reflected subtrees and
  // whole samples interpolated where the reflection grid's anchors agree.
  const TraceOptions grid = render_trace_options();

  struct Run {
    double seconds = 0;
    long segments = 0;
    double cpu_s = 0;
    double mseg_per_s() const { return segments / seconds / 1e6; }
    double mseg_per_cpu_s() const { return segments / cpu_s / 1e6; }
  };
  std::vector<Run> bare_runs, refr_runs, def_runs, corr_runs, grid_runs, camera_ray_runs;
  double camera_ray_checksum = 0;
  BareCounts bare_counts;
  TransportStats refr_stats, def_stats, corr_stats, grid_stats;
  double refr_map_mib = 0, def_map_mib = 0, corr_map_mib = 0, grid_map_mib = 0;
  const double rss_before_maps = peak_rss_mib();

  // One glasspiv map build, timed (wall and process CPU), its stats and size kept.
  const auto trace_map = [&](const TraceOptions& o, std::vector<Run>* runs, TransportStats* stats, double* mib) {
    const Stopwatch clock;
    const double cpu0 = process_cpu_s();
    // With a progress callback, as glasspiv render and correct build their
    // maps (its reporting thread once slept past the end of every row loop).
    const TransportMap map = build_transport_map(ts, cam, pose, o, 1, threads, [](int, int) {});
    runs->push_back({clock.seconds(), map.stats.branches_traced, process_cpu_s() - cpu0});
    *stats = map.stats;
    *mib = map.memory_bytes() / 1048576.0;
  };
  std::printf("\n| rep | tracer | s | segments | M segments/s | s per MP | glasspiv/bare, segments/s | CPU s | "
              "glasspiv/bare, segments per CPU s |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|\n");
  for (int rep = 1; rep <= reps; ++rep) {
    {
      const Stopwatch clock;
      const double cpu0 = process_cpu_s();
      bare_counts = run_bare(bare, rays, threads);
      bare_runs.push_back({clock.seconds(), bare_counts.segments, process_cpu_s() - cpu0});
    }
    {
      const Stopwatch clock;
      const double cpu0 = process_cpu_s();
      camera_ray_checksum += camera_ray_pass(cam, pose, threads);
      camera_ray_runs.push_back({clock.seconds(), 0, process_cpu_s() - cpu0});
    }
    trace_map(refraction_only, &refr_runs, &refr_stats, &refr_map_mib);
    trace_map(defaults, &def_runs, &def_stats, &def_map_mib);
    trace_map(correction, &corr_runs, &corr_stats, &corr_map_mib);
    trace_map(grid, &grid_runs, &grid_stats, &grid_map_mib);
    const Run& b = bare_runs.back();
    const Run& r = refr_runs.back();
    const Run& d = def_runs.back();
    const Run& c = corr_runs.back();
    std::printf("| %d | bare Embree, refraction only | %.3f | %ld | %.2f | %.3f | | %.3f | |\n", rep, b.seconds,
                b.segments, b.mseg_per_s(), b.seconds / mp, b.cpu_s);
    std::printf("| %d | glasspiv's camera rays alone (RowCameraRays, nothing traced) | %.3f | | | %.3f | | %.3f | |\n",
                rep, camera_ray_runs.back().seconds, camera_ray_runs.back().seconds / mp, camera_ray_runs.back().cpu_s);
    const auto row = [&](const char* name, const Run& g) {
      std::printf("| %d | glasspiv, %s | %.3f | %ld | %.2f | %.3f | %.3f | %.3f | %.3f |\n", rep, name, g.seconds,
                  g.segments, g.mseg_per_s(), g.seconds / mp, g.mseg_per_s() / b.mseg_per_s(), g.cpu_s,
                  g.mseg_per_cpu_s() / b.mseg_per_cpu_s());
    };
    row("refraction only", r);
    row("default (reflections, min_weight 1e-2)", d);
    row("correction default (reflections, min_weight 0.1)", c);
    row("render default: reflection grid 2, whole samples (the default's map, fewer segments)", grid_runs.back());
    std::fflush(stdout);
  }

  auto med = [](const std::vector<Run>& runs, auto f) {
    std::vector<double> v;
    for (const Run& r : runs) v.push_back(f(r));
    return median(v);
  };
  // The median over the reps of f(glasspiv's run, the bare run, the camera-ray
  // pass), all three of the same rep.
  auto same_rep_median = [&](const std::vector<Run>& runs, auto f) {
    std::vector<double> v;
    for (std::size_t i = 0; i < runs.size(); ++i) v.push_back(f(runs[i], bare_runs[i], camera_ray_runs[i]));
    return median(v);
  };
  auto ratio_med = [&](const std::vector<Run>& runs) {
    return same_rep_median(runs, [](const Run& g, const Run& b, const Run&) { return g.mseg_per_s() / b.mseg_per_s(); });
  };
  std::printf("\nmedian of %d reps:\n", reps);
  std::printf("| tracer | s | M segments/s | s per MP | glasspiv/bare, segments/s (same rep) |\n|---|---|---|---|---|\n");
  const auto secs = [](const Run& r) { return r.seconds; };
  const auto rate = [](const Run& r) { return r.mseg_per_s(); };
  std::printf("| bare Embree, refraction only | %.3f | %.2f | %.3f | |\n", med(bare_runs, secs), med(bare_runs, rate),
              med(bare_runs, secs) / mp);
  std::printf("| glasspiv, refraction only | %.3f | %.2f | %.3f | %.3f |\n", med(refr_runs, secs), med(refr_runs, rate),
              med(refr_runs, secs) / mp, ratio_med(refr_runs));
  std::printf("| glasspiv, default | %.3f | %.2f | %.3f | %.3f |\n", med(def_runs, secs), med(def_runs, rate),
              med(def_runs, secs) / mp, ratio_med(def_runs));
  std::printf("| glasspiv, correction default | %.3f | %.2f | %.3f | %.3f |\n", med(corr_runs, secs),
              med(corr_runs, rate), med(corr_runs, secs) / mp, ratio_med(corr_runs));
  auto cpu_ratio_med = [&](const std::vector<Run>& runs) {
    return same_rep_median(runs,
                           [](const Run& g, const Run& b, const Run&) { return g.mseg_per_cpu_s() / b.mseg_per_cpu_s(); });
  };
  std::printf("glasspiv/bare, segments per CPU second (same rep, median): refraction only %.3f, default %.3f, "
              "correction default %.3f\n",
              cpu_ratio_med(refr_runs), cpu_ratio_med(def_runs), cpu_ratio_med(corr_runs));
  {
    // Per segment, tracing alone: each build's CPU time less the same rep's
    // camera-ray pass (glasspiv unprojects inside its build, the bare tracer's
    // rays are precomputed), against the bare tracer's CPU time.
    auto trace_only = [&](const std::vector<Run>& runs) {
      return same_rep_median(runs, [](const Run& g, const Run& b, const Run& rays) {
        return g.segments / (g.cpu_s - rays.cpu_s) / b.mseg_per_cpu_s() / 1e6;
      });
    };
    const double ray_cpu_s = med(camera_ray_runs, [](const Run& r) { return r.cpu_s; });
    std::printf("camera rays alone: %.3f CPU s (%.0f ns per pixel, median; checksum %.3g); glasspiv/bare, segments "
                "per CPU s of tracing (each build less its camera rays; same rep, median): refraction only %.3f, "
                "default %.3f, correction default %.3f\n",
                ray_cpu_s, 1e9 * ray_cpu_s / (mp * 1e6), camera_ray_checksum,
                trace_only(refr_runs), trace_only(def_runs), trace_only(corr_runs));
  }
  const auto scaled = [&](const std::vector<Run>& runs) {
    return same_rep_median(runs,
                           [&](const Run& g, const Run& b, const Run&) { return g.seconds / mp * (b.mseg_per_s() / 17.0); });
  };
  std::printf("\ns per MP scaled to a bare tracer at 17 M segments/s (glasspiv s/MP x bare M seg/s / 17, per rep, "
              "median): default %.3f, correction default %.3f, render default (grid 2, whole samples) %.3f\n",
              scaled(def_runs), scaled(corr_runs), scaled(grid_runs));
  {
    // glasspiv unprojects every pixel inside its timed build; the bare time does not.
    const double with_rays = med(bare_runs, secs) + ray_s;
    const double rate_with_rays = bare_counts.segments / with_rays / 1e6;
    std::printf("bare + its up-front camera rays: %.3f s per MP, %.2f M segments/s; glasspiv/(bare + rays), "
                "segments/s: refraction only %.3f, default %.3f\n",
                with_rays / mp, rate_with_rays, med(refr_runs, rate) / rate_with_rays,
                med(def_runs, rate) / rate_with_rays);
  }

  std::printf("\ncounts (last rep):\n");
  std::printf("  bare: %ld camera rays, %ld segments (%.3f per ray), %ld left the scene, %ld ended by total internal "
              "reflection, %ld cut at 32 events\n",
              bare_counts.camera_rays, bare_counts.segments, double(bare_counts.segments) / bare_counts.camera_rays,
              bare_counts.escaped, bare_counts.tir, bare_counts.cut_by_depth);
  std::printf("  glasspiv refraction only: %ld camera rays, %ld segments (%.3f per ray), %ld closed form, %ld "
              "reflections skipped, %ld cut by depth, %ld crossings\n",
              refr_stats.camera_rays, refr_stats.branches_traced,
              double(refr_stats.branches_traced) / refr_stats.camera_rays, refr_stats.closed_form_rays,
              refr_stats.reflections_skipped, refr_stats.branches_cut_by_depth, refr_stats.crossings);
  std::printf("  glasspiv default: %ld camera rays, %ld segments (%.3f per ray), %ld cut by weight, %ld cut by depth, "
              "%ld crossings\n",
              def_stats.camera_rays, def_stats.branches_traced, double(def_stats.branches_traced) / def_stats.camera_rays,
              def_stats.branches_cut_by_weight, def_stats.branches_cut_by_depth, def_stats.crossings);
  std::printf("  glasspiv correction default: %ld camera rays, %ld segments (%.3f per ray), %ld cut by weight, %ld cut "
              "by depth, %ld crossings; map %.1f MiB\n",
              corr_stats.camera_rays, corr_stats.branches_traced,
              double(corr_stats.branches_traced) / corr_stats.camera_rays, corr_stats.branches_cut_by_weight,
              corr_stats.branches_cut_by_depth, corr_stats.crossings, corr_map_mib);
  std::printf("  glasspiv render default (reflection grid 2, whole samples): %ld segments (%.3f per camera sample), "
              "%ld subtrees and %ld samples interpolated, %ld crossings; map %.1f MiB\n",
              grid_stats.branches_traced,
              double(grid_stats.branches_traced) / double(grid_stats.camera_rays + grid_stats.samples_interpolated),
              grid_stats.subtrees_interpolated, grid_stats.samples_interpolated, grid_stats.crossings, grid_map_mib);
  std::printf("  bare vs glasspiv refraction-only segments: %+.4f %%\n",
              100.0 * (double(bare_counts.segments) - refr_stats.branches_traced) / refr_stats.branches_traced);
  std::printf("maps: refraction only %.1f MiB, default %.1f MiB (TransportMap::memory_bytes); peak RSS %.1f MiB "
              "before the first map build (scene, BVHs, float camera rays), %.1f MiB at the end: the builds added "
              "%.1f MiB, %.2fx the default map\n",
              refr_map_mib, def_map_mib, rss_before_maps, peak_rss_mib(), peak_rss_mib() - rss_before_maps,
              (peak_rss_mib() - rss_before_maps) / def_map_mib);
  return 0;
}
