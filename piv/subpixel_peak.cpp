#include "piv/subpixel_peak.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <vector>

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

namespace {

// Highest and lowest of p[0 .. n), eight lanes at a time (vectorised).
void row_extremes(const float* p, int n, float& lowest, float& highest) {
  int i = 0;
  float lo = p[0], hi = p[0];
  if (n >= 8) {
    float l[8], h[8];
    for (int j = 0; j < 8; ++j) l[j] = h[j] = p[j];
    for (i = 8; i + 8 <= n; i += 8)
      for (int j = 0; j < 8; ++j) {
        l[j] = std::min(l[j], p[i + j]);
        h[j] = std::max(h[j], p[i + j]);
      }
    for (int j = 0; j < 8; ++j) lo = std::min(lo, l[j]), hi = std::max(hi, h[j]);
  }
  for (; i < n; ++i) lo = std::min(lo, p[i]), hi = std::max(hi, p[i]);
  lowest = lo;
  highest = hi;
}

float range_max(const float* p, int begin, int end, float init) {
  for (int i = begin; i < end; ++i) init = std::max(init, p[i]);
  return init;
}

}  // namespace

CorrelationPeak find_correlation_peak(const float* plane, int plane_px, int exclusion_radius_px) {
  const int m = plane_px;
  // One pass: each row's highest and lowest sample; the integer peak is the
  // first sample (row-major) equal to the highest.
  // Per-row highest samples, on the stack for the usual plane sizes.
  float small[256];
  std::vector<float> large(m > 256 ? static_cast<std::size_t>(m) : 0);
  float* row_highest = m > 256 ? large.data() : small;
  float lowest = plane[0], highest = plane[0];
  int r = 0;
  for (int row = 0; row < m; ++row) {
    float lo, hi;
    row_extremes(plane + row * m, m, lo, hi);
    row_highest[row] = hi;
    lowest = std::min(lowest, lo);
    if (hi > highest || row == 0) {
      highest = hi;
      r = row;
    }
  }
  CorrelationPeak peak;
  if (!(highest > lowest)) return peak;
  const float* peak_row = plane + r * m;
  int c = 0;
  while (peak_row[c] != highest) ++c;
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
    if (!in_band(row, r)) {
      second = std::max(second, row_highest[row]);
      continue;
    }
    if (2 * e + 1 >= m) continue;  // the band covers every column
    // The columns c + e + 1 ... c - e - 1 + m (mod m), as at most two runs.
    const float* p = plane + row * m;
    const int first = c + e + 1, last = c - e - 1 + m;  // inclusive, first <= last
    if (last < m) {
      second = range_max(p, first, last + 1, second);
    } else if (first >= m) {
      second = range_max(p, first - m, last - m + 1, second);
    } else {
      second = range_max(p, first, m, second);
      second = range_max(p, 0, last - m + 1, second);
    }
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
