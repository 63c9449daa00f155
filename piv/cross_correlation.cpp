#include "piv/cross_correlation.h"

#include <cmath>
#include <complex>
#include <stdexcept>

namespace glasspiv {

BatchCorrelator::BatchCorrelator(int window_px, int capacity) : window_px_(window_px), capacity_(capacity) {
  if (window_px < 4) throw std::invalid_argument("BatchCorrelator: window_px must be at least 4");
  if (capacity < 1) throw std::invalid_argument("BatchCorrelator: capacity must be at least 1");
  const int n = plane_px_ = cv::getOptimalDFTSize(window_px);
  half_px_ = n / 2 + 1;
  scale_.resize(static_cast<std::size_t>(capacity));
  plans_.resize(static_cast<std::size_t>(capacity));
  // Zero once: load() writes only the window, so the padding stays zero.
  windows_ = cv::Mat::zeros(2 * capacity * n, n, CV_32F);
  row_spectra_.create(2 * capacity * n, n, CV_32F);
  columns_.create(2 * capacity * half_px_, n, CV_32FC2);
  spectra_.create(2 * capacity * half_px_, n, CV_32FC2);
  products_.create(capacity * half_px_, n, CV_32FC2);
  inverted_.create(capacity * half_px_, n, CV_32FC2);
  packed_.create(capacity * n, n, CV_32F);
  planes_.create(capacity * n, n, CV_32F);
}

const BatchCorrelator::Plans& BatchCorrelator::plans_for(int pairs) {
  Plans& p = plans_[static_cast<std::size_t>(pairs - 1)];
  if (!p.rows_forward) {
    const int n = plane_px_, h = half_px_;
    using cv::hal::DFT2D;
    // Real rows -> CCS-packed rows; complex rows both ways; CCS rows -> real.
    p.rows_forward = DFT2D::create(n, 2 * pairs * n, CV_32F, 1, 1, cv::DFT_ROWS);
    p.columns_forward = DFT2D::create(n, 2 * pairs * h, CV_32F, 2, 2, cv::DFT_ROWS);
    p.columns_inverse = DFT2D::create(n, pairs * h, CV_32F, 2, 2, cv::DFT_ROWS | cv::DFT_INVERSE);
    p.rows_inverse = DFT2D::create(n, pairs * n, CV_32F, 1, 1, cv::DFT_ROWS | cv::DFT_INVERSE | cv::DFT_REAL_OUTPUT);
  }
  return p;
}

namespace {

// Sum of p[0 .. n) in eight float lanes (vectorised; the lanes' order is fixed).
float lane_sum(const float* p, int n) {
  float lane[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  int i = 0;
  for (; i + 8 <= n; i += 8)
    for (int j = 0; j < 8; ++j) lane[j] += p[i + j];
  float sum = ((lane[0] + lane[4]) + (lane[1] + lane[5])) + ((lane[2] + lane[6]) + (lane[3] + lane[7]));
  for (; i < n; ++i) sum += p[i];
  return sum;
}

// d[x] = s[x] - mean; returns the sum of d[x]^2, in eight lanes.
float subtract_mean(const float* s, int n, float mean, float* d) {
  float lane[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  int i = 0;
  for (; i + 8 <= n; i += 8)
    for (int j = 0; j < 8; ++j) {
      const float v = s[i + j] - mean;
      d[i + j] = v;
      lane[j] += v * v;
    }
  float sum = ((lane[0] + lane[4]) + (lane[1] + lane[5])) + ((lane[2] + lane[6]) + (lane[3] + lane[7]));
  for (; i < n; ++i) {
    d[i] = s[i] - mean;
    sum += d[i] * d[i];
  }
  return sum;
}

}  // namespace

double BatchCorrelator::load(const float* src, int stride, const std::uint8_t* valid, float* dst) const {
  const int n = window_px_, m = plane_px_;
  // Float per row, double across rows: exact enough.
  double sum = 0;
  int count = 0;
  for (int y = 0; y < n; ++y) {
    const float* s = src + static_cast<std::ptrdiff_t>(y) * stride;
    if (valid) {
      const std::uint8_t* v = valid + static_cast<std::ptrdiff_t>(y) * stride;
      float row = 0;
      for (int x = 0; x < n; ++x) {
        row += v[x] ? s[x] : 0.0f;
        count += v[x] != 0;
      }
      sum += row;
    } else {
      sum += lane_sum(s, n);
      count += n;
    }
  }
  if (count < 8) return -1;
  const float mean = static_cast<float>(sum / count);
  double energy = 0;
  for (int y = 0; y < n; ++y) {
    const float* s = src + static_cast<std::ptrdiff_t>(y) * stride;
    float* d = dst + static_cast<std::ptrdiff_t>(y) * m;
    if (valid) {
      const std::uint8_t* v = valid + static_cast<std::ptrdiff_t>(y) * stride;
      float row = 0;
      for (int x = 0; x < n; ++x) {
        d[x] = v[x] ? s[x] - mean : 0.0f;
        row += d[x] * d[x];
      }
      energy += row;
    } else {
      energy += subtract_mean(s, n, mean, d);
    }
  }
  // A uniform window subtracts to exact zeros: no correlation is defined.
  return energy > 1e-20 * count ? energy : -1;
}

int BatchCorrelator::add(const float* a, int stride_a, const std::uint8_t* valid_a, const float* b, int stride_b,
                         const std::uint8_t* valid_b) {
  if (full()) throw std::logic_error("BatchCorrelator::add: the batch is full");
  const int n = plane_px_, slot = size_;
  const double ea = load(a, stride_a, valid_a, windows_.ptr<float>(2 * slot * n));
  const double eb = ea > 0 ? load(b, stride_b, valid_b, windows_.ptr<float>((2 * slot + 1) * n)) : -1;
  if (!(ea > 0 && eb > 0)) return -1;
  // The unscaled forward and inverse DFTs carry a factor plane_px^2.
  scale_[static_cast<std::size_t>(slot)] = 1.0 / (static_cast<double>(n) * n * std::sqrt(ea * eb));
  return size_++;
}

void BatchCorrelator::correlate() {
  if (size_ == 0) return;
  const int n = plane_px_, h = half_px_, k = size_;
  const bool even = n % 2 == 0;
  const Plans& p = plans_for(k);
  using C = std::complex<float>;
  p.rows_forward->apply(windows_.data, windows_.step, row_spectra_.data, row_spectra_.step);
  // CCS row y of plane q -> column y of that plane's half_px rows: complex
  // frequency kx of row y at (q h + kx, y). CCS: Re0, Re1, Im1, ..., and Re(n/2) last for even n.
  for (int q = 0; q < 2 * k; ++q)
    for (int y = 0; y < n; ++y) {
      const float* s = row_spectra_.ptr<float>(q * n + y);
      C* col = columns_.ptr<C>(q * h) + y;
      const std::ptrdiff_t step = n;  // one row of columns_ in complex elements
      col[0] = C(s[0], 0.0f);
      for (int kx = 1; kx < (n + 1) / 2; ++kx) col[kx * step] = C(s[2 * kx - 1], s[2 * kx]);
      if (even) col[(n / 2) * step] = C(s[n - 1], 0.0f);
    }
  p.columns_forward->apply(columns_.data, columns_.step, spectra_.data, spectra_.step);
  // conj(FA) FB transforms back to sum_x a(x) b(x + d) (the correlation theorem).
  for (int s = 0; s < k; ++s) {
    const float scale = static_cast<float>(scale_[static_cast<std::size_t>(s)]);
    const float* fa = spectra_.ptr<float>(2 * s * h);
    const float* fb = spectra_.ptr<float>((2 * s + 1) * h);
    float* out = products_.ptr<float>(s * h);
    for (int i = 0; i < 2 * h * n; i += 2) {
      const float ar = fa[i], ai = fa[i + 1], br = fb[i], bi = fb[i + 1];
      out[i] = (ar * br + ai * bi) * scale;
      out[i + 1] = (ar * bi - ai * br) * scale;
    }
  }
  p.columns_inverse->apply(products_.data, products_.step, inverted_.data, inverted_.step);
  // Back into CCS rows: row y of the plane holds frequencies kx of G(kx, y).
  for (int s = 0; s < k; ++s)
    for (int y = 0; y < n; ++y) {
      const C* col = inverted_.ptr<C>(s * h) + y;
      const std::ptrdiff_t step = n;
      float* d = packed_.ptr<float>(s * n + y);
      d[0] = col[0].real();
      for (int kx = 1; kx < (n + 1) / 2; ++kx) {
        const C g = col[kx * step];
        d[2 * kx - 1] = g.real();
        d[2 * kx] = g.imag();
      }
      if (even) d[n - 1] = col[(n / 2) * step].real();
    }
  p.rows_inverse->apply(packed_.data, packed_.step, planes_.data, planes_.step);
}

bool WindowCorrelator::correlate(const float* a, int stride_a, const std::uint8_t* valid_a, const float* b,
                                 int stride_b, const std::uint8_t* valid_b) {
  batch_.clear();
  ok_ = batch_.add(a, stride_a, valid_a, b, stride_b, valid_b) >= 0;
  if (ok_) batch_.correlate();
  return ok_;
}

float WindowCorrelator::at_lag(int dx_px, int dy_px) const {
  const int m = plane_px();
  const int c = ((dx_px % m) + m) % m, r = ((dy_px % m) + m) % m;
  return plane()[r * m + c];
}

}  // namespace glasspiv
