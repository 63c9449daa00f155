#include "piv/cross_correlation.h"

#include <cmath>
#include <stdexcept>
#include <string>

#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

namespace glasspiv {
namespace {

bool is_power_of_two(int n) { return n > 0 && (n & (n - 1)) == 0; }

// One radix-2 butterfly on whole rows. Decimation in frequency (forward):
// a' = a + b, b' = (a - b) w. Decimation in time (inverse): t = b w,
// a' = a + t, b' = a - t. w = 1 skips the product (exact either way).
inline void butterfly_dif(float* __restrict ar, float* __restrict ai, float* __restrict br, float* __restrict bi,
                          float wr, float wi, bool unit, int n) {
  if (unit) {
    for (int x = 0; x < n; ++x) {
      const float tr = ar[x] - br[x], ti = ai[x] - bi[x];
      ar[x] += br[x];
      ai[x] += bi[x];
      br[x] = tr;
      bi[x] = ti;
    }
    return;
  }
  for (int x = 0; x < n; ++x) {
    const float tr = ar[x] - br[x], ti = ai[x] - bi[x];
    ar[x] += br[x];
    ai[x] += bi[x];
    br[x] = tr * wr - ti * wi;
    bi[x] = tr * wi + ti * wr;
  }
}

inline void butterfly_dit(float* __restrict ar, float* __restrict ai, float* __restrict br, float* __restrict bi,
                          float wr, float wi, bool unit, int n) {
  if (unit) {
    for (int x = 0; x < n; ++x) {
      const float tr = br[x], ti = bi[x];
      br[x] = ar[x] - tr;
      bi[x] = ai[x] - ti;
      ar[x] += tr;
      ai[x] += ti;
    }
    return;
  }
  for (int x = 0; x < n; ++x) {
    const float tr = br[x] * wr - bi[x] * wi, ti = br[x] * wi + bi[x] * wr;
    br[x] = ar[x] - tr;
    bi[x] = ai[x] - ti;
    ar[x] += tr;
    ai[x] += ti;
  }
}


// Builds with AVX2 where the compiler and the loader support function clones
// (x86-64 Linux): the passes are lane-wise float adds and products without
// FMA, so the SSE2 and AVX2 clones give bit-identical results.
#if defined(__x86_64__) && defined(__linux__) && (defined(__GNUC__) || defined(__clang__)) && \
    !defined(__SANITIZE_ADDRESS__)
#define GLASSPIV_FFT_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define GLASSPIV_FFT_CLONES
#endif

// Radix-2 passes along columns of an n x n split-complex plane (every
// butterfly on whole rows); twiddle k = e^{-2 pi i k / n}, k < n / 2.
// Forward (e^{-i}): decimation in frequency, natural in, bit-reversed out.
GLASSPIV_FFT_CLONES
void forward_columns(float* re, float* im, const float* twiddle_re, const float* twiddle_im, int n) {
  for (int h = n / 2; h >= 1; h /= 2) {
    const int step = n / (2 * h);
    for (int base = 0; base < n; base += 2 * h)
      for (int j = 0; j < h; ++j) {
        const std::ptrdiff_t ra = static_cast<std::ptrdiff_t>(base + j) * n, rb = ra + static_cast<std::ptrdiff_t>(h) * n;
        butterfly_dif(re + ra, im + ra, re + rb, im + rb, twiddle_re[j * step], twiddle_im[j * step], j == 0, n);
      }
  }
}

// Inverse (e^{+i}, unscaled): decimation in time, bit-reversed in, natural out.
GLASSPIV_FFT_CLONES
void inverse_columns(float* re, float* im, const float* twiddle_re, const float* twiddle_im, int n) {
  for (int h = 1; h < n; h *= 2) {
    const int step = n / (2 * h);
    for (int base = 0; base < n; base += 2 * h)
      for (int j = 0; j < h; ++j) {
        const std::ptrdiff_t ra = static_cast<std::ptrdiff_t>(base + j) * n, rb = ra + static_cast<std::ptrdiff_t>(h) * n;
        // The inverse twiddle is the conjugate of the forward one.
        butterfly_dit(re + ra, im + ra, re + rb, im + rb, twiddle_re[j * step], -twiddle_im[j * step], j == 0, n);
      }
  }
}

// Sums of a row in kLanes interleaved float partial sums, added in a fixed
// order: vectorisable without reassociating, the same on every machine.
constexpr int kLanes = 8;
inline float fixed_order_sum(const float (&lane)[kLanes]) {
  return ((lane[0] + lane[1]) + (lane[2] + lane[3])) + ((lane[4] + lane[5]) + (lane[6] + lane[7]));
}

inline float row_sum(const float* s, int n) {
  float lane[kLanes] = {};
  int x = 0;
  for (; x + kLanes <= n; x += kLanes)
    for (int k = 0; k < kLanes; ++k) lane[k] += s[x + k];
  for (int k = 0; x < n; ++x, ++k) lane[k] += s[x];
  return fixed_order_sum(lane);
}

inline float row_sum_of_squares(const float* s, int n) {
  float lane[kLanes] = {};
  int x = 0;
  for (; x + kLanes <= n; x += kLanes)
    for (int k = 0; k < kLanes; ++k) lane[k] += s[x + k] * s[x + k];
  for (int k = 0; x < n; ++x, ++k) lane[k] += s[x] * s[x];
  return fixed_order_sum(lane);
}

// Of the usable pixels only; their count added to count.
inline float row_sum_valid(const float* s, const std::uint8_t* v, int n, int& count) {
  float lane[kLanes] = {};
  int x = 0;
  for (; x + kLanes <= n; x += kLanes)
    for (int k = 0; k < kLanes; ++k) lane[k] += v[x + k] ? s[x + k] : 0.0f;
  for (int k = 0; x < n; ++x, ++k) lane[k] += v[x] ? s[x] : 0.0f;
  for (x = 0; x < n; ++x) count += v[x] != 0;
  return fixed_order_sum(lane);
}

// dst[dst_row[r]][c] = src[src_row[c]][r] on n x n planes, both parts; n a
// multiple of 4. 4 x 4 blocks (SSE where there is SSE).
void transpose_mapped(const float* src_re, const float* src_im, float* dst_re, float* dst_im, const int* src_row,
                      const int* dst_row, int n) {
  for (int r0 = 0; r0 < n; r0 += 4)
    for (int c0 = 0; c0 < n; c0 += 4) {
      const float* sr[4];
      const float* si[4];
      float* dr[4];
      float* di[4];
      for (int i = 0; i < 4; ++i) {
        const std::ptrdiff_t s = static_cast<std::ptrdiff_t>(src_row[c0 + i]) * n + r0;
        const std::ptrdiff_t d = static_cast<std::ptrdiff_t>(dst_row[r0 + i]) * n + c0;
        sr[i] = src_re + s;
        si[i] = src_im + s;
        dr[i] = dst_re + d;
        di[i] = dst_im + d;
      }
#if defined(__SSE2__)
      auto block = [](const float* const* src, float* const* dst) {
        __m128 q0 = _mm_loadu_ps(src[0]), q1 = _mm_loadu_ps(src[1]), q2 = _mm_loadu_ps(src[2]), q3 = _mm_loadu_ps(src[3]);
        _MM_TRANSPOSE4_PS(q0, q1, q2, q3);
        _mm_storeu_ps(dst[0], q0);
        _mm_storeu_ps(dst[1], q1);
        _mm_storeu_ps(dst[2], q2);
        _mm_storeu_ps(dst[3], q3);
      };
      block(sr, dr);
      block(si, di);
#else
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
          dr[j][i] = sr[i][j];
          di[j][i] = si[i][j];
        }
#endif
    }
}

}  // namespace

