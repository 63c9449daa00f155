#include "targets/speckle_plate.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace glasspiv {
namespace {

// Integral of the half chord s(u) = sqrt(R^2 - u^2) over [a, b] ∩ [-R, R]:
// S(u) = (u s(u) + R^2 asin(u / R)) / 2.
double half_chord_integral(double a, double b, double radius) {
  a = std::clamp(a, -radius, radius);
  b = std::clamp(b, -radius, radius);
  if (!(b > a)) return 0;
  const double r2 = radius * radius;
  const auto antiderivative = [&](double u) {
    return 0.5 * (u * std::sqrt(std::max(0.0, r2 - u * u)) + r2 * std::asin(std::clamp(u / radius, -1.0, 1.0)));
  };
  return antiderivative(b) - antiderivative(a);
}

// Integral over [a, b] of min(h, s(u)), h >= 0: the part of the disc's upper
// half below height h.
double capped_half_chord_integral(double a, double b, double radius, double h) {
  a = std::clamp(a, -radius, radius);
  b = std::clamp(b, -radius, radius);
  if (!(b > a)) return 0;
  const double whole = half_chord_integral(a, b, radius);
  if (h >= radius) return whole;
  const double w = std::sqrt(radius * radius - h * h);  // s(u) >= h for |u| <= w
  const double ia = std::max(a, -w), ib = std::min(b, w);
  if (!(ib > ia)) return whole;
  return whole - half_chord_integral(ia, ib, radius) + h * (ib - ia);
}

// u in [0, 1) from one 64-bit draw: its top 53 bits, exactly.
double unit_from_draw(std::uint64_t draw) { return static_cast<double>(draw >> 11) * 0x1.0p-53; }

}  // namespace

double disc_rectangle_area(const Eigen::Vector2d& centre, double radius, double x0, double y0, double x1, double y1) {
  if (!(radius > 0) || !(x1 > x0) || !(y1 > y0)) return 0;
  const double a = x0 - centre.x(), b = x1 - centre.x();
  // The chord at u spans [-s, s]; its part below y has length s + sign(y) min(|y|, s).
  const auto below = [&](double y) {
    const double part = capped_half_chord_integral(a, b, radius, std::abs(y));
    return y < 0 ? -part : part;
  };
  return std::max(0.0, below(y1 - centre.y()) - below(y0 - centre.y()));
}

double speckle_expected_fill(double rho) {
  if (!(rho > 0)) return 0;
  const double radius = rho / 2;
  const int reach = static_cast<int>(std::ceil(radius)) + 1;
  constexpr int kHalf = 16;  // 32 x 32 midpoints over the cell, 16 x 16 in the quarter [0, 1/2]^2
  double uncovered = 0;
  for (int a = 0; a < kHalf; ++a) {
    for (int b = 0; b < kHalf; ++b) {
      const Eigen::Vector2d x((a + 0.5) / (2 * kHalf), (b + 0.5) / (2 * kHalf));
      double none = 1;  // probability that no cell's disc covers x
      for (int n = -reach; n <= reach; ++n)
        for (int m = -reach; m <= reach; ++m)
          none *= 1 - disc_rectangle_area(x, radius, m, n, m + 1, n + 1);
      uncovered += none;
    }
  }
  return 1 - uncovered / (kHalf * kHalf);
}

double speckle_diameter_over_pitch(double fill) {
  double lo = 0, hi = 2;
  for (int step = 0; step < 48; ++step) {
    const double mid = 0.5 * (lo + hi);
    if (speckle_expected_fill(mid) < fill) lo = mid;
    else hi = mid;
  }
  return std::round(0.5 * (lo + hi) * 0x1.0p32) * 0x1.0p-32;
}

SpeckleGrid speckle_grid(const TargetSpec& spec) {
  SpeckleGrid g;
  const double d = spec.dot_diameter_mm;
  if (!(d > 0) || !std::isfinite(d) || !(spec.fill > 0) || !(spec.fill < 1) || !(spec.plate_size_mm.minCoeff() > 0) ||
      !spec.plate_size_mm.allFinite())
    return g;
  g.diameter_over_pitch = speckle_diameter_over_pitch(spec.fill);
  g.pitch_mm = d / g.diameter_over_pitch;
  const double across = spec.plate_size_mm.x() / g.pitch_mm, down = spec.plate_size_mm.y() / g.pitch_mm;
  if (!(across < 1e9) || !(down < 1e9)) return g;  // beyond any limit; validate_target says so
  g.cols = std::max(1, static_cast<int>(std::lround(across)));
  g.rows = std::max(1, static_cast<int>(std::lround(down)));
  g.cell_width_mm = spec.plate_size_mm.x() / g.cols;
  g.cell_height_mm = spec.plate_size_mm.y() / g.rows;
  return g;
}

std::vector<SpeckleDot> speckle_dots(const TargetSpec& spec) {
  validate_target(spec);
  const SpeckleGrid g = speckle_grid(spec);
  const double r = spec.dot_diameter_mm / 2, w = spec.plate_size_mm.x(), h = spec.plate_size_mm.y();
  std::mt19937_64 rng(spec.seed);
  std::vector<SpeckleDot> dots;
  dots.reserve(g.dot_count());
  for (int row = 0; row < g.rows; ++row) {
    const double y_lo = std::max(row * g.cell_height_mm, r), y_hi = std::min((row + 1) * g.cell_height_mm, h - r);
    for (int col = 0; col < g.cols; ++col) {
      const double x_lo = std::max(col * g.cell_width_mm, r), x_hi = std::min((col + 1) * g.cell_width_mm, w - r);
      const double u = unit_from_draw(rng()), v = unit_from_draw(rng());
      SpeckleDot dot;
      dot.centre_mm = Eigen::Vector2d(std::min(x_hi, x_lo + u * (x_hi - x_lo)), std::min(y_hi, y_lo + v * (y_hi - y_lo)));
      dot.radius_mm = r;
      dots.push_back(dot);
    }
  }
  return dots;
}

}  // namespace glasspiv
