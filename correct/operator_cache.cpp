#include "correct/operator_cache.h"

#include "correct/correction_operator_file.h"
#include "util/stopwatch.h"

namespace glasspiv {

CachedCorrectionOperator load_or_build_correction_operator(const TransportMap& map, std::uint64_t map_fingerprint,
                                                           const SheetGrid& grid, const OperatorOptions& options,
                                                           const std::string& cache_path, int threads,
                                                           const std::function<void(int, int)>& progress) {
  CachedCorrectionOperator out;
  out.fingerprint = correction_operator_fingerprint(map_fingerprint, grid, options);
  const Stopwatch clock;
  if (!cache_path.empty()) {
    std::optional<CorrectionOperator> cached = load_cached_correction_operator(cache_path, out.fingerprint, &out.why_built);
    if (cached) {
      out.op = std::move(*cached);
      out.reused = true;
      out.why_built.clear();
      out.seconds = clock.seconds();
      return out;
    }
  }
  out.op = build_correction_operator(map, grid, options, threads, progress);
  out.seconds = clock.seconds();
  if (!cache_path.empty()) {
    write_correction_operator(cache_path, out.op, out.fingerprint);
    out.written = true;
  }
  return out;
}

}  // namespace glasspiv
