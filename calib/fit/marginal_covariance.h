#pragma once
// The covariance of some parameters of a least-squares fit with the others
// marginalised, by the Schur complement of the eliminated blocks in J^T J:
//
//   S = sum over eliminated blocks b of (Jk_b^T Jk_b - Jk_b^T Je_b (Je_b^T Je_b)^-1 Je_b^T Jk_b)
//       + Jk_0^T Jk_0  (rows that touch no eliminated block)
//   covariance = sigma^2 S^-1
//
// computed Jacobi-scaled (S -> D S D with D = diag(S)^-1/2) so that the
// condition number compares parameters of any units. Directions whose
// eigenvalue falls below min_reciprocal_condition * lambda_max count as
// undetermined and are left out of the inverse (a pseudo-inverse): a caller
// that cannot accept that must look at `undetermined`.
//
// Used by the intrinsic fit (intrinsics kept, board poses eliminated) and the
// pose fits (everything kept, nothing eliminated). ceres::Covariance gives the
// same matrix on well-scaled problems, but its SuiteSparseQR rank test is not
// scale invariant (it declares long lenses rank deficient and logs to stderr).
#include <vector>

#include <Eigen/Core>

namespace ceres {
struct CRSMatrix;
}

namespace glasspiv {

// Directions of the Jacobi-scaled reduced normal matrix with eigenvalues below
// this fraction of the largest are undetermined.
constexpr double kMinReciprocalCondition = 1e-13;
// The observability checks use max(sigma_px, this): noise-free data must not
// make a degenerate set of observations look determined.
constexpr double kObservabilitySigmaFloorPx = 0.05;

struct MarginalCovariance {
  Eigen::MatrixXd covariance;       // of the kept parameters; empty when S has no positive eigenvalue
  double reciprocal_condition = 0;  // lambda_min / lambda_max of D S D
  Eigen::MatrixXd undetermined;     // unit (scaled) eigenvectors of the undetermined directions
  // Per eliminated block b, what the joint covariance of all parameters needs
  // besides `covariance` (with J^T J = [[A, B], [B^T, C]], C block diagonal):
  // C_b^-1 and K_b = C_b^-1 B_b^T, how block b's best values follow the kept
  // parameters (a shift d of them moves block b by -K_b d). Then, at unit noise,
  //   Cov(kept, block b)    = -S^+ K_b^T
  //   Cov(block b, block c) = delta_bc C_b^-1 + K_b S^+ K_c^T.
  // Empty for a block without rows.
  std::vector<Eigen::MatrixXd> eliminated_inverse;      // C_b^-1, unit noise
  std::vector<Eigen::MatrixXd> eliminated_from_kept;    // K_b (block columns x kept columns)
};

// The Jacobian's layout (a ceres::Problem::Evaluate in the tangent space): the
// first kept_columns columns are the kept parameters, then the eliminated
// blocks one after the other (eliminated_columns[b] columns each). Its rows come
// block by block (eliminated_rows[b] rows touch kept parameters and block b
// only), then the rows that touch kept parameters only.
MarginalCovariance marginal_covariance(const ceres::CRSMatrix& jacobian, int kept_columns,
                                       const std::vector<int>& eliminated_columns,
                                       const std::vector<int>& eliminated_rows, double sigma_px,
                                       double min_reciprocal_condition = kMinReciprocalCondition);

}  // namespace glasspiv
