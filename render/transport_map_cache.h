#pragma once
// The one way commands get a camera's transport map: reused from a cache file
// when that file was made for exactly this setup (its fingerprint,
// render/transport_map_file.h), traced otherwise and then written there. No
// console I/O: what happened is returned for the caller to report.
#include <cstdint>
#include <functional>
#include <string>

#include "render/transport_map.h"

namespace glasspiv {

struct CachedTransportMap {
  TransportMap map;
  std::uint64_t fingerprint = 0;
  bool reused = false;    // loaded from cache_path, nothing traced
  std::string why_traced; // when traced with a cache path: "no file", "made for another setup (...)", ...
  bool written = false;   // traced and written to cache_path
  double seconds = 0;     // wall time of the load or of the trace (writing not included)
};

// cache_path "" traces without a cache. A traced map is written to cache_path
// atomically (a file that is unreadable or made for another setup is
// replaced). progress as for build_transport_map. Throws what
// build_transport_map and write_transport_map throw.
CachedTransportMap load_or_build_transport_map(const TraceScene& scene, const CameraModel& camera,
                                               const RigidTransform& camera_from_world, const TraceOptions& options,
                                               int samples_per_axis, const std::string& cache_path, int threads = 0,
                                               const std::function<void(int, int)>& progress = {});

}  // namespace glasspiv
