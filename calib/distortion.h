#pragma once
// OpenCV's lens distortion model (the one cv::projectPoints evaluates), written
// once as a template so plain doubles, Ceres Jets and the analytic Jacobian share
// the same arithmetic.
//
// Coefficient order is OpenCV's: k1 k2 p1 p2 k3 k4 k5 k6 s1 s2 s3 s4 tau_x tau_y.
// With (x, y) the normalised pinhole coordinates (X/Z, Y/Z) and r^2 = x^2 + y^2:
//   radial = (1 + k1 r^2 + k2 r^4 + k3 r^6) / (1 + k4 r^2 + k5 r^4 + k6 r^6)
//   x' = x radial + 2 p1 x y + p2 (r^2 + 2 x^2) + s1 r^2 + s2 r^4
//   y' = y radial + p1 (r^2 + 2 y^2) + 2 p2 x y + s3 r^2 + s4 r^4
// and the tilted-sensor (Scheimpflug) projection of (x', y', 1) by the matrix
// of cv::computeTiltProjectionMatrix(tau_x, tau_y).
#include <cmath>

namespace glasspiv {

constexpr int kMaxDistortionCoefficients = 14;

// Row-major 3x3 tilt projection matrix for Scheimpflug angles tau_x, tau_y (rad):
// R = Ry(tau_y) Rx(tau_x); M = [[R22, 0, -R02], [0, R22, -R12], [0, 0, 1]] R.
template <typename T>
void tilt_projection_matrix(const T& tau_x, const T& tau_y, T m[9]) {
  using std::cos;
  using std::sin;
  const T cx = cos(tau_x), sx = sin(tau_x), cy = cos(tau_y), sy = sin(tau_y);
  // R = Ry * Rx with Rx = [[1,0,0],[0,cx,sx],[0,-sx,cx]], Ry = [[cy,0,-sy],[0,1,0],[sy,0,cy]].
  const T r[9] = {cy, sy * sx, -sy * cx,  //
                  T(0), cx, sx,           //
                  sy, -cy * sx, cy * cx};
  const T p[9] = {r[8], T(0), -r[2], T(0), r[8], -r[5], T(0), T(0), T(1)};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m[3 * i + j] = p[3 * i] * r[j] + p[3 * i + 1] * r[3 + j] + p[3 * i + 2] * r[6 + j];
}

// Distorts normalised coordinates (x, y) into (xd, yd). `k` holds all 14
// coefficients (unused ones zero); `tilt` is the tilt matrix or nullptr for none.
// If `jacobian` is given it receives d(xd, yd)/d(x, y), row-major 2x2.
// `rational` = false skips the denominator (k4 = k5 = k6 = 0) and `prism` =
// false the thin-prism terms (s1..s4 = 0): for plain doubles whose coefficients
// are zero the result is the same to the bit (a division by 1 and added zeros
// skipped; only a zero's sign may differ), so a model skips what it does not
// have. A Jet's zero coefficient still carries a derivative: keep both true.
template <typename T>
void distort(const T* k, const T* tilt, const T& x, const T& y, T* xd, T* yd, T* jacobian = nullptr,
             bool rational = true, bool prism = true) {
  const T r2 = x * x + y * y;
  const T r4 = r2 * r2;
  const T r6 = r4 * r2;
  const T numerator = T(1) + k[0] * r2 + k[1] * r4 + k[4] * r6;
  const T inv_denominator = rational ? T(1) / (T(1) + k[5] * r2 + k[6] * r4 + k[7] * r6) : T(1);
  const T radial = rational ? numerator * inv_denominator : numerator;
  T x0 = x * radial + T(2) * k[2] * x * y + k[3] * (r2 + T(2) * x * x);
  T y0 = y * radial + k[2] * (r2 + T(2) * y * y) + T(2) * k[3] * x * y;
  if (prism) {  // added in the order of the one formula: left to right
    x0 = x0 + k[8] * r2 + k[9] * r4;
    y0 = y0 + k[10] * r2 + k[11] * r4;
  }

  T jx0[4];  // d(x0, y0)/d(x, y)
  if (jacobian) {
    const T d_num = k[0] + T(2) * k[1] * r2 + T(3) * k[4] * r4;
    T d_radial = d_num;  // d radial / d r^2
    if (rational) {
      const T d_den = k[5] + T(2) * k[6] * r2 + T(3) * k[7] * r4;
      d_radial = (d_num - radial * d_den) * inv_denominator;
    }
    jx0[0] = radial + T(2) * x * x * d_radial + T(2) * k[2] * y + T(6) * k[3] * x;
    jx0[1] = T(2) * x * y * d_radial + T(2) * k[2] * x + T(2) * k[3] * y;
    jx0[2] = T(2) * x * y * d_radial + T(2) * k[2] * x + T(2) * k[3] * y;
    jx0[3] = radial + T(2) * y * y * d_radial + T(6) * k[2] * y + T(2) * k[3] * x;
    if (prism) {
      const T prism_x = k[8] + T(2) * k[9] * r2;  // d(s1 r^2 + s2 r^4)/d r^2
      const T prism_y = k[10] + T(2) * k[11] * r2;
      jx0[0] = jx0[0] + T(2) * x * prism_x;
      jx0[1] = jx0[1] + T(2) * y * prism_x;
      jx0[2] = jx0[2] + T(2) * x * prism_y;
      jx0[3] = jx0[3] + T(2) * y * prism_y;
    }
  }
  if (tilt == nullptr) {
    *xd = x0;
    *yd = y0;
    if (jacobian)
      for (int i = 0; i < 4; ++i) jacobian[i] = jx0[i];
    return;
  }
  const T v0 = tilt[0] * x0 + tilt[1] * y0 + tilt[2];
  const T v1 = tilt[3] * x0 + tilt[4] * y0 + tilt[5];
  const T v2 = tilt[6] * x0 + tilt[7] * y0 + tilt[8];
  const T inv_v2 = T(1) / v2;
  *xd = v0 * inv_v2;
  *yd = v1 * inv_v2;
  if (jacobian) {
    // Quotient rule for the projective map, then the chain rule through (x0, y0).
    const T a00 = (tilt[0] - *xd * tilt[6]) * inv_v2, a01 = (tilt[1] - *xd * tilt[7]) * inv_v2;
    const T a10 = (tilt[3] - *yd * tilt[6]) * inv_v2, a11 = (tilt[4] - *yd * tilt[7]) * inv_v2;
    jacobian[0] = a00 * jx0[0] + a01 * jx0[2];
    jacobian[1] = a00 * jx0[1] + a01 * jx0[3];
    jacobian[2] = a10 * jx0[0] + a11 * jx0[2];
    jacobian[3] = a10 * jx0[1] + a11 * jx0[3];
  }
}

// Projects a point in the camera frame to pixels, for any scalar type (Ceres
// autodiff included). `intrinsics` = fx, fy, cx, cy followed by the 14
// distortion coefficients (zero beyond `distortion_count`); the tilt is applied
// only for the 14-coefficient model, so its derivatives exist even at tau = 0.
// Returns false (pixel untouched) if the point is not in front of the camera.
template <typename T>
bool project_point(const T* intrinsics, int distortion_count, const T* point_camera, T* pixel) {
  if (!(point_camera[2] > T(0))) return false;
  const T x = point_camera[0] / point_camera[2];
  const T y = point_camera[1] / point_camera[2];
  const T* k = intrinsics + 4;
  T tilt[9];
  const bool tilted = distortion_count == kMaxDistortionCoefficients;
  if (tilted) tilt_projection_matrix(k[12], k[13], tilt);
  T xd, yd;
  distort(k, tilted ? tilt : static_cast<const T*>(nullptr), x, y, &xd, &yd);
  pixel[0] = intrinsics[0] * xd + intrinsics[2];
  pixel[1] = intrinsics[1] * yd + intrinsics[3];
  return true;
}

}  // namespace glasspiv
