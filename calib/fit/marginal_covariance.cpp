#include "calib/fit/marginal_covariance.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <utility>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <ceres/crs_matrix.h>

namespace glasspiv {
namespace {

// The rows [row, row + n) of the CRS matrix: the kept columns into jk, the
// columns [column, column + je->cols()) into je (if given).
void gather_rows(const ceres::CRSMatrix& jacobian, int row, int n, int kept_columns, int column, Eigen::MatrixXd* jk,
                 Eigen::MatrixXd* je) {
  for (int r = 0; r < n; ++r)
    for (int k = jacobian.rows[row + r]; k < jacobian.rows[row + r + 1]; ++k) {
      const int c = jacobian.cols[k];
      if (c < kept_columns)
        (*jk)(r, c) = jacobian.values[k];
      else if (je && c >= column && c < column + je->cols())
        (*je)(r, c - column) = jacobian.values[k];
    }
}

// Jk^T Jk - B (Je^T Je)^-1 B^T with B = Jk^T Je; also (Je^T Je)^-1 and
// K = (Je^T Je)^-1 B^T. The common 6-value pose block with a fixed-size
// factorisation.
Eigen::MatrixXd schur_term(const Eigen::MatrixXd& jk, const Eigen::MatrixXd& je, Eigen::MatrixXd* inverse,
                           Eigen::MatrixXd* from_kept) {
  const Eigen::MatrixXd b = jk.transpose() * je;
  if (je.cols() == 6) {
    const Eigen::Matrix<double, 6, 6> ee = je.transpose() * je;
    const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt = ee.ldlt();
    *inverse = ldlt.solve(Eigen::Matrix<double, 6, 6>::Identity());
    *from_kept = ldlt.solve(b.transpose());
  } else {
    const Eigen::MatrixXd ee = je.transpose() * je;
    const Eigen::LDLT<Eigen::MatrixXd> ldlt = ee.ldlt();
    *inverse = ldlt.solve(Eigen::MatrixXd::Identity(ee.rows(), ee.cols()));
    *from_kept = ldlt.solve(b.transpose());
  }
  return jk.transpose() * jk - b * *from_kept;
}

}  // namespace

MarginalCovariance marginal_covariance(const ceres::CRSMatrix& jacobian, int kept_columns,
                                       const std::vector<int>& eliminated_columns,
                                       const std::vector<int>& eliminated_rows, double sigma_px,
                                       double min_reciprocal_condition) {
  MarginalCovariance out;
  const int m = kept_columns;
  const int eliminated_total = std::accumulate(eliminated_columns.begin(), eliminated_columns.end(), 0);
  const int eliminated_row_total = std::accumulate(eliminated_rows.begin(), eliminated_rows.end(), 0);
  if (m <= 0 || eliminated_columns.size() != eliminated_rows.size() ||
      jacobian.num_cols != m + eliminated_total ||
      jacobian.num_rows != static_cast<int>(jacobian.rows.size()) - 1 || eliminated_row_total > jacobian.num_rows)
    return out;

  Eigen::MatrixXd s = Eigen::MatrixXd::Zero(m, m);
  std::vector<Eigen::MatrixXd> eliminated_inverse(eliminated_columns.size()),
      eliminated_from_kept(eliminated_columns.size());
  int row = 0, column = m;
  for (std::size_t b = 0; b < eliminated_columns.size(); ++b) {
    const int n = eliminated_rows[b];
    if (n > 0) {
      Eigen::MatrixXd jk = Eigen::MatrixXd::Zero(n, m), je = Eigen::MatrixXd::Zero(n, eliminated_columns[b]);
      gather_rows(jacobian, row, n, m, column, &jk, &je);
      s += schur_term(jk, je, &eliminated_inverse[b], &eliminated_from_kept[b]);
      row += n;
    }
    column += eliminated_columns[b];
  }
  if (row < jacobian.num_rows) {
    const int n = jacobian.num_rows - row;
    Eigen::MatrixXd jk = Eigen::MatrixXd::Zero(n, m);
    gather_rows(jacobian, row, n, m, column, &jk, nullptr);
    s += jk.transpose() * jk;
  }

  const Eigen::VectorXd d = s.diagonal().cwiseMax(std::numeric_limits<double>::min()).cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd scaled = d.asDiagonal() * s * d.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(scaled);
  const Eigen::VectorXd lambda = eigen.eigenvalues();
  if (!(scaled.allFinite() && lambda.allFinite() && lambda(m - 1) > 0)) return out;
  out.reciprocal_condition = std::max(0.0, lambda(0) / lambda(m - 1));
  int undetermined = 0;
  while (undetermined < m && lambda(undetermined) < min_reciprocal_condition * lambda(m - 1)) ++undetermined;
  out.undetermined = eigen.eigenvectors().leftCols(undetermined);
  Eigen::VectorXd inverse_lambda = lambda.cwiseInverse();
  inverse_lambda.head(undetermined).setZero();
  const Eigen::MatrixXd inverse = eigen.eigenvectors() * inverse_lambda.asDiagonal() * eigen.eigenvectors().transpose();
  out.covariance = sigma_px * sigma_px * d.asDiagonal() * inverse * d.asDiagonal();
  if (!out.covariance.allFinite() || (out.covariance.diagonal().array() < 0).any()) {
    out.covariance.resize(0, 0);
    return out;
  }
  out.eliminated_inverse = std::move(eliminated_inverse);
  out.eliminated_from_kept = std::move(eliminated_from_kept);
  return out;
}

}  // namespace glasspiv
