#include "correct/reconstruct.h"

#include <cmath>
#include <stdexcept>

namespace glasspiv {
namespace {

const SheetGrid& common_grid(const std::vector<CameraImage>& images, const std::vector<CellState>& states) {
  if (images.empty()) throw std::invalid_argument("reconstruct: no camera images");
  for (const CameraImage& im : images) {
    if (!im.op || !im.image) throw std::invalid_argument("reconstruct: missing operator or image");
    if (!(im.op->grid == images.front().op->grid)) throw std::invalid_argument("reconstruct: operators on different grids");
    if (!(im.weight >= 0) || !std::isfinite(im.weight)) throw std::invalid_argument("reconstruct: bad camera weight");
  }
  const SheetGrid& grid = images.front().op->grid;
  if (states.size() != grid.cell_count()) throw std::invalid_argument("reconstruct: cell states of another grid");
  return grid;
}

// The image minus its background, times sqrt(w): the right-hand side of one
// camera; 0 at pixels that are not finite (they are left out).
std::vector<float> data_term(const CameraImage& im) {
  const CorrectionOperator& op = *im.op;
  std::vector<float> b(op.pixel_count());
  const double sw = std::sqrt(im.weight);
  for (std::size_t p = 0; p < b.size(); ++p)
    b[p] = std::isfinite(im.image[p])
               ? static_cast<float>(sw * (im.image[p] - op.background_weight[p] * im.background_radiance))
               : 0.0f;
  return b;
}

// Per camera, 1 where the pixel is finite and 0 where it is left out; empty
// for a camera whose pixels are all finite.
std::vector<std::vector<float>> finite_pixels(const std::vector<CameraImage>& images) {
  std::vector<std::vector<float>> out(images.size());
  for (std::size_t k = 0; k < images.size(); ++k) {
    const std::size_t n = images[k].op->pixel_count();
    if (count_non_finite(images[k].image, n) == 0) continue;
    out[k].resize(n);
    for (std::size_t p = 0; p < n; ++p) out[k][p] = std::isfinite(images[k].image[p]) ? 1.0f : 0.0f;
  }
  return out;
}

bool any_masked(const std::vector<std::vector<float>>& finite) {
  for (const std::vector<float>& f : finite)
    if (!f.empty()) return true;
  return false;
}

// Per cell, sum_c w_c sum_p A_c[p, cell] over the finite pixels: the weight of
// the data a cell has in this frame (its cell_weight when every pixel is finite).
std::vector<double> data_weight(const std::vector<CameraImage>& images, const std::vector<std::vector<float>>& finite) {
  const std::size_t cells = images.front().op->grid.cell_count();
  std::vector<double> weight(cells, 0.0);
  std::vector<float> per_cell(cells);
  for (std::size_t k = 0; k < images.size(); ++k) {
    const CorrectionOperator& op = *images[k].op;
    if (!finite[k].empty()) apply_transpose(op, finite[k].data(), per_cell.data());
    const std::vector<float>& w = finite[k].empty() ? op.cell_weight : per_cell;
    for (std::size_t c = 0; c < cells; ++c) weight[c] += images[k].weight * w[c];
  }
  return weight;
}

double squared_norm(const std::vector<float>& v) {
  double s = 0;
  for (float x : v) s += double(x) * x;
  return s;
}

// K = [sqrt(w_c) A_c M ; sqrt(lambda) G M] with M the valid-cell mask and G the
// forward differences between valid neighbours (right, then down).
class StackedOperator {
 public:
  StackedOperator(const std::vector<CameraImage>& images, const std::vector<CellState>& states, double lambda,
                  const std::vector<std::vector<float>>& finite)
      : images_(images), grid_(images.front().op->grid), lambda_root_(std::sqrt(lambda)), finite_(finite) {
    valid_.resize(states.size());
    for (std::size_t c = 0; c < states.size(); ++c) valid_[c] = states[c] == CellState::valid;
  }

  struct Residual {
    std::vector<std::vector<float>> camera;  // per camera, its pixels
    std::vector<float> gradient;             // 2 per cell: right, down
  };

  Residual zeros() const {
    Residual r;
    for (const CameraImage& im : images_) r.camera.emplace_back(im.op->pixel_count(), 0.0f);
    r.gradient.assign(2 * grid_.cell_count(), 0.0f);
    return r;
  }