WindowCorrelator::WindowCorrelator(int window_px, CorrelationFft fft) : window_px_(window_px) {
  if (window_px < 4) throw std::invalid_argument("WindowCorrelator: window_px must be at least 4");
  plane_px_ = cv::getOptimalDFTSize(window_px);
  const int n = plane_px_;
  if (fft == CorrelationFft::radix2 && !is_power_of_two(n))
    throw std::invalid_argument("WindowCorrelator: the radix-2 FFT needs a power-of-two plane, not " + std::to_string(n));
  fft_ = fft == CorrelationFft::automatic ? (is_power_of_two(n) ? CorrelationFft::radix2 : CorrelationFft::opencv) : fft;
  plane_ = cv::Mat::zeros(n, n, CV_32F);
  if (fft_ == CorrelationFft::opencv) {
    // Real input -> CCS-packed spectrum, and back to real output.
    forward_ = cv::hal::DFT2D::create(n, n, CV_32F, 1, 1, 0);
    inverse_ = cv::hal::DFT2D::create(n, n, CV_32F, 1, 1, cv::DFT_INVERSE | cv::DFT_REAL_OUTPUT);
    for (cv::Mat* m : {&a_, &b_, &fa_, &fb_, &product_}) *m = cv::Mat::zeros(n, n, CV_32F);
    return;
  }
  const double pi = std::acos(-1.0);
  for (int k = 0; k < n / 2; ++k) {
    twiddle_re_.push_back(static_cast<float>(std::cos(2 * pi * k / n)));
    twiddle_im_.push_back(static_cast<float>(-std::sin(2 * pi * k / n)));
  }
  int bits = 0;
  while ((1 << bits) < n) ++bits;
  for (int k = 0; k < n; ++k) {
    int r = 0;
    for (int b = 0; b < bits; ++b) r |= ((k >> b) & 1) << (bits - 1 - b);
    bit_reverse_.push_back(r);
    identity_.push_back(k);
  }
  for (std::vector<float>* v : {&re_, &im_, &t_re_, &t_im_}) v->assign(static_cast<std::size_t>(n) * n, 0.0f);
}

