#pragma once
// Whether a fitted lens model is a lens where it was observed: its projection
// one to one on the disc of the observed corners (undistorted normalised
// radius r_u up to the farthest corner). Beyond them a polynomial model only
// extrapolates, and folds there are common (OpenCV's own fits of its sample
// photos fold near the image corners); inside them a fold means that pixels
// among the observations have several rays. The rational models (opencv8 and
// up) can lower their cost with a pole of the radial factor among the corners,
// where the numerator and the denominator
//   N(s) = 1 + k1 s + k2 s^2 + k3 s^3,  D(s) = 1 + k4 s + k5 s^2 + k6 s^3,
//   s = r_u^2,
// both nearly vanish: a thin ring whose few corners the model bends at will,
// sent to infinity, and a model that cannot be undistorted there.
//
// The radial map r_d(r_u) = r_u N(s) / D(s) is checked exactly (not sampled):
// D > 0 and dr_d/dr_u = P(s) / D(s)^2 > 0 with the polynomial
//   P(s) = (N + 2 s N') D - 2 s N D'   (' = d/ds),
// both minimised over [0, s] at the ends and at the real parts of their
// derivatives' roots (a pole-zero pair can be narrower than any grid: mrcal's
// minimum of OpenCV's right*.jpg corners has D < 0 on r_u in [0.3737, 0.3754]).
// The full map (tangential, thin prism, tilt) is then sampled: the Jacobian
// determinant of (x_u, y_u) -> (x_d, y_d) must stay positive on that disc.
// See docs/intrinsic_fit.md, "One to one where observed".
#include <string>
#include <vector>

#include "calib/camera_model.h"
#include "calib/observations.h"
#include "calib/rigid_transform.h"

namespace glasspiv {

struct LensValidity {
  bool one_to_one = true;
  std::string why;            // empty when one_to_one: where the map folds or meets a pole
  double radius_checked = 0;  // r_u of the disc checked
  // Where the radial map first folds back or meets a pole, wherever that is
  // (CameraModel::kFoldSearchRadius when nowhere within 84 deg off axis).
  double fold_radius = CameraModel::kFoldSearchRadius;
  // Over [0, min(radius_checked, fold_radius)]:
  double min_denominator = 1;   // D(s); 1 without a rational denominator
  double min_radial_slope = 1;  // dr_d/dr_u
};

// The check on the disc r_u <= radius (normalised undistorted coordinates).
LensValidity check_one_to_one(const CameraModel& camera, double radius);

// The largest undistorted normalised radius |(X/Z, Y/Z)| of the corners in
// `observations` placed by `camera_from_board` (one pose per view; views
// without corners ignored, points behind the camera too).
double observed_undistorted_radius(const Observations& observations,
                                   const std::vector<RigidTransform>& camera_from_board);

}  // namespace glasspiv
