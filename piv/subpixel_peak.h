#pragma once
// The correlation peak to sub-pixel precision, and the displacement it means.
//
// Three-point Gaussian fit (Willert & Gharib 1991; Raffel et al., 3rd ed.,
// eq. 5.23), per axis through the highest sample C and its neighbours L, R:
//   offset = (ln L - ln R) / (2 (ln L - 2 ln C + ln R)),
// exact for a sampled Gaussian. When L, C or R is <= 0 (the logarithm is
// undefined; normalised correlations can be negative) the parabolic fit
//   offset = (L - R) / (2 (L - 2 C + R))
// is used instead. Offsets are clamped to [-0.5, 0.5] px.
//
// Peak ratio: (highest - lowest) / (second highest - lowest) over the plane,
// the second peak being the highest sample at least exclusion_radius_px (in
// x or y) from the first. It lies in [1, kMaxPeakRatio], large for a clear
// peak (taking the lowest sample as the base keeps it defined for planes with
// negative values). No I/O.
#include "piv/cross_correlation.h"

namespace glasspiv {

inline constexpr double kMaxPeakRatio = 1e6;

double gaussian_peak_offset_px(double left, double centre, double right);
double parabolic_peak_offset_px(double left, double centre, double right);

struct CorrelationPeak {
  bool found = false;  // false: flat plane (all samples equal) or a correlator that failed
  // Displacement of frame B relative to frame A in px: u along +x (columns),
  // v along +y (rows); the sub-pixel lag of the highest peak (cross_correlation.h).
  double u_px = 0, v_px = 0;
  double height = 0;      // R at the integer peak
  double peak_ratio = 0;  // see above; 0 when not found
};

// The peak of an unshifted plane of plane_px x plane_px (cross_correlation.h),
// neighbours taken with wrap-around.
CorrelationPeak find_correlation_peak(const float* plane, int plane_px, int exclusion_radius_px = 2);
inline CorrelationPeak find_correlation_peak(const WindowCorrelator& c, int exclusion_radius_px = 2) {
  return find_correlation_peak(c.plane(), c.plane_px(), exclusion_radius_px);
}

}  // namespace glasspiv
