#pragma once
// Staged and multi-start intrinsic fits for the rich lens models (opencv8,
// opencv12, opencv14). Their rational denominator nearly trades off against the
// numerator, and the least-squares cost has several minima along that valley:
// fit_intrinsics' staged solve (k1 k2 p1 p2 k3 first, then all) stops where
// cv::calibrateCamera stops, mrcal's regularised passes often find a lower one.
// Several starts are solved on the same corners and the lowest cost is kept:
//
//   staged              fit_intrinsics as it is (the caller's options);
//   regularised         from the opencv5 fit, a pass with mrcal's
//                       regularisation (a small quadratic penalty on the
//                       distortion coefficients and on the principal point's
//                       distance from the image centre), then released: the
//                       plain least-squares fit from there;
//   regularised from pinhole
//                       mrcal's own route: the pinhole fit, the same
//                       regularised pass from zero distortion, released;
//   from opencv5        the opencv5 fit, released with every coefficient
//                       free at once (no staging);
//   valley step +-t     seeded steps of random length t (1 to 50, in units
//                       that move the largest coefficient by 1) from the best
//                       minimum so far along the flattest direction of the
//                       cost (the smallest eigenvector of the reduced normal
//                       matrix, the poses following to first order: the
//                       numerator-denominator trade), released.
//
// Every start ends in an unregularised fit_intrinsics on the inlier corners
// of the staged fit, so the costs compare. A start whose minimum is not one to
// one where the corners are (calib/fit/lens_validity.h: the map folds or meets
// a pole of the rational factor inside the farthest observed corner's radius)
// is refused, whatever its cost; a one-to-one start beats a staged fit that is
// not. Without outliers the winner's fit
// is the result; otherwise the winner is refitted with the caller's options
// (outlier loop) on all corners, and kept if it ends below the staged fit.
// See docs/intrinsic_fit.md, "Multi-start fits for rich models".
#include <string>
#include <utility>
#include <vector>

#include "calib/camera_model.h"
#include "calib/fit/intrinsic_fit.h"
#include "calib/fit/lens_validity.h"
#include "calib/observations.h"

namespace glasspiv {

struct MultiStartOptions {
  // Multiplies mrcal's regularisation weights in the regularised passes (1:
  // mrcal 2.2's); 0 leaves the regularised starts out. Must be finite, >= 0.
  double regularisation_scale = 1.0;
  int perturbed_starts = 3;        // valley steps, >= 0
  unsigned perturbation_seed = 1;  // their lengths are reproducible
  // Refuse minima that are not one to one where the corners are (false: the
  // lowest cost wins, as in mrcal and cv::calibrateCamera).
  bool require_one_to_one = true;
};

struct FitStart {
  std::string name;   // "staged", "from opencv5", "regularised", "regularised from pinhole", "valley step +12.3"
  bool ok = false;    // false: the start's fit failed or was refused (`failure` says why)
  std::string failure;
  double rms_px = 0;  // of its released fit over the staged fit's inlier corners (refused ones too)
  double seconds = 0;
  // Of its released fit: a start that is not one to one is refused (ok false)
  // when MultiStartOptions::require_one_to_one; the staged fit stays the
  // fallback, flagged here only.
  LensValidity validity;
};

struct MultiStartFit {
  explicit MultiStartFit(IntrinsicFit final_fit) : fit(std::move(final_fit)) {}
  // The winner refitted with the caller's options on all corners (the staged
  // fit itself when it wins).
  IntrinsicFit fit;
  std::vector<FitStart> starts;  // in the order tried; starts[0] is "staged"
  int winner = 0;                // index into starts
  double total_time_s = 0;
};

// Models with more than the five coefficients of opencv5.
bool is_rich_lens_model(LensModel model);

// The multi-start for rich models; for the others fit_intrinsics alone (one
// start, "staged"). Throws what fit_intrinsics throws for the staged start;
// other starts that fail are reported in `starts`, not thrown.
MultiStartFit fit_intrinsics_multi_start(const Observations& observations, const IntrinsicFitOptions& options,
                                         const MultiStartOptions& multi = {});

// mrcal 2.2's regularisation (mrcal.c, mrcal_optimize): with N the pixel
// measurements (2 per corner), each distortion coefficient k_j adds the
// residual w_d k_j (5 w_d for the rational denominator k4 k5 k6), and cx, cy
// add w_c (c - centre), centre = ((w - 1) / 2, (h - 1) / 2), with
//   w_d^2 = 0.0025 N / (n_d 2^2),  w_c^2 = 0.0025 N / (2 * 500^2)
// (n_d distortion coefficients): expected to be 0.5 % of the cost at 1 px of
// noise. `scale` multiplies both weights.
struct RegularisationWeights {
  double distortion = 0;   // w_d
  double denominator = 0;  // w_d for k4 k5 k6 (5 w_d)
  double centre = 0;       // w_c, 1/px
};
RegularisationWeights mrcal_regularisation_weights(LensModel model, int corner_count, double scale = 1.0);

// The regularised least-squares fit from `start` (intrinsics of any model, its
// coefficients seed the first ones of options.lens_model) and its board poses
// (`start_camera_from_board`, one per view, as IntrinsicFit gives them; views
// without corners are ignored). Held parameters as in `options`
// (fix_aspect_ratio takes the start's fy / fx). No outlier loop. Returns the
// regularised camera; throws InputError (field "views") if the solve fails.
CameraModel fit_regularised(const Observations& observations, const IntrinsicFitOptions& options,
                            const CameraModel& start, const std::vector<RigidTransform>& start_camera_from_board,
                            double scale = 1.0);

}  // namespace glasspiv
