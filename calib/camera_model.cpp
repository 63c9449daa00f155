#include "calib/camera_model.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include <Eigen/LU>

#include "util/input_error.h"

namespace glasspiv {

std::string lens_model_name(LensModel model) {
  switch (model) {
    case LensModel::Pinhole: return "pinhole";
    case LensModel::OpenCV4: return "opencv4";
    case LensModel::OpenCV5: return "opencv5";
    case LensModel::OpenCV8: return "opencv8";
    case LensModel::OpenCV12: return "opencv12";
    case LensModel::OpenCV14: return "opencv14";
  }
  return "unknown";
}

LensModel lens_model_from_name(const std::string& name) {
  for (LensModel m : {LensModel::Pinhole, LensModel::OpenCV4, LensModel::OpenCV5, LensModel::OpenCV8,
                      LensModel::OpenCV12, LensModel::OpenCV14})
    if (lens_model_name(m) == name) return m;
  throw InputError("", "lens_model",
                   "unknown lens model '" + name + "' (expected pinhole, opencv4, opencv5, opencv8, opencv12 or opencv14)");
}

LensModel lens_model_for_count(std::size_t count, const std::string& field) {
  switch (count) {
    case 0: return LensModel::Pinhole;
    case 4: return LensModel::OpenCV4;
    case 5: return LensModel::OpenCV5;
    case 8: return LensModel::OpenCV8;
    case 12: return LensModel::OpenCV12;
    case 14: return LensModel::OpenCV14;
    default:
      throw InputError("", field,
                       "has " + std::to_string(count) + " coefficients; OpenCV's model takes 0, 4, 5, 8, 12 or 14");
  }
}

const char* to_string(UnprojectStatus status) {
  switch (status) {
    case UnprojectStatus::Ok: return "ok";
    case UnprojectStatus::NonFinite: return "pixel is not finite";
    case UnprojectStatus::NotConverged: return "no ray maps to this pixel (outside the lens model's image)";
    case UnprojectStatus::BeyondFold: return "the pixel lies beyond the radius where the distortion folds back";
  }
  return "unknown";
}

namespace {

// A number as a short text without fmt (this library does not link it).
std::string number_text(double value) {
  std::ostringstream out;
  out.imbue(std::locale::classic());
  out.precision(17);
  out << value;
  return out.str();
}

const std::string& image_limit_text() {
  static const std::string text = "glasspiv takes images of at most " + std::to_string(kMaxImageSidePx) +
                                  " px a side and " + std::to_string(kMaxImagePixels) + " px (2^30) in all";
  return text;
}

// The problem with one side, or "" when it is fine.
std::string side_problem(double value) {
  if (!(value == std::floor(value)) || !std::isfinite(value))
    return "must be a whole number of pixels, got " + number_text(value);
  if (value <= 0) return "must be a positive number of pixels, got " + number_text(value);
  if (value > kMaxImageSidePx) return number_text(value) + " px is too large: " + image_limit_text();
  return "";
}

}  // namespace

int checked_image_side_px(double value, const std::string& field) {
  const std::string problem = side_problem(value);
  if (!problem.empty()) throw InputError("", field, problem);
  return static_cast<int>(value);
}

void check_image_size(double width_px, double height_px, const std::string& field) {
  if (const std::string problem = side_problem(width_px); !problem.empty())
    throw InputError("", field, "width " + problem);
  if (const std::string problem = side_problem(height_px); !problem.empty())
    throw InputError("", field, "height " + problem);
  if (width_px * height_px > static_cast<double>(kMaxImagePixels))
    throw InputError("", field,
                     number_text(width_px) + " x " + number_text(height_px) + " = " +
                         number_text(width_px * height_px) + " px is too large: " + image_limit_text());
}

CameraModel::CameraModel(int width_px, int height_px, double fx_px, double fy_px, double cx_px, double cy_px,
                         std::vector<double> distortion)
    : width_px_(width_px), height_px_(height_px), lens_model_(lens_model_for_count(distortion.size())) {
  checked_image_side_px(width_px, "image width");
  checked_image_side_px(height_px, "image height");
  check_image_size(width_px, height_px, "image size");
  if (!(std::isfinite(fx_px) && fx_px > 0)) throw InputError("", "fx", "must be positive and finite");
  if (!(std::isfinite(fy_px) && fy_px > 0)) throw InputError("", "fy", "must be positive and finite");
  if (!std::isfinite(cx_px)) throw InputError("", "cx", "must be finite");
  if (!std::isfinite(cy_px)) throw InputError("", "cy", "must be finite");
  static const char* names[] = {"k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6",
                                "s1", "s2", "s3", "s4", "tau_x", "tau_y"};
  for (std::size_t i = 0; i < distortion.size(); ++i)
    if (!std::isfinite(distortion[i])) throw InputError("", names[i], "must be finite");
  intrinsics_ = {fx_px, fy_px, cx_px, cy_px};
  std::copy(distortion.begin(), distortion.end(), intrinsics_.begin() + 4);
  tilted_ = lens_model_ == LensModel::OpenCV14;
  const auto nonzero = [&](int first, int last) {
    return std::any_of(intrinsics_.begin() + 4 + first, intrinsics_.begin() + 4 + last + 1,
                       [](double c) { return c != 0; });
  };
  rational_ = nonzero(5, 7);
  prism_ = nonzero(8, 11);
  if (tilted_) tilt_projection_matrix(intrinsics_[4 + 12], intrinsics_[4 + 13], tilt_.data());
  find_fold_radii();
}

std::vector<double> CameraModel::distortion() const {
  return {intrinsics_.begin() + 4, intrinsics_.begin() + 4 + distortion_count()};
}

Eigen::Matrix3d CameraModel::camera_matrix() const {
  Eigen::Matrix3d k;
  k << fx_px(), 0, cx_px(), 0, fy_px(), cy_px(), 0, 0, 1;
  return k;
}

// Inlined into Newton's loops: its Jacobian stays in registers, and the
// interleaved pixels of unproject_batch overlap.
[[gnu::always_inline]] inline Eigen::Vector2d CameraModel::project_normalized_inline(
    const Eigen::Vector2d& normalized, Eigen::Matrix2d* d_pixel_d_normalized) const {
  double xd, yd, j[4];
  distort(intrinsics_.data() + 4, tilted_ ? tilt_.data() : nullptr, normalized.x(), normalized.y(), &xd, &yd,
          d_pixel_d_normalized ? j : nullptr, rational_, prism_);
  if (d_pixel_d_normalized) *d_pixel_d_normalized << fx_px() * j[0], fx_px() * j[1], fy_px() * j[2], fy_px() * j[3];
  return {fx_px() * xd + cx_px(), fy_px() * yd + cy_px()};
}

Eigen::Vector2d CameraModel::project_normalized(const Eigen::Vector2d& normalized,
                                                Eigen::Matrix2d* d_pixel_d_normalized) const {
  return project_normalized_inline(normalized, d_pixel_d_normalized);
}

std::optional<Eigen::Vector2d> CameraModel::project(const Eigen::Vector3d& p,
                                                    Eigen::Matrix<double, 2, 3>* d_pixel_d_point) const {
  if (!p.allFinite() || !(p.z() > 0)) return std::nullopt;
  const double inv_z = 1.0 / p.z();
  const Eigen::Vector2d n(p.x() * inv_z, p.y() * inv_z);
  Eigen::Matrix2d d_pixel_d_n;
  const Eigen::Vector2d pixel = project_normalized(n, d_pixel_d_point ? &d_pixel_d_n : nullptr);
  if (d_pixel_d_point) {
    Eigen::Matrix<double, 2, 3> d_n_d_p;
    d_n_d_p << inv_z, 0, -n.x() * inv_z, 0, inv_z, -n.y() * inv_z;
    *d_pixel_d_point = d_pixel_d_n * d_n_d_p;
  }
  return pixel;
}

void CameraModel::find_fold_radii() {
  // March outwards along each direction until the Jacobian determinant of the
  // distortion stops being positive: that is where the image folds back.
  constexpr double kStep = 1e-2;  // relative radius step of the march, refined by bisection
  const auto folded = [&](const Eigen::Vector2d& n) {
    Eigen::Matrix2d j;
    project_normalized(n, &j);
    return !(j.determinant() > 0);
  };
  for (int d = 0; d < kFoldDirections; ++d) {
    double& fold = fold_radius_by_direction_[d];
    fold = kFoldSearchRadius;
    if (lens_model_ == LensModel::Pinhole) continue;
    const double angle = 2.0 * M_PI * d / kFoldDirections;
    const Eigen::Vector2d direction(std::cos(angle), std::sin(angle));
    double inside = 0;
    for (double r = 1e-3; r < kFoldSearchRadius; inside = r, r *= 1.0 + kStep) {
      if (!folded(direction * r)) continue;
      double outside = r;
      for (int i = 0; i < 30; ++i) {
        const double mid = 0.5 * (inside + outside);
        (folded(direction * mid) ? outside : inside) = mid;
      }
      fold = inside;
      break;
    }
  }
  // Directions between the samples may fold slightly earlier: keep a margin.
  const double fold = *std::min_element(fold_radius_by_direction_.begin(), fold_radius_by_direction_.end());
  fold_radius_ = fold < kFoldSearchRadius ? 0.98 * fold : fold;
}

bool CameraModel::inside_invertible_region(const Eigen::Vector2d& n) const {
  if (lens_model_ == LensModel::Pinhole) return true;
  const double r = n.norm();
  if (r < fold_radius_) return true;  // inside the fold in every direction: no look-up needed
  if (r >= kFoldSearchRadius) return false;
  double sector = std::atan2(n.y(), n.x()) / (2.0 * M_PI) * kFoldDirections;
  if (sector < 0) sector += kFoldDirections;
  const int i = static_cast<int>(sector) % kFoldDirections;
  const double bound = std::min(fold_radius_by_direction_[i], fold_radius_by_direction_[(i + 1) % kFoldDirections]);
  return bound >= kFoldSearchRadius ? true : r < 0.98 * bound;
}

UnprojectResult CameraModel::unproject(const Eigen::Vector2d& pixel, double tolerance_px) const {
  UnprojectResult result;
  if (!pixel.allFinite()) {
    result.status = UnprojectStatus::NonFinite;
    return result;
  }
  Eigen::Vector2d n = undistorted_guess(pixel);
  result.dpixel_dnormalized = Eigen::Vector2d(fx_px(), fy_px()).asDiagonal();
  if (lens_model_ != LensModel::Pinhole) {
    Eigen::Matrix2d j;
    Eigen::Vector2d error = project_normalized(n, &j) - pixel;
    double error_norm = error.norm();
    bool converged = error_norm <= tolerance_px;
    int it = 0;
    for (; it < kMaxUnprojectIterations && !converged; ++it) {
      const double det = j.determinant();
      if (!(std::abs(det) > 0) || !std::isfinite(det)) break;
      const Eigen::Vector2d step = j.inverse() * error;
      // Backtracking: halve the Newton step until the residual decreases, so
      // strong distortion far from the guess cannot throw the iterate away.
      double scale = 1.0;
      Eigen::Vector2d trial_n, trial_error;
      Eigen::Matrix2d trial_j;
      double trial_norm = 0;
      bool improved = false;
      for (int halving = 0; halving < 30; ++halving, scale *= 0.5) {
        trial_n = n - scale * step;
        trial_error = project_normalized(trial_n, &trial_j) - pixel;
        trial_norm = trial_error.norm();
        if (trial_error.allFinite() && trial_norm < error_norm) {
          improved = true;
          break;
        }
      }
      if (!improved) break;
      n = trial_n;
      error = trial_error;
      error_norm = trial_norm;
      j = trial_j;
      converged = error_norm <= tolerance_px;
    }
    result.iterations = it;
    if (!converged) {
      result.status = UnprojectStatus::NotConverged;
      return result;
    }
    return converged_result(n, j, it);
  }
  return converged_result(n, result.dpixel_dnormalized, 0);
}

Eigen::Vector2d CameraModel::undistorted_guess(const Eigen::Vector2d& pixel) const {
  return {(pixel.x() - cx_px()) / fx_px(), (pixel.y() - cy_px()) / fy_px()};
}

UnprojectResult CameraModel::converged_result(const Eigen::Vector2d& n, const Eigen::Matrix2d& j,
                                              int iterations) const {
  UnprojectResult result;
  result.iterations = iterations;
  if (!inside_invertible_region(n)) {
    result.status = UnprojectStatus::BeyondFold;
    return result;
  }
  result.dpixel_dnormalized = j;
  result.status = UnprojectStatus::Ok;
  result.normalized = n;
  result.ray_camera = Eigen::Vector3d(n.x(), n.y(), 1.0).normalized();
  return result;
}

void CameraModel::unproject_batch(const Eigen::Vector2d* pixels, int count, UnprojectResult* out,
                                  double tolerance_px) const {
  unproject_lanes(pixels, nullptr, count, out, tolerance_px);
}

void CameraModel::unproject_batch_near(const Eigen::Vector2d* pixels, int count, const Eigen::Vector2d* near_pixels,
                                       const UnprojectResult* near, UnprojectResult* out,
                                       double tolerance_px) const {
  Eigen::Vector2d start[kUnprojectBatch];
  for (int first = 0; first < count; first += kUnprojectBatch) {
    const int lanes = std::min(kUnprojectBatch, count - first);
    for (int l = 0; l < lanes; ++l) {
      const int i = first + l;
      const Eigen::Vector2d offset = pixels[i] - near_pixels[i];
      const double det = near[i].dpixel_dnormalized.determinant();
      // One Newton step from the neighbour's solution, whose Jacobian is known:
      // n = n_near + J^-1 (pixel - pixel_near).
      if (near[i].ok() && offset.allFinite() && offset.cwiseAbs().maxCoeff() <= kWarmStartMaxPx &&
          std::abs(det) > 0 && std::isfinite(det))
        start[l] = near[i].normalized + near[i].dpixel_dnormalized.inverse() * offset;
      else
        start[l] = undistorted_guess(pixels[i]);
    }
    unproject_lanes(pixels + first, start, lanes, out + first, tolerance_px);
  }
}

void CameraModel::unproject_lanes(const Eigen::Vector2d* pixels, const Eigen::Vector2d* start, int count,
                                  UnprojectResult* out, double tolerance_px) const {
  for (int first = 0; first < count; first += kUnprojectBatch) {
    const int lanes = std::min(kUnprojectBatch, count - first);
    const Eigen::Vector2d* pixel = pixels + first;
    // Each lane runs unproject's own arithmetic while every full Newton step
    // lowers its residual (the common path); a lane that leaves that path
    // (a halved step, a singular Jacobian, a non-finite pixel) is handed to
    // unproject whole, which retraces the same steps: results equal to the bit.
    Eigen::Vector2d n[kUnprojectBatch], error[kUnprojectBatch];
    Eigen::Matrix2d j[kUnprojectBatch];
    double error_norm[kUnprojectBatch];
    int iterations[kUnprojectBatch];
    bool active[kUnprojectBatch], fallback[kUnprojectBatch];
    const bool pinhole = lens_model_ == LensModel::Pinhole;
    for (int l = 0; l < lanes; ++l) {
      fallback[l] = pinhole || !pixel[l].allFinite();
      active[l] = false;
      if (fallback[l]) continue;
      n[l] = start ? start[first + l] : undistorted_guess(pixel[l]);
      error[l] = project_normalized_inline(n[l], &j[l]) - pixel[l];
      error_norm[l] = error[l].norm();
      iterations[l] = 0;
      active[l] = !(error_norm[l] <= tolerance_px);
    }
    for (bool any = true; any;) {
      any = false;
      for (int l = 0; l < lanes; ++l) {
        if (!active[l]) continue;
        const double det = j[l].determinant();
        if (iterations[l] >= kMaxUnprojectIterations || !(std::abs(det) > 0) || !std::isfinite(det)) {
          fallback[l] = true;
          active[l] = false;
          continue;
        }
        const Eigen::Vector2d step = j[l].inverse() * error[l];
        const double scale = 1.0;
        const Eigen::Vector2d trial_n = n[l] - scale * step;
        Eigen::Matrix2d trial_j;
        const Eigen::Vector2d trial_error = project_normalized_inline(trial_n, &trial_j) - pixel[l];
        const double trial_norm = trial_error.norm();
        if (!(trial_error.allFinite() && trial_norm < error_norm[l])) {
          fallback[l] = true;
          active[l] = false;
          continue;
        }
        n[l] = trial_n;
        error[l] = trial_error;
        error_norm[l] = trial_norm;
        j[l] = trial_j;
        ++iterations[l];
        active[l] = !(error_norm[l] <= tolerance_px);
        any = any || active[l];
      }
    }
    for (int l = 0; l < lanes; ++l)
      out[first + l] = fallback[l] ? unproject(pixel[l], tolerance_px) : converged_result(n[l], j[l], iterations[l]);
  }
}

std::optional<CameraModel::FieldOfView> CameraModel::field_of_view() const {
  // Angles between the rays through opposite edge points (pixel centres of the
  // outermost pixels extended by half a pixel to the sensor edge).
  const double left = -0.5, right = width_px_ - 0.5, top = -0.5, bottom = height_px_ - 0.5;
  const auto angle_deg = [&](Eigen::Vector2d a, Eigen::Vector2d b) -> std::optional<double> {
    const UnprojectResult ra = unproject(a, 1e-9), rb = unproject(b, 1e-9);
    if (!ra.ok() || !rb.ok()) return std::nullopt;
    return std::acos(std::clamp(ra.ray_camera.dot(rb.ray_camera), -1.0, 1.0)) * 180.0 / M_PI;
  };
  const auto h = angle_deg({left, cy_px()}, {right, cy_px()});
  const auto v = angle_deg({cx_px(), top}, {cx_px(), bottom});
  const auto d = angle_deg({left, top}, {right, bottom});
  if (!h || !v || !d) return std::nullopt;
  return FieldOfView{*h, *v, *d};
}

bool CameraModel::operator==(const CameraModel& other) const {
  return width_px_ == other.width_px_ && height_px_ == other.height_px_ && lens_model_ == other.lens_model_ &&
         intrinsics_ == other.intrinsics_;
}

CameraModel binned(const CameraModel& m, int factor) {
  if (factor < 1 || m.width_px() / factor < 1 || m.height_px() / factor < 1)
    throw InputError("", "binning", "must be a whole number from 1 to the image size");
  if (factor == 1) return m;
  const double k = factor;
  return CameraModel(m.width_px() / factor, m.height_px() / factor, m.fx_px() / k, m.fy_px() / k,
                     (m.cx_px() + 0.5) / k - 0.5, (m.cy_px() + 0.5) / k - 0.5, m.distortion());
}

}  // namespace glasspiv
