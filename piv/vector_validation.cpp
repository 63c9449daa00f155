#include "piv/vector_validation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include "piv/row_threads.h"

namespace glasspiv {
namespace {

// The median (of an even count: the mean of the two middle values); reorders.
double median_of(double* first, int n) {
  const int m = n / 2;
  std::nth_element(first, first + m, first + n);
  return n % 2 ? first[m] : 0.5 * (*std::max_element(first, first + m) + first[m]);
}

// The test's neighbours of a vector: values and grid offsets from it.
struct Neighbours {
  int n = 0;
  double u[8], v[8];
  int dc[8], dr[8];
};

// A component's local gradient per grid step.
struct Gradient {
  double per_col = 0, per_row = 0;
};

// The local gradients of u and v from the 5 x 5 block around (col, row): per
// axis the median of the slopes between the block's usable vectors (the
// centre left out) that share a grid row (columns: a grid column). Up to 50
// pairs per axis, so a few outlying neighbours do not tilt it (the 3 x 3
// block next to a mask can have two pairs). 0 along an axis with no pair.
void block_gradients(const std::vector<double>& u, const std::vector<double>& v, const std::vector<std::uint8_t>& use,
                     int cols, int rows, int col, int row, Gradient& gu, Gradient& gv) {
  double u_slopes[50], v_slopes[50];
  const auto along = [&](bool rows_of_block) {
    int count = 0;
    for (int line = -2; line <= 2; ++line) {
      std::size_t at[5];
      int step[5], k = 0;
      for (int t = -2; t <= 2; ++t) {
        const int c = rows_of_block ? col + t : col + line, r = rows_of_block ? row + line : row + t;
        if (c < 0 || r < 0 || c >= cols || r >= rows || (c == col && r == row)) continue;
        const std::size_t j = static_cast<std::size_t>(r) * cols + c;
        if (!use[j]) continue;
        at[k] = j;
        step[k++] = t;
      }
      for (int a = 0; a < k; ++a)
        for (int b = a + 1; b < k; ++b) {
          const double d = step[a] - step[b];
          u_slopes[count] = (u[at[a]] - u[at[b]]) / d;
          v_slopes[count++] = (v[at[a]] - v[at[b]]) / d;
        }
    }
    return count;
  };
  int count = along(true);
  gu.per_col = count ? median_of(u_slopes, count) : 0.0;
  gv.per_col = count ? median_of(v_slopes, count) : 0.0;
  count = along(false);
  gu.per_row = count ? median_of(u_slopes, count) : 0.0;
  gv.per_row = count ? median_of(v_slopes, count) : 0.0;
}

// The neighbours' values carried to the vector's place along the local
// gradient g, then their median U_m and the median of their residuals r_m.
struct MedianEstimate {
  double median = 0, residual = 0;
};
MedianEstimate median_estimate(const double* value, const Neighbours& nb, const Gradient& g) {
  double carried[8], residuals[8];
  for (int j = 0; j < nb.n; ++j) carried[j] = value[j] - g.per_col * nb.dc[j] - g.per_row * nb.dr[j];
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
  auto gather = [&](int col, int row, const std::vector<std::uint8_t>& use) {
    const int bc = std::clamp(col, lo_c, hi_c), br = std::clamp(row, lo_r, hi_r);
    Neighbours nb;
    for (int r = br - 1; r <= br + 1; ++r)
      for (int c = bc - 1; c <= bc + 1; ++c) {
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
  // Each vector's verdict depends only on the field as it came in: rows in parallel.
  for_each_row(rows, options.threads, [&](int row, int) {
    for (int col = 0; col < cols; ++col) {
      const std::size_t i = static_cast<std::size_t>(row) * cols + col;
      if (!usable[i]) continue;
      const Neighbours nb = gather(col, row, usable);
      if (nb.n < options.min_neighbours) continue;
      Gradient gu, gv;
      if (follow) block_gradients(u_px, v_px, usable, cols, rows, col, row, gu, gv);
      const MedianEstimate eu = median_estimate(nb.u, nb, gu), ev = median_estimate(nb.v, nb, gv);
      const double ru = std::abs(u_px[i] - eu.median) / (eu.residual + options.epsilon_px);
      const double rv = std::abs(v_px[i] - ev.median) / (ev.residual + options.epsilon_px);
      outlier[i] = ru > options.threshold || rv > options.threshold || !std::isfinite(u_px[i]) || !std::isfinite(v_px[i]);
    }
  });
  for (std::size_t i = 0; i < n; ++i) counts.outliers += outlier[i];
  // Replacement from the neighbours that passed, all decided on the tested field.
  std::vector<std::uint8_t> passed(n);
  for (std::size_t i = 0; i < n; ++i) passed[i] = usable[i] && !outlier[i];
  std::vector<double> new_u(u_px), new_v(v_px);
  for (int row = 0; row < rows; ++row)
    for (int col = 0; col < cols; ++col) {
      const std::size_t i = static_cast<std::size_t>(row) * cols + col;
      if (!outlier[i]) continue;
      const Neighbours nb = gather(col, row, passed);
      if (nb.n == 0) {
        new_u[i] = new_v[i] = std::numeric_limits<double>::quiet_NaN();
        flags[i] = VectorFlag::invalid;
        ++counts.unreplaceable;
      } else {
        Gradient gu, gv;
        if (follow) block_gradients(u_px, v_px, passed, cols, rows, col, row, gu, gv);
        new_u[i] = median_estimate(nb.u, nb, gu).median;
        new_v[i] = median_estimate(nb.v, nb, gv).median;
        flags[i] = VectorFlag::replaced;
        ++counts.replaced;
      }
    }
  u_px.swap(new_u);
  v_px.swap(new_v);
  return counts;
}

}  // namespace glasspiv
