#include "piv/subpixel_peak.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace glasspiv {
namespace {
double clamp_half(double offset) { return std::isfinite(offset) ? std::clamp(offset, -0.5, 0.5) : 0.0; }
}  // namespace

double parabolic_peak_offset_px(double left, double centre, double right) {
  const double curvature = left - 2 * centre + right;
  return curvature < 0 ? clamp_half((left - right) / (2 * curvature)) : 0.0;
}

double gaussian_peak_offset_px(double left, double centre, double right) {
  if (!(left > 0 && centre > 0 && right > 0)) return parabolic_peak_offset_px(left, centre, right);
  const double ll = std::log(left), lc = std::log(centre), lr = std::log(right);
  const double curvature = ll - 2 * lc + lr;
  return curvature < 0 ? clamp_half((ll - lr) / (2 * curvature)) : 0.0;
}

CorrelationPeak find_correlation_peak(const float* plane, int plane_px, int exclusion_radius_px) {
  const int m = plane_px;
  int best = 0;
  float lowest = plane[0], highest_seen = plane[0];
  for (int i = 1; i < m * m; ++i) {
    if (plane[i] > highest_seen) {
      highest_seen = plane[i];
      best = i;
    }
    lowest = std::min(lowest, plane[i]);
  }
  CorrelationPeak peak;
  const float highest = plane[best];
  if (!(highest > lowest)) return peak;
  const int r = best / m, c = best % m;
  auto at = [&](int row, int col) -> double { return plane[((row + m) % m) * m + (col + m) % m]; };
  // The second peak: the highest sample outside the exclusion square around
  // (r, c), wrapped: rows of the band skip its columns, other rows are whole.
  const int e = exclusion_radius_px;
  float second = lowest;
  auto in_band = [&](int k, int centre) {
    const int d = std::abs(k - centre);
    return std::min(d, m - d) <= e;
  };
  for (int row = 0; row < m; ++row) {
    const float* p = plane + row * m;
    if (!in_band(row, r)) {
      for (int col = 0; col < m; ++col) second = std::max(second, p[col]);
      continue;
    }
    if (2 * e + 1 >= m) continue;  // the band covers every column
    for (int k = e + 1; k < m - e; ++k) second = std::max(second, p[(c + k) % m]);
  }
  peak.found = true;
  peak.height = highest;
  const double span = static_cast<double>(highest) - lowest;
  peak.peak_ratio = span / std::max(static_cast<double>(second) - lowest, span / kMaxPeakRatio);
  const double centre = highest;
  peak.u_px = correlation_lag_px(c, m) + gaussian_peak_offset_px(at(r, c - 1), centre, at(r, c + 1));
  peak.v_px = correlation_lag_px(r, m) + gaussian_peak_offset_px(at(r - 1, c), centre, at(r + 1, c));
  return peak;
}

}  // namespace glasspiv
