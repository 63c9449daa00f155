#include "render/transport_map_cache.h"

#include "render/transport_map_file.h"
#include "util/stopwatch.h"

namespace glasspiv {

CachedTransportMap load_or_build_transport_map(const TraceScene& scene, const CameraModel& camera,
                                               const RigidTransform& camera_from_world, const TraceOptions& options,
                                               int samples_per_axis, const std::string& cache_path, int threads,
                                               const std::function<void(int, int)>& progress) {
  CachedTransportMap out;
  out.fingerprint = transport_map_fingerprint(scene, camera, camera_from_world, options, samples_per_axis);
  const Stopwatch clock;
  if (!cache_path.empty()) {
    std::optional<TransportMap> cached = load_cached_transport_map(cache_path, out.fingerprint, &out.why_traced);
    if (cached) {
      out.map = std::move(*cached);
      out.reused = true;
      out.why_traced.clear();
      out.seconds = clock.seconds();
      return out;
    }
  }
  out.map = build_transport_map(scene, camera, camera_from_world, options, samples_per_axis, threads, progress);
  out.seconds = clock.seconds();
  if (!cache_path.empty()) {
    write_transport_map(cache_path, out.map, out.fingerprint);
    out.written = true;
  }
  return out;
}

}  // namespace glasspiv
