#include "render/sheet_texture.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace glasspiv {

SheetTexture::SheetTexture(const float* values, int rows, int cols, double mm_per_texel,
                           const Eigen::Vector2d& centre_st_mm)
    : mm_per_texel_(mm_per_texel), centre_st_mm_(centre_st_mm) {
  if (rows < 1 || cols < 1 || !values) throw std::invalid_argument("SheetTexture: empty picture");
  if (!(mm_per_texel > 0) || !std::isfinite(mm_per_texel))
    throw std::invalid_argument("SheetTexture: mm_per_texel must be positive");
  levels_.emplace_back(values, values + static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols));
  rows_.push_back(rows);
  cols_.push_back(cols);
  // Box-filtered pyramid down to one texel: level L+1 texel (r, c) is the mean
  // of level L's texels (2r..2r+1, 2c..2c+1) that exist (odd edges average fewer).
  while (rows_.back() > 1 || cols_.back() > 1) {
    const std::vector<float>& src = levels_.back();
    const int sr = rows_.back(), sc = cols_.back();
    const int dr = (sr + 1) / 2, dc = (sc + 1) / 2;
    std::vector<float> dst(static_cast<std::size_t>(dr) * dc);
    for (int r = 0; r < dr; ++r) {
      for (int c = 0; c < dc; ++c) {
        double sum = 0;
        int n = 0;
        for (int y = 2 * r; y < std::min(2 * r + 2, sr); ++y)
          for (int x = 2 * c; x < std::min(2 * c + 2, sc); ++x, ++n) sum += src[static_cast<std::size_t>(y) * sc + x];
        dst[static_cast<std::size_t>(r) * dc + c] = static_cast<float>(sum / n);
      }
    }
    levels_.push_back(std::move(dst));
    rows_.push_back(dr);
    cols_.push_back(dc);
  }
}

double SheetTexture::bilinear(int level, double x, double y) const {
  const int rows = rows_[static_cast<std::size_t>(level)], cols = cols_[static_cast<std::size_t>(level)];
  if (!(x > -1 && y > -1 && x < cols && y < rows)) return 0.0;  // every tap outside: dark
  const double fx0 = std::floor(x), fy0 = std::floor(y);
  const int x0 = static_cast<int>(fx0), y0 = static_cast<int>(fy0);
  const double fx = x - fx0, fy = y - fy0;
  const std::vector<float>& v = levels_[static_cast<std::size_t>(level)];
  auto texel = [&](int r, int c) -> double {
    return (r < 0 || c < 0 || r >= rows || c >= cols) ? 0.0 : v[static_cast<std::size_t>(r) * cols + c];
  };
  return (1 - fy) * ((1 - fx) * texel(y0, x0) + fx * texel(y0, x0 + 1)) +
         fy * ((1 - fx) * texel(y0 + 1, x0) + fx * texel(y0 + 1, x0 + 1));
}

float SheetTexture::at(double s_mm, double t_mm) const {
  const double x = (s_mm - centre_st_mm_.x()) / mm_per_texel_ + 0.5 * (cols_[0] - 1);
  const double y = -(t_mm - centre_st_mm_.y()) / mm_per_texel_ + 0.5 * (rows_[0] - 1);
  return static_cast<float>(bilinear(0, x, y));
}

float SheetTexture::average(double s_mm, double t_mm, const Eigen::Matrix2d& dst_dpixel) const {
  // Footprint axes in level-0 texels (x = col grows with s, y = row grows with -t).
  Eigen::Vector2d a(dst_dpixel(0, 0), -dst_dpixel(1, 0)), b(dst_dpixel(0, 1), -dst_dpixel(1, 1));
  a /= mm_per_texel_;
  b /= mm_per_texel_;
  const double longest = std::max(a.norm(), b.norm());
  if (!std::isfinite(longest)) return at(s_mm, t_mm);
  int level = 0;
  if (longest > kMaxTapsPerAxis)
    level = std::min(levels() - 1, static_cast<int>(std::ceil(std::log2(longest / kMaxTapsPerAxis))));
  const double scale = std::ldexp(1.0, -level);
  a *= scale;
  b *= scale;
  // Centre in this level's texel coordinates: level-L texel centre i covers level-0 texels [i 2^L, (i+1) 2^L).
  const double x0 = ((s_mm - centre_st_mm_.x()) / mm_per_texel_ + 0.5 * (cols_[0] - 1) + 0.5) * scale - 0.5;
  const double y0 = (-(t_mm - centre_st_mm_.y()) / mm_per_texel_ + 0.5 * (rows_[0] - 1) + 0.5) * scale - 0.5;
  const int na = std::clamp(static_cast<int>(std::ceil(a.norm())), 1, kMaxTapsPerAxis);
  const int nb = std::clamp(static_cast<int>(std::ceil(b.norm())), 1, kMaxTapsPerAxis);
  if (na == 1 && nb == 1) return static_cast<float>(bilinear(level, x0, y0));
  double sum = 0;
  for (int j = 0; j < nb; ++j) {
    const double v = (j + 0.5) / nb - 0.5;
    for (int i = 0; i < na; ++i) {
      const double u = (i + 0.5) / na - 0.5;
      sum += bilinear(level, x0 + u * a.x() + v * b.x(), y0 + u * a.y() + v * b.y());
    }
  }
  return static_cast<float>(sum / (na * nb));
}

}  // namespace glasspiv
