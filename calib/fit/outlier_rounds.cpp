#include "calib/fit/outlier_rounds.h"

#include <algorithm>
#include <cmath>

namespace glasspiv {

double robust_sigma_px(std::vector<double> residual_norms_px) {
  if (residual_norms_px.empty()) return 0;
  const auto middle = residual_norms_px.begin() + residual_norms_px.size() / 2;
  std::nth_element(residual_norms_px.begin(), middle, residual_norms_px.end());
  return *middle / std::sqrt(2 * std::log(2.0));
}

OutlierVerdict judge_outliers(const std::vector<OutlierCandidate>& candidates, double outlier_k) {
  std::vector<double> norms;
  norms.reserve(candidates.size());
  for (const OutlierCandidate& c : candidates) norms.push_back(c.residual_norm_px);
  OutlierVerdict verdict;
  verdict.threshold_px = std::max(outlier_k * robust_sigma_px(std::move(norms)), kMinOutlierThresholdPx);
  verdict.outlier.reserve(candidates.size());
  for (const OutlierCandidate& c : candidates) {
    const bool outlier = !(c.residual_norm_px <= verdict.threshold_px);  // NaN counts as an outlier
    verdict.dropped += outlier && !c.outlier;
    verdict.readmitted += !outlier && c.outlier;
    verdict.outlier.push_back(outlier);
  }
  return verdict;
}

OutlierRoundsLog run_outlier_rounds(double outlier_k, const std::function<void(int round)>& solve,
                                    const std::function<std::vector<OutlierCandidate>()>& candidates,
                                    const std::function<void(const OutlierVerdict&)>& apply) {
  OutlierRoundsLog log;
  for (int round = 0;; ++round) {
    solve(round);
    log.rounds = round + 1;
    if (outlier_k == 0 || round + 1 >= kMaxOutlierRounds) break;
    const OutlierVerdict verdict = judge_outliers(candidates(), outlier_k);
    log.dropped_per_round.push_back(verdict.dropped);
    log.readmitted_per_round.push_back(verdict.readmitted);
    log.threshold_px_per_round.push_back(verdict.threshold_px);
    apply(verdict);
    if (!verdict.changed()) break;
  }
  return log;
}

}  // namespace glasspiv
