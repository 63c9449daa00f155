#include "calib/fit/lens_validity.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>

#include <Eigen/Eigenvalues>

namespace glasspiv {
namespace {

// A polynomial in s, coefficients from the constant term up.
using Polynomial = std::vector<double>;

double evaluate(const Polynomial& p, double s) {
  double v = 0;
  for (auto c = p.rbegin(); c != p.rend(); ++c) v = v * s + *c;
  return v;
}

Polynomial derivative(const Polynomial& p) {
  Polynomial d;
  for (std::size_t i = 1; i < p.size(); ++i) d.push_back(static_cast<double>(i) * p[i]);
  return d;
}

Polynomial product(const Polynomial& a, const Polynomial& b) {
  Polynomial c(a.size() + b.size() - 1, 0.0);
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) c[i + j] += a[i] * b[j];
  return c;
}

// The real parts of all complex roots (eigenvalues of the companion matrix):
// a superset of the real roots, so that a minimum taken over them and the
// interval's ends is never above the true one.
std::vector<double> root_real_parts(Polynomial p) {
  while (!p.empty() && p.back() == 0) p.pop_back();
  const int degree = static_cast<int>(p.size()) - 1;
  if (degree < 1) return {};
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(degree, degree);
  for (int i = 0; i < degree; ++i) companion(0, i) = -p[degree - 1 - i] / p[degree];
  for (int i = 1; i < degree; ++i) companion(i, i - 1) = 1;
  const Eigen::EigenSolver<Eigen::MatrixXd> eigen(companion, false);
  std::vector<double> out;
  for (int i = 0; i < degree; ++i) out.push_back(eigen.eigenvalues()(i).real());
  return out;
}

// A polynomial's minimum over [0, s]: at an end or at a critical point.
struct MinimumOn {
  Polynomial p;
  std::vector<double> critical;  // real parts of the roots of p'
  explicit MinimumOn(Polynomial poly) : p(std::move(poly)), critical(root_real_parts(derivative(p))) {}
  double operator()(double s) const {
    double m = std::min(evaluate(p, 0), evaluate(p, s));
    for (double c : critical)
      if (c > 0 && c < s) m = std::min(m, evaluate(p, c));
    return m;
  }
  // The smallest s in (0, s_max] where p reaches 0 (p(0) > 0), or s_max.
  double first_zero(double s_max) const {
    if ((*this)(s_max) > 0) return s_max;
    double inside = 0, outside = s_max;
    for (int i = 0; i < 200 && outside - inside > 1e-15 * outside; ++i) {
      const double mid = 0.5 * (inside + outside);
      ((*this)(mid) > 0 ? inside : outside) = mid;
    }
    return outside;
  }
};

std::string format(const char* pattern, double a, double b = 0, double c = 0, double d = 0) {
  char text[256];
  std::snprintf(text, sizeof text, pattern, a, b, c, d);
  return text;
}

}  // namespace

LensValidity check_one_to_one(const CameraModel& camera, double radius) {
  const auto& q = camera.intrinsics();
  const double* k = q.data() + 4;
  // N, D and P of the header, in s = r_u^2.
  const Polynomial numerator{1, k[0], k[1], k[4]}, denominator{1, k[5], k[6], k[7]};
  Polynomial numerator_term(4), denominator_term(4);  // N + 2 s N', 2 s D'
  for (int i = 0; i < 4; ++i) {
    numerator_term[i] = (1 + 2 * i) * numerator[i];
    denominator_term[i] = 2 * i * denominator[i];
  }
  Polynomial slope = product(numerator_term, denominator);
  const Polynomial minus = product(numerator, denominator_term);
  for (std::size_t i = 0; i < slope.size(); ++i) slope[i] -= minus[i];
  const MinimumOn min_denominator(denominator), min_slope(slope);
  const auto radial = [&](double s) { return std::sqrt(s) * evaluate(numerator, s) / evaluate(denominator, s); };

  LensValidity out;
  out.radius_checked = radius;
  const double focal_px = 0.5 * (camera.fx_px() + camera.fy_px());
  // Where the radial map first stops increasing (P = 0) or meets a pole
  // (D = 0), searched up to 84 deg off axis (CameraModel::kFoldSearchRadius).
  const double s_max = CameraModel::kFoldSearchRadius * CameraModel::kFoldSearchRadius;
  const double s_fold = min_slope.first_zero(s_max), s_pole = min_denominator.first_zero(s_max);
  const double s_bad = std::min(s_fold, s_pole);
  out.fold_radius = s_bad < s_max ? std::sqrt(s_bad) : CameraModel::kFoldSearchRadius;
  const double s_checked = std::min(radius * radius, s_bad);
  out.min_denominator = min_denominator(s_checked);
  out.min_radial_slope = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= 4096; ++i) {
    const double si = s_checked * i / 4096.0, d = evaluate(denominator, si);
    out.min_radial_slope = std::min(out.min_radial_slope, evaluate(slope, si) / (d * d));
  }
  if (radius * radius >= s_bad) {
    out.one_to_one = false;
    out.why = s_pole <= s_fold
                  ? format("the rational denominator crosses 0 at r_u = %.4f", std::sqrt(s_pole))
                  : format("the radial map folds back at r_u = %.4f (r_d = %.4f, %.0f px from the principal point)",
                           std::sqrt(s_fold), radial(s_fold), radial(s_fold) * focal_px);
    if (s_pole < s_max && s_pole > s_fold)
      out.why += format(" and its denominator crosses 0 at r_u = %.4f", std::sqrt(s_pole));
    out.why += format(", inside the checked radius %.4f", radius);
    return out;
  }

  // The full map on the disc r_u <= radius_checked: tangential and thin-prism
  // terms and the tilt can fold it where the radial map does not.
  std::array<double, 9> tilt{};
  const bool tilted = q[4 + 12] != 0 || q[4 + 13] != 0;
  if (tilted) tilt_projection_matrix(q[4 + 12], q[4 + 13], tilt.data());
  constexpr int kRadii = 256, kAngles = 72;
  for (int i = 1; i <= kRadii; ++i)
    for (int a = 0; a < kAngles; ++a) {
      const double r = radius * i / kRadii, angle = 2 * M_PI * a / kAngles;
      const double x = r * std::cos(angle), y = r * std::sin(angle);
      double xd = 0, yd = 0, j[4];
      distort(k, tilted ? tilt.data() : nullptr, x, y, &xd, &yd, j);
      if (!(j[0] * j[3] - j[1] * j[2] > 0)) {
        out.one_to_one = false;
        out.why = format("the distortion folds at (x_u, y_u) = (%.4f, %.4f), inside the checked radius %.4f", x, y, radius);
        return out;
      }
    }
  return out;
}

double observed_undistorted_radius(const Observations& observations,
                                   const std::vector<RigidTransform>& camera_from_board) {
  double radius = 0;
  for (std::size_t v = 0; v < observations.views.size() && v < camera_from_board.size(); ++v)
    for (const CornerObservation& c : observations.views[v].corners) {
      const Eigen::Vector3d p = camera_from_board[v].apply(c.board_point_mm);
      if (p.z() > 0) radius = std::max(radius, p.head<2>().norm() / p.z());
    }
  return radius;
}

}  // namespace glasspiv
