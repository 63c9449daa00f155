#pragma once
// What the benchmarks share: peak memory, the reactor camera cut to N x N,
// medians of repeated timings. Header-only, bench/ only.
#include <sys/resource.h>

#include <algorithm>
#include <vector>

#include "calib/camera_model.h"
#include "util/stopwatch.h"

namespace glasspiv::bench {

inline double peak_rss_mib() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss / 1024.0;  // Linux: KiB
}

// The camera resampled to n x n px: the central square of its sensor, intrinsics scaled by n / height.
inline CameraModel square(const CameraModel& m, int n) {
  const double k = static_cast<double>(n) / m.height_px();
  const double crop = 0.5 * (m.width_px() - m.height_px());  // columns cut on each side
  return CameraModel(n, n, m.fx_px() * k, m.fy_px() * k, (m.cx_px() + 0.5 - crop) * k - 0.5, (m.cy_px() + 0.5) * k - 0.5,
                     m.distortion());
}

inline double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

template <typename Fn>
double seconds_of(const Fn& fn) {
  const Stopwatch clock;
  fn();
  return clock.seconds();
}

}  // namespace glasspiv::bench
