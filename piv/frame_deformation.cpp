#include "piv/frame_deformation.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "piv/row_threads.h"

namespace glasspiv {
namespace {

// Cell index and fraction of a coordinate on a grid axis of n centres; beyond
// the outermost centres the end cell is extended (fraction < 0 or > 1), so a
// gradient carries on to the image border, where the border windows need it.
void axis_cell(double coordinate, double first, int step, int n, int& i0, double& f) {
  const double g = (coordinate - first) / step;
  i0 = std::clamp(static_cast<int>(std::floor(g)), 0, std::max(0, n - 2));
  f = n > 1 ? g - i0 : 0.0;
}

// Keys (1981) cubic convolution weights, a = -0.5, for taps -1, 0, 1, 2 at fraction t.
void keys_weights(double t, double w[4]) {
  const double t2 = t * t, t3 = t2 * t;
  w[0] = -0.5 * t3 + t2 - 0.5 * t;
  w[1] = 1.5 * t3 - 2.5 * t2 + 1;
  w[2] = -1.5 * t3 + 2 * t2 + 0.5 * t;
  w[3] = 0.5 * t3 - 0.5 * t2;
}

// Tap index reflected about the border pixels (taps reach at most 2 beyond).
int mirrored(int i, int n) {
  if (n == 1) return 0;
  if (i < 0) i = -i;
  if (i > n - 1) i = 2 * (n - 1) - i;
  return std::clamp(i, 0, n - 1);
}

// Cubic B-spline weights for taps -1, 0, 1, 2 at fraction t.
void bspline_weights(double t, double w[4]) {
  const double s = 1 - t, t2 = t * t, t3 = t2 * t;
  w[0] = s * s * s / 6;
  w[1] = (3 * t3 - 6 * t2 + 4) / 6;
  w[2] = (-3 * t3 + 3 * t2 + 3 * t + 1) / 6;
  w[3] = t3 / 6;
}

// One pole z of the B-spline prefilter along a line, in place (Unser 1999:
// causal and anti-causal first-order recursions, mirror boundaries; the gain
// is applied by the caller).
void bspline_pole_line(double* c, int n, double z) {
  // Causal start: the mirrored sum, truncated where |z|^k is below 1e-12.
  const int horizon = std::min(n, static_cast<int>(std::ceil(std::log(1e-12) / std::log(std::abs(z)))) + 1);
  double sum = c[0], zk = z;
  for (int k = 1; k < horizon; ++k, zk *= z) sum += zk * c[k];
  c[0] = sum;
  for (int i = 1; i < n; ++i) c[i] += z * c[i - 1];
  c[n - 1] = z / (z * z - 1) * (z * c[n - 2] + c[n - 1]);
  for (int i = n - 2; i >= 0; --i) c[i] = z * (c[i + 1] - c[i]);
}

// The poles of the cubic and quintic B-spline prefilters (Unser 1999, table I).
std::vector<double> bspline_poles(int degree) {
  if (degree == 3) return {std::sqrt(3.0) - 2};
  return {-0.430575347099973791851434783493520, -0.043096288203264653822712376822550};
}

void bspline_prefilter_line(double* c, int n, const std::vector<double>& poles) {
  if (n < 2) return;
  double gain = 1;
  for (double z : poles) gain *= (1 - z) * (1 - 1 / z);
  for (int i = 0; i < n; ++i) c[i] *= gain;
  for (double z : poles) bspline_pole_line(c, n, z);
}

cv::Mat bspline_coefficients(const cv::Mat& frame, int degree, int threads) {
  const int w = frame.cols, h = frame.rows;
  const std::vector<double> poles = bspline_poles(degree);
  cv::Mat c;
  frame.convertTo(c, CV_64F);
  for_each_row(h, threads, [&](int y, int) { bspline_prefilter_line(c.ptr<double>(y), w, poles); });
  // Columns in blocks of 8, copied to a line and back.
  const int blocks = (w + 7) / 8;
  for_each_row(blocks, threads, [&](int block, int) {
    std::vector<double> line(static_cast<std::size_t>(h));
    for (int x = block * 8; x < std::min(w, block * 8 + 8); ++x) {
      for (int y = 0; y < h; ++y) line[static_cast<std::size_t>(y)] = c.at<double>(y, x);
      bspline_prefilter_line(line.data(), h, poles);
      for (int y = 0; y < h; ++y) c.at<double>(y, x) = line[static_cast<std::size_t>(y)];
    }
  });
  cv::Mat out;
  c.convertTo(out, CV_32F);
  return out;
}

// Quintic B-spline weights for taps -2 .. 3 at fraction t: beta5(t - k), the
// pieces of beta5 written as polynomials in t (they sum to 1).
void bspline5_weights(double t, double w[6]) {
  const double s = 1 - t;
  const double t2 = t * t, t3 = t2 * t, t4 = t3 * t, t5 = t4 * t;
  const double s2 = s * s, s3 = s2 * s, s4 = s3 * s, s5 = s4 * s;
  w[0] = s5 / 120;
  w[1] = (1 + 5 * s + 10 * s2 + 10 * s3 + 5 * s4 - 5 * s5) / 120;
  w[2] = (66 - 60 * t2 + 30 * t4 - 10 * t5) / 120;
  w[3] = (66 - 60 * s2 + 30 * s4 - 10 * s5) / 120;
  w[4] = (1 + 5 * t + 10 * t2 + 10 * t3 + 5 * t4 - 5 * t5) / 120;
  w[5] = t5 / 120;
}

}  // namespace

const char* deform_interpolation_name(DeformInterpolation interpolation) {
  switch (interpolation) {
    case DeformInterpolation::bilinear: return "bilinear";
    case DeformInterpolation::bicubic: return "bicubic";
    case DeformInterpolation::bspline3: return "bspline3";
    case DeformInterpolation::bspline5: return "bspline5";
  }
  return "?";
}

double grid_field_at(const InterrogationGrid& grid, const std::vector<double>& field, double x_px, double y_px) {
  int c0, r0;
  double fx, fy;
  axis_cell(x_px, grid.x_px(0), grid.step_px, grid.cols, c0, fx);
  axis_cell(y_px, grid.y_px(0), grid.step_px, grid.rows, r0, fy);
  const int c1 = std::min(c0 + 1, grid.cols - 1), r1 = std::min(r0 + 1, grid.rows - 1);
  auto at = [&](int c, int r) { return field[static_cast<std::size_t>(grid.index(c, r))]; };
  return (1 - fy) * ((1 - fx) * at(c0, r0) + fx * at(c1, r0)) + fy * ((1 - fx) * at(c0, r1) + fx * at(c1, r1));
}

cv::Mat dense_field(const InterrogationGrid& grid, const std::vector<double>& field, int width_px, int height_px) {
  if (field.size() != static_cast<std::size_t>(grid.size()) || grid.size() == 0)
    throw std::invalid_argument("dense_field: field size differs from the grid");
  std::vector<int> c0(static_cast<std::size_t>(width_px));
  std::vector<double> fx(static_cast<std::size_t>(width_px));
  for (int x = 0; x < width_px; ++x) axis_cell(x, grid.x_px(0), grid.step_px, grid.cols, c0[x], fx[x]);
  cv::Mat out(height_px, width_px, CV_32F);
  for (int y = 0; y < height_px; ++y) {
    int r0;
    double fy;
    axis_cell(y, grid.y_px(0), grid.step_px, grid.rows, r0, fy);
    const int r1 = std::min(r0 + 1, grid.rows - 1);
    const double* row0 = &field[static_cast<std::size_t>(grid.index(0, r0))];
    const double* row1 = &field[static_cast<std::size_t>(grid.index(0, r1))];
    float* o = out.ptr<float>(y);
    for (int x = 0; x < width_px; ++x) {
      const int a = c0[x], b = std::min(a + 1, grid.cols - 1);
      const double f = fx[x];
      o[x] = static_cast<float>((1 - fy) * ((1 - f) * row0[a] + f * row0[b]) + fy * ((1 - f) * row1[a] + f * row1[b]));
    }
  }
  return out;
}

DeformedFrame deform_frame(const cv::Mat& frame, const cv::Mat& usable, const cv::Mat& u_px, const cv::Mat& v_px,
                           double fraction, DeformInterpolation interpolation, int threads) {
  const int w = frame.cols, h = frame.rows;
  if (frame.type() != CV_32F || u_px.type() != CV_32F || v_px.type() != CV_32F || u_px.size() != frame.size() ||
      v_px.size() != frame.size() || (!usable.empty() && (usable.type() != CV_8U || usable.size() != frame.size())))
    throw std::invalid_argument("deform_frame: frame, field and mask must be CV_32F / CV_8U of one size");
  DeformedFrame out{cv::Mat(h, w, CV_32F), cv::Mat(h, w, CV_8U)};
  const int degree = interpolation == DeformInterpolation::bspline3   ? 3
                     : interpolation == DeformInterpolation::bspline5 ? 5
                     : interpolation == DeformInterpolation::bicubic  ? 1 /* Keys */
                                                                      : 0;
  const int taps = degree == 5 ? 6 : degree == 0 ? 2 : 4, first_tap = degree == 5 ? -2 : degree == 0 ? 0 : -1;
  const cv::Mat source = degree >= 3 ? bspline_coefficients(frame, degree, threads) : frame;
  for_each_row(h, threads, [&](int y, int) {
    const float* u = u_px.ptr<float>(y);
    const float* v = v_px.ptr<float>(y);
    float* o = out.values.ptr<float>(y);
    std::uint8_t* ok = out.usable.ptr<std::uint8_t>(y);
    for (int x = 0; x < w; ++x) {
      const double sx = x + fraction * u[x], sy = y + fraction * v[x];
      if (!(sx >= 0 && sx <= w - 1 && sy >= 0 && sy <= h - 1)) {
        o[x] = 0;
        ok[x] = 0;
        continue;
      }
      const int x0 = static_cast<int>(sx), y0 = static_cast<int>(sy);
      double wx[6], wy[6];
      if (degree == 5) {
        bspline5_weights(sx - x0, wx);
        bspline5_weights(sy - y0, wy);
      } else if (degree == 3) {
        bspline_weights(sx - x0, wx);
        bspline_weights(sy - y0, wy);
      } else if (degree == 1) {
        keys_weights(sx - x0, wx);
        keys_weights(sy - y0, wy);
      } else {
        wx[0] = 1 - (sx - x0), wx[1] = sx - x0;
        wy[0] = 1 - (sy - y0), wy[1] = sy - y0;
      }
      int xi[6];
      for (int i = 0; i < taps; ++i) xi[i] = mirrored(x0 + first_tap + i, w);
      double sum = 0;
      bool good = true;
      for (int j = 0; j < taps; ++j) {
        if (wy[j] == 0) continue;
        const int yy = mirrored(y0 + first_tap + j, h);
        const float* src = source.ptr<float>(yy);
        double row = 0;
        for (int i = 0; i < taps; ++i) row += wx[i] * src[xi[i]];
        sum += wy[j] * row;
        if (!usable.empty()) {
          const std::uint8_t* m = usable.ptr<std::uint8_t>(yy);
          for (int i = 0; i < taps; ++i) good &= wx[i] == 0 || m[xi[i]] != 0;
        }
      }
      o[x] = good ? static_cast<float>(sum) : 0.0f;
      ok[x] = good ? 1 : 0;
    }
  });
  return out;
}

}  // namespace glasspiv
