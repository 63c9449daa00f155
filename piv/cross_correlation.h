#pragma once
// FFT cross-correlation of one pair of interrogation windows (the standard
// digital PIV estimator, Willert & Gharib 1991; Raffel et al., "Particle Image
// Velocimetry", 3rd ed., sec. 5.3).
//
// Both windows are mean-subtracted over their valid pixels (invalid ones, e.g.
// masked or deformed from outside the image, count as the mean, i.e. zero),
// then correlated circularly on a plane of plane_px = cv::getOptimalDFTSize
// (window_px) (= window_px for 16, 32, 64 px) and normalised by
// sqrt(sum a'^2 * sum b'^2), so that the plane holds correlation coefficients:
//
//   R(dx, dy) = sum_{x,y} a'(x, y) b'(x + dx, y + dy) / sqrt(sum a'^2 sum b'^2)
//
// Two FFT paths, equal to float round-off (the tests hold both to the direct
// sum):
//  - radix2 (the default when plane_px is a power of two): the two real
//    windows packed as one complex image z = a' + i b', one complex 2-D FFT
//    Z, then conj(FA) FB = Im(Z(-k) Z(k)) / 2 - i (|Z(k)|^2 - |Z(-k)|^2) / 4
//    (FA = (Z(k) + conj Z(-k)) / 2, FB = (Z(k) - conj Z(-k)) / 2i), and one
//    complex inverse FFT whose real part is R. Radix-2 passes run along
//    columns, so every butterfly works on whole rows (vectorised), with a
//    transpose between the two axes; forward passes are decimation in
//    frequency (bit-reversed output), inverse ones decimation in time
//    (bit-reversed input), so no separate reordering pass. Float, twiddles
//    rounded from double. Plans (twiddles, index tables, buffers) are made
//    once per correlator; no allocation per window.
//  - opencv (any plane_px): OpenCV's real DFT (CCS packing), mulSpectrums
//    with conjB and its real inverse, plans made once per window size.
//
// Sign: if frame B holds frame A's pattern moved by (+s_x, +s_y) px, R peaks at
// lag (dx, dy) = (s_x, s_y): the lag of the peak is the displacement of B
// relative to A, dx along +x (columns), dy along +y (rows). The plane is stored
// unshifted: row r, column c hold lag (wrap(c), wrap(r)) with
// wrap(k) = k for k < plane_px / 2, k - plane_px otherwise, so lags run over
// [-plane_px / 2, plane_px / 2 - 1]. Not thread-safe: one per thread. No I/O.
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/core/hal/hal.hpp>

namespace glasspiv {

// Lag of plane index k on a plane of plane_px (see above).
inline int correlation_lag_px(int k, int plane_px) { return k < plane_px / 2 ? k : k - plane_px; }

enum class CorrelationFft {
  automatic,  // radix2 where plane_px is a power of two, else opencv
  radix2,     // std::invalid_argument unless plane_px is a power of two
  opencv,
};

class WindowCorrelator {
 public:
  explicit WindowCorrelator(int window_px, CorrelationFft fft = CorrelationFft::automatic);
  int window_px() const { return window_px_; }
  int plane_px() const { return plane_px_; }
  CorrelationFft fft() const { return fft_; }  // the path in use (never automatic)

  // a, b: the top-left pixel of window_px x window_px float windows with row
  // strides in elements; valid_a / valid_b: 1 per usable pixel, same strides
  // (nullptr: all usable). Returns false, leaving the plane zero, when a window
  // has fewer than 8 usable pixels or no variation (no correlation is defined).
  bool correlate(const float* a, int stride_a, const std::uint8_t* valid_a, const float* b, int stride_b,
                 const std::uint8_t* valid_b);

  // plane_px x plane_px, row-major, unshifted (see above).
  const float* plane() const { return plane_.ptr<float>(); }
  // R at lag (dx_px, dy_px), indices wrapped.
  float at_lag(int dx_px, int dy_px) const;

 private:
  // Copies a window mean-subtracted into a zero-padded plane (row stride
  // plane_px); its sum of squares, or -1.
  double load(const float* src, int stride, const std::uint8_t* valid, float* dst) const;
  void correlate_radix2(double scale);
  void correlate_opencv(double scale);

  int window_px_, plane_px_;
  CorrelationFft fft_;
  cv::Mat plane_;  // CV_32F, plane_px x plane_px
  // opencv path
  cv::Ptr<cv::hal::DFT2D> forward_, inverse_;
  cv::Mat a_, b_, fa_, fb_, product_;  // CV_32F, plane_px x plane_px
  // radix2 path
  std::vector<float> twiddle_re_, twiddle_im_;  // e^{-2 pi i k / plane_px}, k < plane_px / 2
  std::vector<int> bit_reverse_, identity_;     // of log2(plane_px) bits; k -> k
  std::vector<float> re_, im_, t_re_, t_im_;    // plane_px^2 each
};

}  // namespace glasspiv
