#pragma once
// The camera model of glasspiv: a pinhole with OpenCV's distortion (0, 4, 5, 8,
// 12 or 14 coefficients). Conventions (docs/conventions.md): camera frame x right,
// y down, z forward; pixel (0, 0) is the centre of the top-left pixel, as in
// OpenCV and mrcal.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "calib/distortion.h"
#include "util/image_file.h"

namespace glasspiv {

// The OpenCV distortion lengths we support, named as mrcal names them.
enum class LensModel { Pinhole = 0, OpenCV4 = 4, OpenCV5 = 5, OpenCV8 = 8, OpenCV12 = 12, OpenCV14 = 14 };

// "opencv8" etc.; parse throws InputError on an unknown name.
std::string lens_model_name(LensModel model);
LensModel lens_model_from_name(const std::string& name);
// The model for a coefficient count; throws InputError naming `field` otherwise.
LensModel lens_model_for_count(std::size_t count, const std::string& field = "distortion_coefficients");

// The largest image glasspiv takes is the image files' (util/image_file.h):
// each side at most kMaxImageSidePx pixels and width x height at most
// kMaxImagePixels (2^30). CameraModel and every camera and observation reader
// enforce it, before anything is allocated.

// One side of an image as read from a file: throws InputError (no file, field
// `field`) unless `value` is a whole number in [1, kMaxImageSidePx]. Takes a
// double so that readers check a value before narrowing it to int.
int checked_image_side_px(double value, const std::string& field);
// Both sides (as above, the problem naming "width" or "height") and the pixel
// count against kMaxImagePixels; InputError (no file, field `field`) otherwise.
void check_image_size(double width_px, double height_px, const std::string& field);

enum class UnprojectStatus {
  Ok,
  NonFinite,      // the pixel was NaN or infinite
  NotConverged,   // the iteration did not reach the tolerance (no preimage)
  BeyondFold,     // the only preimage lies past the fold (or past kFoldSearchRadius)
};
const char* to_string(UnprojectStatus status);

struct UnprojectResult {
  UnprojectStatus status = UnprojectStatus::NotConverged;
  Eigen::Vector3d ray_camera = Eigen::Vector3d::Zero();  // unit vector, z > 0, when Ok
  Eigen::Vector2d normalized = Eigen::Vector2d::Zero();  // (X/Z, Y/Z) when Ok
  // d(pixel)/d(normalised) at the solution when Ok (the last Newton Jacobian):
  // ray differentials need it, and it comes for free.
  Eigen::Matrix2d dpixel_dnormalized = Eigen::Matrix2d::Zero();
  int iterations = 0;
  bool ok() const { return status == UnprojectStatus::Ok; }
};

class CameraModel {
 public:
  // Throws InputError (field named, no file) if a value is unusable: sizes not
  // positive or past kMaxImageSidePx / kMaxImagePixels, focal lengths not
  // positive, anything non-finite, or a distortion vector whose length is not
  // 0, 4, 5, 8, 12 or 14.
  CameraModel(int width_px, int height_px, double fx_px, double fy_px, double cx_px, double cy_px,
              std::vector<double> distortion = {});

  int width_px() const { return width_px_; }
  int height_px() const { return height_px_; }
  double fx_px() const { return intrinsics_[0]; }
  double fy_px() const { return intrinsics_[1]; }
  double cx_px() const { return intrinsics_[2]; }
  double cy_px() const { return intrinsics_[3]; }
  LensModel lens_model() const { return lens_model_; }
  int distortion_count() const { return static_cast<int>(lens_model_); }
  // The distortion vector in OpenCV order with the model's length.
  std::vector<double> distortion() const;
  // fx, fy, cx, cy then 14 distortion coefficients (zero beyond the model's length):
  // the parameter block project_point<T> takes.
  const std::array<double, 4 + kMaxDistortionCoefficients>& intrinsics() const { return intrinsics_; }
  Eigen::Matrix3d camera_matrix() const;

  // Pixel of a point in the camera frame (mm or any unit). Returns nullopt if the
  // point is not in front of the camera (z <= 0) or not finite.
  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& point_camera,
                                         Eigen::Matrix<double, 2, 3>* d_pixel_d_point = nullptr) const;
  // Pixel of normalised coordinates (X/Z, Y/Z), with d(pixel)/d(normalised) if asked.
  Eigen::Vector2d project_normalized(const Eigen::Vector2d& normalized,
                                     Eigen::Matrix2d* d_pixel_d_normalized = nullptr) const;