  void apply(const std::vector<float>& x, Residual& out) const {
    for (std::size_t k = 0; k < images_.size(); ++k) {
      apply_forward(*images_[k].op, x.data(), 0.0, out.camera[k].data());
      const float sw = static_cast<float>(std::sqrt(images_[k].weight));
      for (float& v : out.camera[k]) v *= sw;
      if (!finite_[k].empty())  // a pixel left out has no row in K
        for (std::size_t p = 0; p < out.camera[k].size(); ++p) out.camera[k][p] *= finite_[k][p];
    }
    for (int row = 0; row < grid_.rows; ++row)
      for (int col = 0; col < grid_.cols; ++col) {
        const std::size_t c = static_cast<std::size_t>(row) * grid_.cols + col;
        out.gradient[2 * c] = col + 1 < grid_.cols && valid_[c] && valid_[c + 1]
                                  ? static_cast<float>(lambda_root_ * (x[c + 1] - x[c])) : 0.0f;
        out.gradient[2 * c + 1] = row + 1 < grid_.rows && valid_[c] && valid_[c + grid_.cols]
                                      ? static_cast<float>(lambda_root_ * (x[c + grid_.cols] - x[c])) : 0.0f;
      }
  }

  void apply_adjoint(const Residual& r, std::vector<float>& out) const {
    std::vector<float> tmp(grid_.cell_count());
    std::fill(out.begin(), out.end(), 0.0f);
    for (std::size_t k = 0; k < images_.size(); ++k) {
      apply_transpose(*images_[k].op, r.camera[k].data(), tmp.data());
      const float sw = static_cast<float>(std::sqrt(images_[k].weight));
      for (std::size_t c = 0; c < tmp.size(); ++c) out[c] += sw * tmp[c];
    }
    for (int row = 0; row < grid_.rows; ++row)
      for (int col = 0; col < grid_.cols; ++col) {
        const std::size_t c = static_cast<std::size_t>(row) * grid_.cols + col;
        const float gx = static_cast<float>(lambda_root_ * r.gradient[2 * c]);
        const float gy = static_cast<float>(lambda_root_ * r.gradient[2 * c + 1]);
        if (gx != 0) {
          out[c + 1] += gx;
          out[c] -= gx;
        }
        if (gy != 0) {
          out[c + grid_.cols] += gy;
          out[c] -= gy;
        }
      }
    for (std::size_t c = 0; c < out.size(); ++c)
      if (!valid_[c]) out[c] = 0;
  }

 private:
  const std::vector<CameraImage>& images_;
  const SheetGrid& grid_;
  double lambda_root_;
  const std::vector<std::vector<float>>& finite_;
  std::vector<char> valid_;
};

double squared_norm(const StackedOperator::Residual& r) {
  double s = squared_norm(r.gradient);
  for (const std::vector<float>& v : r.camera) s += squared_norm(v);
  return s;
}

// a += alpha * b over all parts.
void axpy(StackedOperator::Residual& a, double alpha, const StackedOperator::Residual& b) {
  for (std::size_t k = 0; k < a.camera.size(); ++k)
    for (std::size_t i = 0; i < a.camera[k].size(); ++i) a.camera[k][i] += static_cast<float>(alpha * b.camera[k][i]);
  for (std::size_t i = 0; i < a.gradient.size(); ++i) a.gradient[i] += static_cast<float>(alpha * b.gradient[i]);
}

double camera_rms(const StackedOperator::Residual& r) {
  double s = 0;
  std::size_t n = 0;
  for (const std::vector<float>& v : r.camera) {
    s += squared_norm(v);
    n += v.size();
  }
  return n ? std::sqrt(s / n) : 0.0;
}

}  // namespace

std::size_t count_non_finite(const float* values, std::size_t count) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < count; ++i) n += !std::isfinite(values[i]);
  return n;
}

std::vector<float> back_projection(const std::vector<CameraImage>& images, const std::vector<CellState>& states) {
  const SheetGrid& grid = common_grid(images, states);
  const std::vector<std::vector<float>> finite = finite_pixels(images);
  const bool masked = any_masked(finite);
  std::vector<float> per_cell(grid.cell_count());
  std::vector<double> sum, weight;
  if (masked || images.size() > 1 || images[0].weight != 1 || images[0].background_radiance != 0)
    sum.assign(grid.cell_count(), 0.0);
  // One camera of weight 1 without background (the usual PIV frame): A^T I / W in place, no copies.
  if (!masked && images.size() == 1 && images[0].weight == 1 && images[0].background_radiance == 0) {
    const CorrectionOperator& op = *images[0].op;
    apply_transpose(op, images[0].image, per_cell.data());
    for (std::size_t c = 0; c < per_cell.size(); ++c)
      per_cell[c] = states[c] == CellState::valid && op.cell_weight[c] > 0 ? per_cell[c] / op.cell_weight[c] : 0.0f;
    return per_cell;
  }
  for (const CameraImage& im : images) {
    const std::vector<float> b = data_term(im);  // sqrt(w) (I - bg)
    apply_transpose(*im.op, b.data(), per_cell.data());
    const double sw = std::sqrt(im.weight);
    for (std::size_t c = 0; c < per_cell.size(); ++c) sum[c] += sw * per_cell[c];
  }
  weight = data_weight(images, finite);
  std::vector<float> l(grid.cell_count(), 0.0f);
  for (std::size_t c = 0; c < l.size(); ++c)
    if (states[c] == CellState::valid && weight[c] > 0) l[c] = static_cast<float>(sum[c] / weight[c]);
    else if (states[c] == CellState::valid && masked) l[c] = kNoData;  // seen by left-out pixels only
  return l;
}