double WindowCorrelator::load(const float* src, int stride, const std::uint8_t* valid, float* dst) const {
  const int n = window_px_;
  double sum = 0;
  int count = 0;
  // float per row (in fixed-order lanes), double across rows: exact enough, and vectorised
  for (int y = 0; y < n; ++y) {
    const float* s = src + static_cast<std::ptrdiff_t>(y) * stride;
    if (valid) {
      sum += row_sum_valid(s, valid + static_cast<std::ptrdiff_t>(y) * stride, n, count);
    } else {
      sum += row_sum(s, n);
      count += n;
    }
  }
  if (count < 8) return -1;
  const float mean = static_cast<float>(sum / count);
  double energy = 0;
  for (int y = 0; y < n; ++y) {
    const float* s = src + static_cast<std::ptrdiff_t>(y) * stride;
    float* d = dst + static_cast<std::ptrdiff_t>(y) * plane_px_;
    if (valid) {
      const std::uint8_t* v = valid + static_cast<std::ptrdiff_t>(y) * stride;
      for (int x = 0; x < n; ++x) d[x] = v[x] ? s[x] - mean : 0.0f;
    } else {
      for (int x = 0; x < n; ++x) d[x] = s[x] - mean;
    }
    energy += row_sum_of_squares(d, n);
  }
  // A uniform window subtracts to exact zeros: no correlation is defined.
  return energy > 1e-20 * count ? energy : -1;
}

bool WindowCorrelator::correlate(const float* a, int stride_a, const std::uint8_t* valid_a, const float* b,
                                 int stride_b, const std::uint8_t* valid_b) {
  const bool radix2 = fft_ == CorrelationFft::radix2;
  float* da = radix2 ? re_.data() : a_.ptr<float>();
  float* db = radix2 ? im_.data() : b_.ptr<float>();
  const double ea = load(a, stride_a, valid_a, da), eb = ea > 0 ? load(b, stride_b, valid_b, db) : -1;
  if (!(ea > 0 && eb > 0)) {
    plane_.setTo(0);
    return false;
  }
  // The unscaled inverse DFT carries a factor plane_px^2.
  const double scale = 1.0 / (static_cast<double>(plane_px_) * plane_px_ * std::sqrt(ea * eb));
  if (radix2)
    correlate_radix2(scale);
  else
    correlate_opencv(scale);
  return true;
}

