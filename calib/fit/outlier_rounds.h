#pragma once
// The outlier loop shared by the intrinsic and the pose fits: solve, judge every
// point against the new fit, drop those beyond the threshold and readmit those
// back within it, until a round changes nothing.
//
//   robust sigma = median |r| / sqrt(2 ln 2)     (|r| of 2-D Gaussian noise is
//                                                 Rayleigh: median sigma sqrt(2 ln 2))
//   threshold    = max(outlier_k * robust sigma, kMinOutlierThresholdPx)
//
// Every point is re-tested in every round, so points that only looked bad while
// the outliers still pulled the fit come back.
#include <functional>
#include <vector>

namespace glasspiv {

// At most this many solves (the last round's verdict is then not applied).
constexpr int kMaxOutlierRounds = 10;
// The outlier threshold never goes below this: on noise-free data the residuals
// are round-off, and no corner detector is this precise anyway.
constexpr double kMinOutlierThresholdPx = 0.01;

// A point taking part in the current round.
struct OutlierCandidate {
  double residual_norm_px = 0;  // |r| at the current fit; infinite when it has no image
  bool outlier = false;         // dropped in the previous round
};

struct OutlierVerdict {
  double threshold_px = 0;
  std::vector<bool> outlier;  // per candidate, in their order
  int dropped = 0;            // outliers that were inliers
  int readmitted = 0;         // inliers that were outliers
  bool changed() const { return dropped > 0 || readmitted > 0; }
};

// median |r| / sqrt(2 ln 2) over the norms (infinite ones count as large); 0 if empty.
double robust_sigma_px(std::vector<double> residual_norms_px);

// One round's verdict: a candidate is an outlier unless |r| <= threshold.
OutlierVerdict judge_outliers(const std::vector<OutlierCandidate>& candidates, double outlier_k);

// What the rounds did; the per-round vectors have one entry per verdict.
struct OutlierRoundsLog {
  int rounds = 0;  // solves
  std::vector<int> dropped_per_round, readmitted_per_round;
  std::vector<double> threshold_px_per_round;
};

// The loop. solve() fits the current inliers; candidates() gives the points
// taking part with their residuals at that fit; apply() moves the points whose
// flag changed into or out of the problem (and whatever follows, such as a view
// left with too few points). Stops after a verdict that changes nothing, after
// kMaxOutlierRounds solves, or after the first solve when outlier_k == 0.
OutlierRoundsLog run_outlier_rounds(double outlier_k, const std::function<void(int round)>& solve,
                                    const std::function<std::vector<OutlierCandidate>()>& candidates,
                                    const std::function<void(const OutlierVerdict&)>& apply);

}  // namespace glasspiv
