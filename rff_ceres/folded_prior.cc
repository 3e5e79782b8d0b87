#include "rff_ceres/folded_prior.h"

#include <algorithm>
#include <cmath>

#include "Eigen/Eigenvalues"

namespace rff {

void FoldedPrior::Add(const std::vector<double*>& blocks,
                      const std::vector<int32_t>& sizes,
                      const std::vector<double*>& jacobians,
                      const double* residual, int rows, double cost) {
  // New blocks join the quadratic at their current values.
  for (std::size_t j = 0; j < blocks.size(); ++j) {
    if (jacobians[j] == nullptr || column_.count(blocks[j]) > 0) continue;
    const Eigen::Index n = reference_.size();
    column_[blocks[j]] = static_cast<int>(n);
    blocks_.push_back(blocks[j]);
    sizes_.push_back(sizes[j]);
    reference_.conservativeResize(n + sizes[j]);
    reference_.tail(sizes[j]) =
        Eigen::Map<const Eigen::VectorXd>(blocks[j], sizes[j]);
    hessian_.conservativeResize(n + sizes[j], n + sizes[j]);
    hessian_.rightCols(sizes[j]).setZero();
    hessian_.bottomRows(sizes[j]).setZero();
    linear_.conservativeResize(n + sizes[j]);
    linear_.tail(sizes[j]).setZero();
  }
  // J (rows x n) in the quadratic's columns, and d_i = x_i - x_ref.
  const Eigen::Index n = reference_.size();
  Eigen::MatrixXd jacobian = Eigen::MatrixXd::Zero(rows, n);
  Eigen::VectorXd at = Eigen::VectorXd::Zero(n);
  for (std::size_t j = 0; j < blocks.size(); ++j) {
    if (jacobians[j] == nullptr) continue;
    const int column = column_.at(blocks[j]);
    jacobian.middleCols(column, sizes[j]) =
        Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic,
                                       Eigen::RowMajor>>(jacobians[j], rows,
                                                         sizes[j]);
    at.segment(column, sizes[j]) =
        Eigen::Map<const Eigen::VectorXd>(blocks[j], sizes[j]) -
        reference_.segment(column, sizes[j]);
  }
  const Eigen::Map<const Eigen::VectorXd> r(residual, rows);
  const Eigen::VectorXd gradient = jacobian.transpose() * r;
  const Eigen::MatrixXd information = jacobian.transpose() * jacobian;
  // c + g^T (d - d_i) + 1/2 (d - d_i)^T A (d - d_i), expanded in d.
  hessian_ += information;
  const Eigen::VectorXd information_at = information * at;
  linear_ += information_at - gradient;
  constant_ += cost - gradient.dot(at) + 0.5 * at.dot(information_at);
  ++num_folded_;
}

std::unique_ptr<FoldedPriorCost> FoldedPrior::MakeCost() const {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(hessian_);
  const Eigen::VectorXd& lambda = eigen.eigenvalues();  // Ascending.
  const double floor = 1e-12 * std::max(lambda.maxCoeff(), 0.0);
  Eigen::Index first = 0;
  while (first < lambda.size() && !(lambda[first] > floor)) ++first;
  const Eigen::Index rows = lambda.size() - first;
  const Eigen::VectorXd root = lambda.tail(rows).cwiseSqrt();
  const Eigen::MatrixXd directions =
      eigen.eigenvectors().rightCols(rows).transpose();  // V^T.
  const Eigen::MatrixXd sqrt_information = root.asDiagonal() * directions;
  const Eigen::VectorXd offset =
      root.cwiseInverse().asDiagonal() * (directions * linear_);
  // 1/2 |A d - offset|^2 = 1/2 d^T H d - b^T d + 1/2 |offset|^2: the rest of
  // k is the constant row (never negative but by rounding).
  const double rest = std::max(0.0, 2.0 * constant_ - offset.squaredNorm());
  return std::make_unique<FoldedPriorCost>(
      sqrt_information, offset + sqrt_information * reference_, std::sqrt(rest),
      sizes_);
}

}  // namespace rff