  // The ray through a pixel: damped Newton on the distortion, iterated until the
  // reprojection agrees to `tolerance_px` (far below 1e-6 px by default).
  UnprojectResult unproject(const Eigen::Vector2d& pixel, double tolerance_px = 1e-10) const;
  // unproject for pixels[0..count), out[i] equal to unproject(pixels[i]) to the
  // bit, several pixels interleaved: Newton is a chain of dependent steps whose
  // latency one pixel alone leaves idle (1.3-1.6x the throughput, camera_bench).
  void unproject_batch(const Eigen::Vector2d* pixels, int count, UnprojectResult* out,
                       double tolerance_px = 1e-10) const;
  static constexpr int kUnprojectBatch = 4;
  // unproject_batch with each pixel's Newton iteration started from a nearby
  // pixel already unprojected, near_pixels[i] with result near[i] (its
  // solution moved to pixels[i] by its Jacobian), instead of the undistorted
  // guess: along a row of pixels a step or two fewer. A pixel whose near[i] is
  // not ok, or lies more than kWarmStartMaxPx away, starts from the guess.
  // Converged to the same tolerance as unproject, so the two agree to about
  // tolerance_px, but not to the bit.
  void unproject_batch_near(const Eigen::Vector2d* pixels, int count, const Eigen::Vector2d* near_pixels,
                            const UnprojectResult* near, UnprojectResult* out, double tolerance_px = 1e-10) const;
  static constexpr double kWarmStartMaxPx = 16;

  // Normalised radius below which the distortion is invertible in every
  // direction (the Jacobian stays positive); kFoldSearchRadius when no fold was
  // found within that radius (84 deg off axis, far past any pinhole lens).
  double fold_radius() const { return fold_radius_; }
  static constexpr double kFoldSearchRadius = 10.0;

  // Horizontal, vertical and diagonal field of view in degrees, measured through
  // the real (distorted) model from the image edges.
  struct FieldOfView {
    double horizontal_deg, vertical_deg, diagonal_deg;
  };
  std::optional<FieldOfView> field_of_view() const;

  bool operator==(const CameraModel& other) const;

 private:
  // The first fold along each of kFoldDirections directions from the axis; the
  // invertible region is star-shaped around the axis and bounded by them.
  static constexpr int kFoldDirections = 72;
  void find_fold_radii();
  static constexpr int kMaxUnprojectIterations = 100;
  Eigen::Vector2d project_normalized_inline(const Eigen::Vector2d& normalized,
                                            Eigen::Matrix2d* d_pixel_d_normalized) const;
  // Newton's start: the pixel's normalised coordinates without distortion,
  // close for realistic lenses.
  Eigen::Vector2d undistorted_guess(const Eigen::Vector2d& pixel) const;
  // unproject_batch and unproject_batch_near: Newton from start[i] (nullptr:
  // the undistorted guess).
  void unproject_lanes(const Eigen::Vector2d* pixels, const Eigen::Vector2d* start, int count, UnprojectResult* out,
                       double tolerance_px) const;
  // The result for a converged Newton iterate n with Jacobian j: Ok, or
  // BeyondFold outside the invertible region.
  UnprojectResult converged_result(const Eigen::Vector2d& n, const Eigen::Matrix2d& j, int iterations) const;
  bool inside_invertible_region(const Eigen::Vector2d& normalized) const;

  int width_px_, height_px_;
  LensModel lens_model_;
  std::array<double, 4 + kMaxDistortionCoefficients> intrinsics_{};
  std::array<double, 9> tilt_{};
  bool tilted_ = false;
  bool rational_ = false, prism_ = false;  // any of k4..k6, of s1..s4 non-zero
  std::array<double, kFoldDirections> fold_radius_by_direction_{};
  double fold_radius_ = kFoldSearchRadius;  // min over the directions, with a margin
};

// The same lens and sensor read out with factor x factor pixel binning: size,
// focal lengths and principal point scaled by 1/factor (pixel centres kept:
// cx' = (cx + 1/2) / factor - 1/2), distortion unchanged (it acts on normalised
// coordinates). Previews and quick renders at a fraction of the cost. Width and
// height round down; throws InputError if factor < 1 or the image vanishes.
CameraModel binned(const CameraModel& model, int factor);

}  // namespace glasspiv