std::vector<float> least_squares(const std::vector<CameraImage>& images, const std::vector<CellState>& states,
                                 const std::vector<float>& start, const LeastSquaresOptions& options,
                                 LeastSquaresReport* report) {
  const SheetGrid& grid = common_grid(images, states);
  if (start.size() != grid.cell_count()) throw std::invalid_argument("least_squares: start of another grid");
  if (!(options.smoothness >= 0) || !std::isfinite(options.smoothness) || options.max_iterations < 0 ||
      !(options.tolerance >= 0))
    throw std::invalid_argument("least_squares: bad options");

  // lambda relative to the mean squared column norm of the data term over valid cells.
  std::vector<double> column(grid.cell_count(), 0.0);
  for (const CameraImage& im : images)
    for (std::size_t c = 0; c < column.size(); ++c) {
      double s = 0;
      for (std::uint32_t i = im.op->cell_offsets[c]; i < im.op->cell_offsets[c + 1]; ++i)
        s += double(im.op->value_by_cell[i]) * im.op->value_by_cell[i];
      column[c] += im.weight * s;
    }
  double mean_column = 0;
  std::size_t valid = 0;
  for (std::size_t c = 0; c < column.size(); ++c)
    if (states[c] == CellState::valid) {
      mean_column += column[c];
      ++valid;
    }
  mean_column = valid ? mean_column / valid : 0.0;
  const std::vector<std::vector<float>> finite = finite_pixels(images);
  std::size_t finite_count = 0, masked_count = 0;
  for (std::size_t cam = 0; cam < images.size(); ++cam) {
    const std::size_t n = images[cam].op->pixel_count(), bad = finite[cam].empty() ? 0 : count_non_finite(images[cam].image, n);
    masked_count += bad;
    finite_count += n - bad;
  }
  if (finite_count == 0) throw std::invalid_argument("least_squares: no finite pixel in any camera's image");
  const StackedOperator k(images, states, options.smoothness * mean_column, finite);

  std::vector<float> x(start);
  for (std::size_t c = 0; c < x.size(); ++c)
    if (states[c] != CellState::valid || !std::isfinite(x[c])) x[c] = 0;
  // r = b - K x
  StackedOperator::Residual r = k.zeros(), q = k.zeros();
  k.apply(x, q);
  for (std::size_t cam = 0; cam < images.size(); ++cam) {
    r.camera[cam] = data_term(images[cam]);
    for (std::size_t p = 0; p < r.camera[cam].size(); ++p) r.camera[cam][p] -= q.camera[cam][p];
  }
  for (std::size_t i = 0; i < r.gradient.size(); ++i) r.gradient[i] = -q.gradient[i];

  std::vector<float> s(x.size()), p(x.size());
  k.apply_adjoint(r, s);
  p = s;
  double gamma = squared_norm(s);
  const double gamma0 = gamma;
  if (!std::isfinite(gamma0) || !std::isfinite(squared_norm(r)))
    throw std::invalid_argument("least_squares: the data overflow single precision (pixel values near 1e38?)");
  LeastSquaresReport rep;
  rep.masked_pixels = masked_count;
  rep.residual_start = camera_rms(r);
  rep.converged = gamma0 == 0;
  int it = 0;
  for (; it < options.max_iterations && !rep.converged; ++it) {
    k.apply(p, q);
    const double delta = squared_norm(q);
    if (!(delta > 0)) break;
    const double alpha = gamma / delta;
    for (std::size_t c = 0; c < x.size(); ++c) x[c] += static_cast<float>(alpha * p[c]);
    axpy(r, -alpha, q);
    k.apply_adjoint(r, s);
    const double gamma_new = squared_norm(s);
    rep.gradient_ratio = std::sqrt(gamma_new / gamma0);
    if (rep.gradient_ratio < options.tolerance) rep.converged = true;
    const double beta = gamma_new / gamma;
    for (std::size_t c = 0; c < p.size(); ++c) p[c] = static_cast<float>(s[c] + beta * p[c]);
    gamma = gamma_new;
  }
  rep.iterations = it;
  rep.residual_end = camera_rms(r);
  if (any_masked(finite)) {  // a cell only left-out pixels see has no data: not the regulariser's guess
    const std::vector<double> weight = data_weight(images, finite);
    for (std::size_t c = 0; c < x.size(); ++c)
      if (states[c] == CellState::valid && !(weight[c] > 0)) x[c] = kNoData;
  }
  if (report) *report = rep;
  return x;
}

}  // namespace glasspiv
