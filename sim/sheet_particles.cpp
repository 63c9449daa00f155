#include "sim/sheet_particles.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace glasspiv {

std::vector<float> SheetParticles::on(const SheetGrid& g) const {
  std::vector<float> v(g.cell_count(), 0.0f);
  const double reach = 2 * diameter_mm, r2 = 0.25 * diameter_mm * diameter_mm;
  for (const SheetParticle& p : particles) {
    const int c0 = std::max(0, int(std::floor(g.col(p.s_mm - reach))));
    const int c1 = std::min(g.cols - 1, int(std::ceil(g.col(p.s_mm + reach))));
    const int r0 = std::max(0, int(std::floor(g.row(p.t_mm + reach))));
    const int r1 = std::min(g.rows - 1, int(std::ceil(g.row(p.t_mm - reach))));
    for (int r = r0; r <= r1; ++r)
      for (int c = c0; c <= c1; ++c) {
        const double ds = g.s_mm(c) - p.s_mm, dt = g.t_mm(r) - p.t_mm;
        v[static_cast<std::size_t>(r) * g.cols + c] += static_cast<float>(std::exp(-2 * (ds * ds + dt * dt) / r2));
      }
  }
  return v;
}

SheetTexture SheetParticles::texture(const SheetPlane& sheet, double mm_per_texel) const {
  const SheetGrid fine = sheet_grid_covering(sheet, mm_per_texel);
  const std::vector<float> v = on(fine);
  return SheetTexture(v.data(), fine.rows, fine.cols, fine.mm_per_px);
}

SheetParticles random_sheet_particles(const SheetPlane& sheet, double per_mm2, double diameter_mm, std::uint64_t seed) {
  SheetParticles f;
  f.diameter_mm = diameter_mm;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> us(-0.5 * sheet.extent_s_mm, 0.5 * sheet.extent_s_mm),
      ut(-0.5 * sheet.extent_t_mm, 0.5 * sheet.extent_t_mm);
  const auto n = static_cast<long>(per_mm2 * sheet.extent_s_mm * sheet.extent_t_mm);
  for (long i = 0; i < n; ++i) f.particles.push_back({us(rng), ut(rng)});
  return f;
}

std::vector<std::uint8_t> valid_cells(const std::vector<CellState>& states) {
  std::vector<std::uint8_t> use(states.size());
  for (std::size_t i = 0; i < use.size(); ++i) use[i] = states[i] == CellState::valid;
  return use;
}

double ncc_where(const std::vector<float>& a, const std::vector<float>& b, const std::vector<std::uint8_t>& use) {
  double sa = 0, sb = 0, n = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (use[i]) {
      sa += a[i];
      sb += b[i];
      ++n;
    }
  if (n == 0) return 0;
  const double ma = sa / n, mb = sb / n;
  double ab = 0, aa = 0, bb = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (use[i]) {
      ab += (a[i] - ma) * (b[i] - mb);
      aa += (a[i] - ma) * (a[i] - ma);
      bb += (b[i] - mb) * (b[i] - mb);
    }
  return aa > 0 && bb > 0 ? ab / std::sqrt(aa * bb) : 0.0;
}

double rms_difference_where(const std::vector<float>& a, const std::vector<float>& b,
                            const std::vector<std::uint8_t>& use) {
  double s = 0, n = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (use[i]) {
      s += (double(a[i]) - b[i]) * (double(a[i]) - b[i]);
      ++n;
    }
  return n ? std::sqrt(s / n) : 0.0;
}

double mean_centroid_error_cells(const std::vector<float>& l, const SheetParticles& f, const SheetGrid& g,
                                 const std::vector<std::uint8_t>& use, int* counted) {
  const int half = static_cast<int>(std::ceil(f.diameter_mm / g.mm_per_px));
  const double near_mm = 3 * f.diameter_mm;
  // Isolation through buckets of near_mm: only neighbouring buckets can hold a near particle.
  double smin = 0, tmin = 0, smax = 0, tmax = 0;
  for (std::size_t k = 0; k < f.particles.size(); ++k) {
    const SheetParticle& p = f.particles[k];
    smin = k ? std::min(smin, p.s_mm) : p.s_mm;
    tmin = k ? std::min(tmin, p.t_mm) : p.t_mm;
    smax = k ? std::max(smax, p.s_mm) : p.s_mm;
    tmax = k ? std::max(tmax, p.t_mm) : p.t_mm;
  }
  const int bc = std::max(1, int((smax - smin) / near_mm) + 1), br = std::max(1, int((tmax - tmin) / near_mm) + 1);
  std::vector<std::vector<std::size_t>> bucket(static_cast<std::size_t>(bc) * br);
  auto bucket_of = [&](const SheetParticle& p) {
    return std::make_pair(int((p.s_mm - smin) / near_mm), int((p.t_mm - tmin) / near_mm));
  };
  for (std::size_t k = 0; k < f.particles.size(); ++k) {
    const auto [x, y] = bucket_of(f.particles[k]);
    bucket[static_cast<std::size_t>(y) * bc + x].push_back(k);
  }
  double sum = 0;
  int n = 0;
  for (std::size_t k = 0; k < f.particles.size(); ++k) {
    const SheetParticle& p = f.particles[k];
    const auto [bx, by] = bucket_of(p);
    bool isolated = true;
    for (int y = std::max(0, by - 1); y <= std::min(br - 1, by + 1) && isolated; ++y)
      for (int x = std::max(0, bx - 1); x <= std::min(bc - 1, bx + 1) && isolated; ++x)
        for (std::size_t j : bucket[static_cast<std::size_t>(y) * bc + x])
          if (j != k && std::hypot(f.particles[j].s_mm - p.s_mm, f.particles[j].t_mm - p.t_mm) <= near_mm) {
            isolated = false;
            break;
          }
    if (!isolated) continue;
    const double x = g.col(p.s_mm), y = g.row(p.t_mm);
    const int cx = static_cast<int>(std::lround(x)), cy = static_cast<int>(std::lround(y));
    if (cx - half < 0 || cy - half < 0 || cx + half >= g.cols || cy + half >= g.rows) continue;
    bool ok = true;
    double w = 0, wx = 0, wy = 0;
    for (int r = cy - half; r <= cy + half && ok; ++r)
      for (int c = cx - half; c <= cx + half && ok; ++c) {
        const std::size_t i = static_cast<std::size_t>(r) * g.cols + c;
        ok = use[i] != 0;
        const double v = std::max(0.0f, l[i]);
        w += v;
        wx += v * c;
        wy += v * r;
      }
    if (!ok || w <= 0) continue;
    sum += std::hypot(wx / w - x, wy / w - y);
    ++n;
  }
  *counted = n;
  return n ? sum / n : std::nan("");
}

}  // namespace glasspiv
