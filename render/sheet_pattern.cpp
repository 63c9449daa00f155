#include "render/sheet_pattern.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace glasspiv {

namespace {

SheetPicture blank(double extent_s_mm, double extent_t_mm, double mm_per_texel) {
  if (!(extent_s_mm > 0 && extent_t_mm > 0 && mm_per_texel > 0))
    throw std::invalid_argument("sheet picture: extents and texel size must be positive");
  const double cols = std::ceil(extent_s_mm / mm_per_texel), rows = std::ceil(extent_t_mm / mm_per_texel);
  if (cols * rows > 4e8) throw std::invalid_argument("sheet picture: more than 4e8 texels; use larger texels");
  SheetPicture p;
  p.cols = static_cast<int>(cols);
  p.rows = static_cast<int>(rows);
  p.mm_per_texel = mm_per_texel;
  p.values.assign(static_cast<std::size_t>(p.rows) * static_cast<std::size_t>(p.cols), 0.0f);
  return p;
}

// Sheet coordinates of a texel centre.
double s_of(const SheetPicture& p, int col) { return (col - 0.5 * (p.cols - 1)) * p.mm_per_texel; }
double t_of(const SheetPicture& p, int row) { return -(row - 0.5 * (p.rows - 1)) * p.mm_per_texel; }

// Length of [x - h, x + h] covered by lines of width w centred on multiples of pitch.
double line_coverage(double x, double h, double pitch, double w) {
  double covered = 0;
  const long k0 = static_cast<long>(std::floor((x - h - w) / pitch)), k1 = static_cast<long>(std::ceil((x + h + w) / pitch));
  for (long k = k0; k <= k1; ++k) {
    const double c = k * pitch;
    covered += std::max(0.0, std::min(x + h, c + 0.5 * w) - std::max(x - h, c - 0.5 * w));
  }
  return covered;
}

}  // namespace

SheetPicture checkerboard_picture(double extent_s_mm, double extent_t_mm, double square_mm, int texels_per_square) {
  if (!(square_mm > 0) || texels_per_square < 1) throw std::invalid_argument("checkerboard: bad square size");
  SheetPicture p = blank(extent_s_mm, extent_t_mm, square_mm / texels_per_square);
  for (int r = 0; r < p.rows; ++r)
    for (int c = 0; c < p.cols; ++c) {
      const long i = static_cast<long>(std::floor(s_of(p, c) / square_mm)) +
                     static_cast<long>(std::floor(t_of(p, r) / square_mm));
      p.values[static_cast<std::size_t>(r) * p.cols + c] = (i & 1) ? 1.0f : 0.0f;
    }
  return p;
}

SheetPicture grid_picture(double extent_s_mm, double extent_t_mm, double pitch_mm, double line_mm,
                          double mm_per_texel) {
  if (!(pitch_mm > 0 && line_mm > 0 && line_mm < pitch_mm)) throw std::invalid_argument("grid: need 0 < line < pitch");
  SheetPicture p = blank(extent_s_mm, extent_t_mm, mm_per_texel);
  const double h = 0.5 * mm_per_texel;
  for (int r = 0; r < p.rows; ++r) {
    const double ft = line_coverage(t_of(p, r), h, pitch_mm, line_mm) / mm_per_texel;
    for (int c = 0; c < p.cols; ++c) {
      const double fs = line_coverage(s_of(p, c), h, pitch_mm, line_mm) / mm_per_texel;
      p.values[static_cast<std::size_t>(r) * p.cols + c] = static_cast<float>(fs + ft - fs * ft);  // union
    }
  }
  return p;
}

SheetPicture particle_picture(double extent_s_mm, double extent_t_mm, double particles_per_mm2, double diameter_mm,
                              double mm_per_texel, std::uint64_t seed) {
  if (!(particles_per_mm2 >= 0 && diameter_mm > 0)) throw std::invalid_argument("particles: bad density or diameter");
  SheetPicture p = blank(extent_s_mm, extent_t_mm, mm_per_texel);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> us(-0.5 * extent_s_mm, 0.5 * extent_s_mm), ut(-0.5 * extent_t_mm, 0.5 * extent_t_mm);
  const auto count = static_cast<long>(std::llround(particles_per_mm2 * extent_s_mm * extent_t_mm));
  const double radius_e2 = 0.5 * diameter_mm;  // exp(-2 r^2 / radius_e2^2) = e^-2 at the rim
  const double reach = 1.5 * diameter_mm;      // exp(-18): nothing visible beyond
  std::vector<double> acc(p.values.size(), 0.0);
  for (long i = 0; i < count; ++i) {
    const double s = us(rng), t = ut(rng);
    const double cc = s / mm_per_texel + 0.5 * (p.cols - 1), rc = -t / mm_per_texel + 0.5 * (p.rows - 1);
    const int c0 = std::max(0, static_cast<int>(std::floor(cc - reach / mm_per_texel)));
    const int c1 = std::min(p.cols - 1, static_cast<int>(std::ceil(cc + reach / mm_per_texel)));
    const int r0 = std::max(0, static_cast<int>(std::floor(rc - reach / mm_per_texel)));
    const int r1 = std::min(p.rows - 1, static_cast<int>(std::ceil(rc + reach / mm_per_texel)));
    for (int r = r0; r <= r1; ++r)
      for (int c = c0; c <= c1; ++c) {
        const double ds = (c - cc) * mm_per_texel, dt = (r - rc) * mm_per_texel;
        acc[static_cast<std::size_t>(r) * p.cols + c] += std::exp(-2.0 * (ds * ds + dt * dt) / (radius_e2 * radius_e2));
      }
  }
  for (std::size_t i = 0; i < acc.size(); ++i) p.values[i] = static_cast<float>(std::min(1.0, acc[i]));
  return p;
}

}  // namespace glasspiv
