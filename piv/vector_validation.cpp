#include "piv/vector_validation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

namespace glasspiv {
namespace {

double median_of(double* first, int n) {
  std::sort(first, first + n);
  return n % 2 ? first[n / 2] : 0.5 * (first[n / 2 - 1] + first[n / 2]);
}

// The neighbours of a vector: values and grid offsets from it, up to the 5 x 5
// block around it.
struct Neighbours {
  static constexpr int kMax = 24;
  int n = 0;
  double u[kMax], v[kMax];
  int dc[kMax], dr[kMax];
};

// The local gradient of one component per grid step, (d/dcol, d/drow), from
// the 5 x 5 block's neighbours: the median of the slopes between neighbours
// of one grid row (columns: one grid column). Up to 50 pairs per axis, so a
// few outlying neighbours do not tilt it (the 3 x 3 block next to a mask can
// have two pairs). 0 along an axis with no such pair.
std::pair<double, double> robust_gradient(const double* value, const Neighbours& nb) {
  double along_c[50], along_r[50];
  int nc = 0, nr = 0;
  for (int j = 0; j < nb.n; ++j)
    for (int k = j + 1; k < nb.n; ++k) {
      if (nb.dr[j] == nb.dr[k] && nb.dc[j] != nb.dc[k])
        along_c[nc++] = (value[j] - value[k]) / (nb.dc[j] - nb.dc[k]);
      if (nb.dc[j] == nb.dc[k] && nb.dr[j] != nb.dr[k])
        along_r[nr++] = (value[j] - value[k]) / (nb.dr[j] - nb.dr[k]);
    }
  return {nc ? median_of(along_c, nc) : 0.0, nr ? median_of(along_r, nr) : 0.0};
}

// The neighbours' values carried to the vector's place along the local
// gradient (or as they are), then their median U_m and the median of their
// residuals r_m.
struct MedianEstimate {
  double median = 0, residual = 0;
};
// slope: the 5 x 5 block's neighbours (slope_value: their values of the component), or nullptr for none.
MedianEstimate median_estimate(const double* value, const Neighbours& nb, const double* slope_value,
                               const Neighbours* slope) {
  double carried[8], residuals[8];
  const auto [per_col, per_row] = slope ? robust_gradient(slope_value, *slope) : std::pair<double, double>{};
  for (int j = 0; j < nb.n; ++j) carried[j] = value[j] - per_col * nb.dc[j] - per_row * nb.dr[j];
  MedianEstimate e;
  e.median = median_of(carried, nb.n);
  for (int j = 0; j < nb.n; ++j) residuals[j] = std::abs(carried[j] - e.median);
  e.residual = median_of(residuals, nb.n);
  return e;
}

}  // namespace

MedianTestCounts normalised_median_test(int cols, int rows, std::vector<double>& u_px, std::vector<double>& v_px,
                                        std::vector<VectorFlag>& flags, const MedianTestOptions& options) {
  const std::size_t n = static_cast<std::size_t>(cols) * rows;
  if (cols < 0 || rows < 0 || u_px.size() != n || v_px.size() != n || flags.size() != n)
    throw std::invalid_argument("normalised_median_test: field sizes differ from cols x rows");
  // The 3 x 3 block around (col, row), moved inwards at the borders so that it
  // lies inside the grid; its usable members other than (col, row) itself.
  const int lo_c = cols >= 3 ? 1 : 0, hi_c = cols >= 3 ? cols - 2 : cols - 1;
  const int lo_r = rows >= 3 ? 1 : 0, hi_r = rows >= 3 ? rows - 2 : rows - 1;
  // radius 1: the test's 3 x 3 block (moved inwards at the borders); 2: the
  // 5 x 5 block around the vector for the gradient.
  auto gather = [&](int col, int row, const std::vector<std::uint8_t>& use, int radius) {
    const int bc = radius == 1 ? std::clamp(col, lo_c, hi_c) : col, br = radius == 1 ? std::clamp(row, lo_r, hi_r) : row;
    Neighbours nb;
    for (int r = br - radius; r <= br + radius; ++r)
      for (int c = bc - radius; c <= bc + radius; ++c) {
        if ((c == col && r == row) || c < 0 || r < 0 || c >= cols || r >= rows) continue;
        const std::size_t j = static_cast<std::size_t>(r) * cols + c;
        if (!use[j]) continue;
        nb.u[nb.n] = u_px[j];
        nb.v[nb.n] = v_px[j];
        nb.dc[nb.n] = c - col;
        nb.dr[nb.n] = r - row;
        ++nb.n;
      }
    return nb;
  };
  std::vector<std::uint8_t> usable(n), outlier(n, 0);
  for (std::size_t i = 0; i < n; ++i) usable[i] = flags[i] != VectorFlag::invalid;
  MedianTestCounts counts;
  const bool follow = options.follow_gradient;
  for (int row = 0; row < rows; ++row)
    for (int col = 0; col < cols; ++col) {
      const std::size_t i = static_cast<std::size_t>(row) * cols + col;
      if (!usable[i]) continue;
      const Neighbours nb = gather(col, row, usable, 1);
      if (nb.n < options.min_neighbours) continue;
      const Neighbours wide = follow ? gather(col, row, usable, 2) : Neighbours{};
      const Neighbours* slope = follow ? &wide : nullptr;
      const MedianEstimate eu = median_estimate(nb.u, nb, wide.u, slope), ev = median_estimate(nb.v, nb, wide.v, slope);
      const double ru = std::abs(u_px[i] - eu.median) / (eu.residual + options.epsilon_px);
      const double rv = std::abs(v_px[i] - ev.median) / (ev.residual + options.epsilon_px);
      if (ru > options.threshold || rv > options.threshold || !std::isfinite(u_px[i]) || !std::isfinite(v_px[i])) {
        outlier[i] = 1;
        ++counts.outliers;
      }
    }
  // Replacement from the neighbours that passed, all decided on the tested field.
  std::vector<std::uint8_t> passed(n);
  for (std::size_t i = 0; i < n; ++i) passed[i] = usable[i] && !outlier[i];
  std::vector<double> new_u(u_px), new_v(v_px);
  for (int row = 0; row < rows; ++row)
    for (int col = 0; col < cols; ++col) {
      const std::size_t i = static_cast<std::size_t>(row) * cols + col;
      if (!outlier[i]) continue;
      const Neighbours nb = gather(col, row, passed, 1);
      const Neighbours wide = follow ? gather(col, row, passed, 2) : Neighbours{};
      const Neighbours* slope = follow ? &wide : nullptr;
      if (nb.n == 0) {
        new_u[i] = new_v[i] = std::numeric_limits<double>::quiet_NaN();
        flags[i] = VectorFlag::invalid;
        ++counts.unreplaceable;
      } else {
        new_u[i] = median_estimate(nb.u, nb, wide.u, slope).median;
        new_v[i] = median_estimate(nb.v, nb, wide.v, slope).median;
        flags[i] = VectorFlag::replaced;
        ++counts.replaced;
      }
    }
  u_px.swap(new_u);
  v_px.swap(new_v);
  return counts;
}

}  // namespace glasspiv
