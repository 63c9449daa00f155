#include "piv/mask_overlap.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace glasspiv {

MaskOverlap::MaskOverlap(int window_px, int plane_px) : window_px_(window_px), plane_px_(plane_px) {
  if (window_px < 1 || plane_px < window_px) throw std::invalid_argument("MaskOverlap: plane smaller than the window");
  mask_a_ = cv::Mat::zeros(plane_px, plane_px, CV_32F);
  mask_b_ = cv::Mat::zeros(plane_px, plane_px, CV_32F);
}

bool MaskOverlap::load(const std::uint8_t* valid, int stride, cv::Mat& dst) const {
  dst.setTo(0.0f);
  bool partial = false;
  for (int y = 0; y < window_px_; ++y) {
    float* d = dst.ptr<float>(y);
    for (int x = 0; x < window_px_; ++x) {
      const bool ok = valid == nullptr || valid[static_cast<std::ptrdiff_t>(y) * stride + x] != 0;
      d[x] = ok ? 1.0f : 0.0f;
      partial |= !ok;
    }
  }
  return partial;
}

bool MaskOverlap::normalise(float* plane, const std::uint8_t* valid_a, int stride_a, const std::uint8_t* valid_b,
                            int stride_b, double min_overlap) {
  if (valid_a == nullptr && valid_b == nullptr) return false;
  const bool partial_a = load(valid_a, stride_a, mask_a_);
  const bool partial_b = load(valid_b, stride_b, mask_b_);
  if (!partial_a && !partial_b) return false;

  // O(s) = sum_x m_a(x) m_b(x + s) = IDFT(conj(M_a) M_b), circular as R is.
  cv::dft(mask_a_, spectrum_a_, cv::DFT_COMPLEX_OUTPUT);
  cv::dft(mask_b_, spectrum_b_, cv::DFT_COMPLEX_OUTPUT);
  cv::mulSpectrums(spectrum_b_, spectrum_a_, spectrum_b_, 0, /*conjB=*/true);
  cv::dft(spectrum_b_, overlap_, cv::DFT_INVERSE | cv::DFT_SCALE | cv::DFT_REAL_OUTPUT);

  // Pixel-pair counts are integers: rounding removes the DFT's noise.
  const int n = plane_px_ * plane_px_;
  const float* o = overlap_.ptr<float>(0);
  const double at_zero = std::round(o[0]);
  if (at_zero < 1) return false;  // the correlator defines no plane for such windows
  const double least = std::max(1.0, min_overlap * at_zero);
  // Excluded lags are marked NaN (no plane value is), then get the lowest kept value.
  float lowest = std::numeric_limits<float>::max();
  for (int i = 0; i < n; ++i) {
    const double pairs = std::round(o[i]);
    plane[i] = pairs < least ? NAN : static_cast<float>(plane[i] * (at_zero / pairs));
    if (!std::isnan(plane[i])) lowest = std::min(lowest, plane[i]);
  }
  if (lowest == std::numeric_limits<float>::max()) lowest = 0.0f;
  for (int i = 0; i < n; ++i)
    if (std::isnan(plane[i])) plane[i] = lowest;
  return true;
}

}  // namespace glasspiv
