#pragma once
// The one way commands get a camera's correction operator: reused from a
// cache file made for exactly this map, grid and options (its fingerprint,
// correct/correction_operator_file.h), built otherwise and then written
// there. No console I/O: what happened is returned for the caller to report.
#include <cstdint>
#include <functional>
#include <string>

#include "correct/correction_operator.h"

namespace glasspiv {

struct CachedCorrectionOperator {
  CorrectionOperator op;
  std::uint64_t fingerprint = 0;
  bool reused = false;
  std::string why_built;  // with a cache path: "no file", "made for another setup (...)", ...
  bool written = false;
  double seconds = 0;     // the load or the build (writing not included)
};

// map_fingerprint: the fingerprint the map was traced under (render/transport_map_cache.h).
// cache_path "" builds without a cache. Throws what build_correction_operator and
// write_correction_operator throw.
CachedCorrectionOperator load_or_build_correction_operator(const TransportMap& map, std::uint64_t map_fingerprint,
                                                           const SheetGrid& grid, const OperatorOptions& options,
                                                           const std::string& cache_path, int threads = 0,
                                                           const std::function<void(int, int)>& progress = {});

}  // namespace glasspiv