void WindowCorrelator::correlate_opencv(double scale) {
  forward_->apply(a_.data, a_.step, fa_.data, fa_.step);
  forward_->apply(b_.data, b_.step, fb_.data, fb_.step);
  // conj(FA) FB transforms back to sum_x a(x) b(x + d) (the correlation theorem).
  cv::mulSpectrums(fb_, fa_, product_, 0, /*conjB=*/true);
  inverse_->apply(product_.data, product_.step, plane_.data, plane_.step);
  plane_ *= scale;
}

void WindowCorrelator::correlate_radix2(double scale) {
  const int n = plane_px_;
  // z = a' + i b' (loaded into re_, im_), Z = FFT2(z). Along y: row r of the
  // result holds ky = bit_reverse(r); the transpose restores natural ky along
  // rows and makes x the row index; along x: row r holds kx = bit_reverse(r),
  // column c holds ky = c.
  forward_columns(re_.data(), im_.data(), twiddle_re_.data(), twiddle_im_.data(), n);
  transpose_mapped(re_.data(), im_.data(), t_re_.data(), t_im_.data(), bit_reverse_.data(), identity_.data(), n);
  forward_columns(t_re_.data(), t_im_.data(), twiddle_re_.data(), twiddle_im_.data(), n);
  // P(k) = conj(FA(k)) FB(k) = Im(Z(-k) Z(k)) / 2 - i (|Z(k)|^2 - |Z(-k)|^2) / 4,
  // scaled, into re_ / im_ in the same layout. P is exactly Hermitian
  // (P(-k) is computed from the same products), so its inverse is real.
  const float half = static_cast<float>(scale / 2), quarter = static_cast<float>(scale / 4);
  for (int r = 0; r < n; ++r) {
    const int kx = bit_reverse_[r], partner = bit_reverse_[(n - kx) & (n - 1)];
    const float* zr = t_re_.data() + static_cast<std::ptrdiff_t>(r) * n;
    const float* zi = t_im_.data() + static_cast<std::ptrdiff_t>(r) * n;
    const float* mr = t_re_.data() + static_cast<std::ptrdiff_t>(partner) * n;
    const float* mi = t_im_.data() + static_cast<std::ptrdiff_t>(partner) * n;
    float* pr = re_.data() + static_cast<std::ptrdiff_t>(r) * n;
    float* pi = im_.data() + static_cast<std::ptrdiff_t>(r) * n;
    // Column c pairs with (n - c) mod n: column 0 with itself, the rest in reverse.
    auto product = [&](int c, float mre, float mim) {
      pr[c] = half * (mre * zi[c] + mim * zr[c]);
      pi[c] = quarter * ((mre * mre + mim * mim) - (zr[c] * zr[c] + zi[c] * zi[c]));
    };
    product(0, mr[0], mi[0]);
    const float* mr_end = mr + n;
    const float* mi_end = mi + n;
    for (int c = 1; c < n; ++c) product(c, mr_end[-c], mi_end[-c]);
  }
  // Inverse along x: bit-reversed kx rows in, lag dx rows out (column ky);
  // the transpose puts ky back along rows, bit-reversed as the inverse along
  // y wants it; its real part, row dy and column dx, lands in the plane.
  inverse_columns(re_.data(), im_.data(), twiddle_re_.data(), twiddle_im_.data(), n);
  float* out = plane_.ptr<float>();
  transpose_mapped(re_.data(), im_.data(), out, t_im_.data(), identity_.data(), bit_reverse_.data(), n);
  inverse_columns(out, t_im_.data(), twiddle_re_.data(), twiddle_im_.data(), n);
}

float WindowCorrelator::at_lag(int dx_px, int dy_px) const {
  const int m = plane_px_;
  const int c = ((dx_px % m) + m) % m, r = ((dy_px % m) + m) % m;
  return plane_.at<float>(r, c);
}

}  // namespace glasspiv
