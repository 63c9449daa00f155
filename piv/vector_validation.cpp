#include "piv/vector_validation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace glasspiv {
namespace {

double median_of(double* first, int n) {
  std::sort(first, first + n);
  return n % 2 ? first[n / 2] : 0.5 * (first[n / 2 - 1] + first[n / 2]);
}

// |U_0 - U_m| / (r_m + eps) for one component over n neighbour values (reordered).
double normalised_residual(double centre, double* neighbours, int n, double epsilon) {
  const double um = median_of(neighbours, n);
  double residuals[8];
  for (int i = 0; i < n; ++i) residuals[i] = std::abs(neighbours[i] - um);
  const double rm = median_of(residuals, n);
  return std::abs(centre - um) / (rm + epsilon);
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
  auto gather = [&](int col, int row, const std::vector<std::uint8_t>& use, double* u, double* v) {
    const int bc = std::clamp(col, lo_c, hi_c), br = std::clamp(row, lo_r, hi_r);
    int k = 0;
    for (int r = br - 1; r <= br + 1; ++r)
      for (int c = bc - 1; c <= bc + 1; ++c) {
        if ((c == col && r == row) || c < 0 || r < 0 || c >= cols || r >= rows) continue;
        const std::size_t j = static_cast<std::size_t>(r) * cols + c;
        if (!use[j]) continue;
        u[k] = u_px[j];
        v[k] = v_px[j];
        ++k;
      }
    return k;
  };
  std::vector<std::uint8_t> usable(n), outlier(n, 0);
  for (std::size_t i = 0; i < n; ++i) usable[i] = flags[i] != VectorFlag::invalid;
  MedianTestCounts counts;
  double u[8], v[8];
  for (int row = 0; row < rows; ++row)
    for (int col = 0; col < cols; ++col) {
      const std::size_t i = static_cast<std::size_t>(row) * cols + col;
      if (!usable[i]) continue;
      const int k = gather(col, row, usable, u, v);
      if (k < options.min_neighbours) continue;
      const double ru = normalised_residual(u_px[i], u, k, options.epsilon_px);
      const double rv = normalised_residual(v_px[i], v, k, options.epsilon_px);
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
      const int k = gather(col, row, passed, u, v);
      if (k == 0) {
        new_u[i] = new_v[i] = std::numeric_limits<double>::quiet_NaN();
        flags[i] = VectorFlag::invalid;
        ++counts.unreplaceable;
      } else {
        new_u[i] = median_of(u, k);
        new_v[i] = median_of(v, k);
        flags[i] = VectorFlag::replaced;
        ++counts.replaced;
      }
    }
  u_px.swap(new_u);
  v_px.swap(new_v);
  return counts;
}

}  // namespace glasspiv
