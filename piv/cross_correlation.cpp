#include "piv/cross_correlation.h"

#include <cmath>
#include <stdexcept>

namespace glasspiv {

WindowCorrelator::WindowCorrelator(int window_px) : window_px_(window_px) {
  if (window_px < 4) throw std::invalid_argument("WindowCorrelator: window_px must be at least 4");
  plane_px_ = cv::getOptimalDFTSize(window_px);
  // Real input -> CCS-packed spectrum, and back to real output.
  forward_ = cv::hal::DFT2D::create(plane_px_, plane_px_, CV_32F, 1, 1, 0);
  inverse_ = cv::hal::DFT2D::create(plane_px_, plane_px_, CV_32F, 1, 1, cv::DFT_INVERSE | cv::DFT_REAL_OUTPUT);
  for (cv::Mat* m : {&a_, &b_, &fa_, &fb_, &product_, &plane_}) *m = cv::Mat::zeros(plane_px_, plane_px_, CV_32F);
}

double WindowCorrelator::load(const float* src, int stride, const std::uint8_t* valid, cv::Mat& dst) const {
  const int n = window_px_;
  double sum = 0;
  int count = 0;
  for (int y = 0; y < n; ++y) {
    const float* s = src + static_cast<std::ptrdiff_t>(y) * stride;
    float row = 0;  // float per row, double across rows: exact enough, and vectorised
    if (valid) {
      const std::uint8_t* v = valid + static_cast<std::ptrdiff_t>(y) * stride;
      for (int x = 0; x < n; ++x) {
        row += v[x] ? s[x] : 0.0f;
        count += v[x] != 0;
      }
    } else {
      for (int x = 0; x < n; ++x) row += s[x];
      count += n;
    }
    sum += row;
  }
  if (count < 8) return -1;
  const float mean = static_cast<float>(sum / count);
  double energy = 0;
  for (int y = 0; y < n; ++y) {
    const float* s = src + static_cast<std::ptrdiff_t>(y) * stride;
    float* d = dst.ptr<float>(y);
    float row = 0;
    if (valid) {
      const std::uint8_t* v = valid + static_cast<std::ptrdiff_t>(y) * stride;
      for (int x = 0; x < n; ++x) d[x] = v[x] ? s[x] - mean : 0.0f;
    } else {
      for (int x = 0; x < n; ++x) d[x] = s[x] - mean;
    }
    for (int x = 0; x < n; ++x) row += d[x] * d[x];
    energy += row;
  }
  // A uniform window subtracts to exact zeros: no correlation is defined.
  return energy > 1e-20 * count ? energy : -1;
}

bool WindowCorrelator::correlate(const float* a, int stride_a, const std::uint8_t* valid_a, const float* b,
                                 int stride_b, const std::uint8_t* valid_b) {
  const double ea = load(a, stride_a, valid_a, a_), eb = ea > 0 ? load(b, stride_b, valid_b, b_) : -1;
  if (!(ea > 0 && eb > 0)) {
    plane_.setTo(0);
    return false;
  }
  forward_->apply(a_.data, a_.step, fa_.data, fa_.step);
  forward_->apply(b_.data, b_.step, fb_.data, fb_.step);
  // conj(FA) FB transforms back to sum_x a(x) b(x + d) (the correlation theorem).
  cv::mulSpectrums(fb_, fa_, product_, 0, /*conjB=*/true);
  inverse_->apply(product_.data, product_.step, plane_.data, plane_.step);
  // The unscaled inverse DFT carries a factor plane_px^2.
  const double scale = 1.0 / (static_cast<double>(plane_px_) * plane_px_ * std::sqrt(ea * eb));
  plane_ *= scale;
  return true;
}

float WindowCorrelator::at_lag(int dx_px, int dy_px) const {
  const int m = plane_px_;
  const int c = ((dx_px % m) + m) % m, r = ((dy_px % m) + m) % m;
  return plane_.at<float>(r, c);
}

}  // namespace glasspiv
