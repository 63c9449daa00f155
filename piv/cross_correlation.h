#pragma once
// FFT cross-correlation of interrogation window pairs (the standard digital
// PIV estimator, Willert & Gharib 1991; Raffel et al., "Particle Image
// Velocimetry", 3rd ed., sec. 5.3), through OpenCV's DFT.
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
//
// How (BatchCorrelator): OpenCV's DFT costs little per row but much per call
// for planes this small, so a batch of window pairs goes through five calls,
// each over all rows of the batch with a plan made once: real row DFTs of
// every window, the half spectrum (plane_px / 2 + 1 columns, the rest is its
// conjugate) transposed and transformed along the other axis, conj(FA) FB
// scaled by the normalisation, the inverse along that axis, transposed back
// into CCS-packed rows and the real inverse row DFTs. Each row's DFT does not
// depend on what else is in the batch, so planes are the same whatever the
// batch holds.
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/core/hal/hal.hpp>

namespace glasspiv {

// Lag of plane index k on a plane of plane_px (see above).
inline int correlation_lag_px(int k, int plane_px) { return k < plane_px / 2 ? k : k - plane_px; }

class BatchCorrelator {
 public:
  // capacity: window pairs per batch (at least 1).
  explicit BatchCorrelator(int window_px, int capacity = 16);
  int window_px() const { return window_px_; }
  int plane_px() const { return plane_px_; }
  int capacity() const { return capacity_; }
  int size() const { return size_; }
  bool full() const { return size_ == capacity_; }
  // Empties the batch.
  void clear() { size_ = 0; }

  // Loads one pair into the next slot (the batch must not be full). a, b: the
  // top-left pixel of window_px x window_px float windows with row strides in
  // elements; valid_a / valid_b: 1 per usable pixel, same strides (nullptr:
  // all usable). Returns the slot, or -1 (nothing loaded) when a window has
  // fewer than 8 usable pixels or no variation (no correlation is defined).
  int add(const float* a, int stride_a, const std::uint8_t* valid_a, const float* b, int stride_b,
          const std::uint8_t* valid_b);

  // Correlates every loaded pair; plane(slot) then holds its plane until the
  // next correlate().
  void correlate();
  // plane_px x plane_px, row-major, unshifted (see above).
  const float* plane(int slot) const { return planes_.ptr<float>(slot * plane_px_); }
  float* plane(int slot) { return planes_.ptr<float>(slot * plane_px_); }  // for normalising in place

 private:
  // Copies a window mean-subtracted into a zero-padded plane_px x plane_px
  // block; its sum of squares, or -1.
  double load(const float* src, int stride, const std::uint8_t* valid, float* dst) const;
  struct Plans {
    cv::Ptr<cv::hal::DFT2D> rows_forward, columns_forward, columns_inverse, rows_inverse;
  };
  const Plans& plans_for(int pairs);

  int window_px_, plane_px_, half_px_, capacity_, size_ = 0;
  std::vector<double> scale_;  // per slot: 1 / (plane_px^2 sqrt(sum a'^2 sum b'^2))
  std::vector<Plans> plans_;   // by batch size - 1, made when first needed
  // windows_: 2 planes per slot (A, B), real; row_spectra_: their row DFTs (CCS);
  // columns_: the half spectra transposed (half_px rows of plane_px complex per
  // plane), then their 2-D DFT; products_: conj(FA) FB, then inverted along
  // its rows; packed_: transposed back into CCS rows; planes_: the result.
  cv::Mat windows_, row_spectra_, columns_, spectra_, products_, inverted_, packed_, planes_;
};

// One pair at a time (a BatchCorrelator of one slot): same planes.
class WindowCorrelator {
 public:
  explicit WindowCorrelator(int window_px) : batch_(window_px, 1) {}
  int window_px() const { return batch_.window_px(); }
  int plane_px() const { return batch_.plane_px(); }

  // As BatchCorrelator::add; returns false, leaving the plane zero, when no
  // correlation is defined.
  bool correlate(const float* a, int stride_a, const std::uint8_t* valid_a, const float* b, int stride_b,
                 const std::uint8_t* valid_b);

  // plane_px x plane_px, row-major, unshifted (see above).
  const float* plane() const { return ok_ ? batch_.plane(0) : zeros_.data(); }
  // R at lag (dx_px, dy_px), indices wrapped.
  float at_lag(int dx_px, int dy_px) const;

 private:
  BatchCorrelator batch_;
  bool ok_ = false;
  std::vector<float> zeros_ = std::vector<float>(static_cast<std::size_t>(plane_px()) * plane_px(), 0.0f);
};

}  // namespace glasspiv
