#include "render/transport_map.h"

#ifdef __GLIBC__
#include <malloc.h>
#endif

#include <algorithm>
#include <limits>
#include <stdexcept>

#include "render/parallel_rows.h"
#include "render/row_camera_rays.h"
#include "render/trace_scene_builder.h"

namespace glasspiv {

std::size_t TransportMap::memory_bytes() const {
  return pixel_offsets.size() * sizeof(std::uint32_t) +
         (s_mm.size() + t_mm.size() + weight.size() + ds_dcol.size() + ds_drow.size() + dt_dcol.size() +
          dt_drow.size()) * sizeof(float) +
         tag.size() + (background_weight.size() + opaque_weight.size()) * sizeof(float);
}

namespace {

struct RowBuffer {
  std::vector<std::uint32_t> counts;  // crossings per pixel of the row
  std::vector<float> s, t, w, ds_dcol, ds_drow, dt_dcol, dt_drow;
  std::vector<std::uint8_t> tag;
  std::vector<float> background, opaque;
  long camera_rays = 0, branches = 0, no_hit_pixels = 0, unproject_failures = 0;
  long closed_form = 0, cut_by_weight = 0, cut_by_depth = 0, reflections_skipped = 0;
  double cut_weight = 0;

  void clear() {
    for (auto* v : {&s, &t, &w, &ds_dcol, &ds_drow, &dt_dcol, &dt_drow}) v->clear();
    tag.clear();
  }
  // The crossings of `from`, in arrays of exactly their size (the row waits
  // for the concatenation: no growth slack).
  void take_crossings(const RowBuffer& from) {
    s.assign(from.s.begin(), from.s.end());
    t.assign(from.t.begin(), from.t.end());
    w.assign(from.w.begin(), from.w.end());
    ds_dcol.assign(from.ds_dcol.begin(), from.ds_dcol.end());
    ds_drow.assign(from.ds_drow.begin(), from.ds_drow.end());
    dt_dcol.assign(from.dt_dcol.begin(), from.dt_dcol.end());
    dt_drow.assign(from.dt_drow.begin(), from.dt_drow.end());
    tag.assign(from.tag.begin(), from.tag.end());
  }
};

void trace_row(const TraceScene& scene, const SceneIndex& index, const CameraModel& camera,
               const RigidTransform& camera_from_world, const TraceOptions& options, int k, int row,
               RowBuffer* out) {
  thread_local TraceResult r;  // reused: no allocation per ray
  // The row's crossings grow here, in one buffer per thread that keeps its
  // capacity from row to row, and are copied to the row once, at their size.
  thread_local RowBuffer scratch;
  scratch.clear();
  RowBuffer* const crossings = &scratch;
  const int width = camera.width_px();
  const double inv_samples = 1.0 / (static_cast<double>(k) * k);
  out->counts.assign(static_cast<std::size_t>(width), 0);
  out->background.assign(static_cast<std::size_t>(width), 0.0f);
  out->opaque.assign(static_cast<std::size_t>(width), 0.0f);
  RowCameraRays rays(camera, camera_from_world, row, k);
  for (int col = 0; col < width; ++col) {
    bool any_hit = false;
    double background = 0, opaque = 0;
    std::uint32_t count = 0;
    for (int sy = 0; sy < k; ++sy) {
      for (int sx = 0; sx < k; ++sx) {
        const std::optional<CameraRay>& ray = rays.next();
        if (!ray) {
          ++out->unproject_failures;
          continue;
        }
        trace_ray(scene, index, *ray, options, &r);
        ++out->camera_rays;
        out->branches += r.counts.branches_traced;
        out->closed_form += r.counts.closed_form;
        out->cut_by_weight += r.counts.cut_by_weight;
        out->cut_by_depth += r.counts.cut_by_depth;
        out->reflections_skipped += r.counts.reflections_skipped;
        out->cut_weight += (r.cut_by_weight_weight + r.cut_by_depth_weight + r.skipped_reflection_weight) * inv_samples;
        if (r.counts.branches_traced > 1 || !r.opaque_hits.empty()) any_hit = true;
        for (const SheetCrossing& c : r.crossings) {
          crossings->s.push_back(static_cast<float>(c.s_mm));
          crossings->t.push_back(static_cast<float>(c.t_mm));
          crossings->w.push_back(static_cast<float>(c.weight * inv_samples));
          crossings->tag.push_back(static_cast<std::uint8_t>(c.tag));
          crossings->ds_dcol.push_back(static_cast<float>(c.dst_dpixel(0, 0)));
          crossings->ds_drow.push_back(static_cast<float>(c.dst_dpixel(0, 1)));
          crossings->dt_dcol.push_back(static_cast<float>(c.dst_dpixel(1, 0)));
          crossings->dt_drow.push_back(static_cast<float>(c.dst_dpixel(1, 1)));
          ++count;
        }
        background += r.background_weight * inv_samples;
        opaque += r.opaque_weight * inv_samples;
      }
    }
    if (!any_hit) ++out->no_hit_pixels;
    out->counts[static_cast<std::size_t>(col)] = count;
    out->background[static_cast<std::size_t>(col)] = static_cast<float>(background);
    out->opaque[static_cast<std::size_t>(col)] = static_cast<float>(opaque);
  }
  out->take_crossings(scratch);
}

}  // namespace

TransportMap build_transport_map(const TraceScene& scene, const CameraModel& camera,
                                 const RigidTransform& camera_from_world, const TraceOptions& options,
                                 int samples_per_axis, int threads, const std::function<void(int, int)>& progress) {
  if (samples_per_axis < 1) throw std::invalid_argument("build_transport_map: samples_per_axis must be >= 1");
  const int width = camera.width_px(), height = camera.height_px();

  const std::unique_ptr<SceneIndex> index = make_scene_index(scene);
  std::vector<RowBuffer> rows(static_cast<std::size_t>(height));
  // trace_ray throws only for non-finite rays, which pixel_camera_ray never produces.
  threads = parallel_rows(
      height, threads,
      [&](int row) {
        trace_row(scene, *index, camera, camera_from_world, options, samples_per_axis, row,
                  &rows[static_cast<std::size_t>(row)]);
      },
      progress);

  TransportMap map;
  map.width = width;
  map.height = height;
  map.samples_per_axis = samples_per_axis;
  map.stats.threads = threads;
  std::size_t total = 0;
  for (const RowBuffer& rb : rows) total += rb.w.size();
  if (total > std::numeric_limits<std::uint32_t>::max())
    throw std::overflow_error("build_transport_map: more than 2^32 - 1 crossings");
  map.pixel_offsets.reserve(map.pixel_count() + 1);
  map.s_mm.reserve(total);
  map.t_mm.reserve(total);
  map.weight.reserve(total);
  map.tag.reserve(total);
  for (auto* v : {&map.ds_dcol, &map.ds_drow, &map.dt_dcol, &map.dt_drow}) v->reserve(total);
  map.background_weight.reserve(map.pixel_count());
  map.opaque_weight.reserve(map.pixel_count());
  std::uint32_t offset = 0;
  [[maybe_unused]] int rows_freed = 0;
  map.pixel_offsets.push_back(0);
  for (RowBuffer& rb : rows) {
    for (std::uint32_t c : rb.counts) map.pixel_offsets.push_back(offset += c);
    map.s_mm.insert(map.s_mm.end(), rb.s.begin(), rb.s.end());
    map.t_mm.insert(map.t_mm.end(), rb.t.begin(), rb.t.end());
    map.weight.insert(map.weight.end(), rb.w.begin(), rb.w.end());
    map.tag.insert(map.tag.end(), rb.tag.begin(), rb.tag.end());
    map.ds_dcol.insert(map.ds_dcol.end(), rb.ds_dcol.begin(), rb.ds_dcol.end());
    map.ds_drow.insert(map.ds_drow.end(), rb.ds_drow.begin(), rb.ds_drow.end());
    map.dt_dcol.insert(map.dt_dcol.end(), rb.dt_dcol.begin(), rb.dt_dcol.end());
    map.dt_drow.insert(map.dt_drow.end(), rb.dt_drow.begin(), rb.dt_drow.end());
    map.background_weight.insert(map.background_weight.end(), rb.background.begin(), rb.background.end());
    map.opaque_weight.insert(map.opaque_weight.end(), rb.opaque.begin(), rb.opaque.end());
    map.stats.camera_rays += rb.camera_rays;
    map.stats.branches_traced += rb.branches;
    map.stats.pixels_without_solid_hit += rb.no_hit_pixels;
    map.stats.unproject_failures += rb.unproject_failures;
    map.stats.closed_form_rays += rb.closed_form;
    map.stats.branches_cut_by_weight += rb.cut_by_weight;
    map.stats.branches_cut_by_depth += rb.cut_by_depth;
    map.stats.reflections_skipped += rb.reflections_skipped;
    map.stats.cut_weight += rb.cut_weight;
    rb = RowBuffer{};  // free as we go: peak memory ~ one copy
#ifdef __GLIBC__
    // The rows' small blocks go back to malloc's free lists, which the map's
    // large arrays (mmapped) never reuse: hand the freed pages back to the system.
    if (++rows_freed % 64 == 0) malloc_trim(0);
#endif
  }
  map.stats.crossings = static_cast<long>(total);
  return map;
}

}  // namespace glasspiv
