#pragma once
// FFT cross-correlation of one pair of interrogation windows (the standard
// digital PIV estimator, Willert & Gharib 1991; Raffel et al., "Particle Image
// Velocimetry", 3rd ed., sec. 5.3), through OpenCV's DFT with its plans made
// once per window size.
//
// Both windows are mean-subtracted over their valid pixels (invalid ones, e.g.
// masked or deformed from outside the image, count as the mean, i.e. zero),
// then correlated circularly on a plane of plane_px = cv::getOptimalDFTSize
// (window_px) (= window_px for 16, 32, 64 px) and normalised by
// sqrt(sum a'^2 * sum b'^2), so that the plane holds correlation coefficients:
//
//   R(dx, dy) = sum_{x,y} a'(x, y) b'(x + dx, y + dy) / sqrt(sum a'^2 sum b'^2)
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

class WindowCorrelator {
 public:
  explicit WindowCorrelator(int window_px);
  int window_px() const { return window_px_; }
  int plane_px() const { return plane_px_; }

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
  // Copies a window mean-subtracted into a zero-padded plane; its sum of squares, or -1.
  double load(const float* src, int stride, const std::uint8_t* valid, cv::Mat& dst) const;
  int window_px_, plane_px_;
  cv::Ptr<cv::hal::DFT2D> forward_, inverse_;
  cv::Mat a_, b_, fa_, fb_, product_, plane_;  // CV_32F, plane_px x plane_px
};

}  // namespace glasspiv
