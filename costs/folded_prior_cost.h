// A quadratic in several parameter blocks x = (x_1, ..., x_m), stacked:
//
//   q(x) = 1/2 x^T H x - b^T x + k,   H = V diag(lambda) V^T (lambda > 0),
//
// as residuals r = [diag(sqrt(lambda)) V^T x - diag(1 / sqrt(lambda)) V^T b;
// sqrt(2 k - b^T H^+ b)], so 1/2 |r|^2 = q(x) where b lies in H's range, and
// dr/dx_j = diag(sqrt(lambda)) V^T restricted to block j's columns. The
// Gauss-Newton quadratic of residuals folded away by a fixed-lag smoother
// (FoldedPrior), in the blocks they still move.
#ifndef RFF_COSTS_FOLDED_PRIOR_COST_H_
#define RFF_COSTS_FOLDED_PRIOR_COST_H_

#include <cmath>
#include <utility>
#include <vector>

#include "Eigen/Core"
#include "ceres/cost_function.h"

namespace rff {

class FoldedPriorCost : public ceres::CostFunction {
 public:
  // `sqrt_information` (rows x n) = diag(sqrt(lambda)) V^T, `offset` (rows)
  // = diag(1 / sqrt(lambda)) V^T b, `constant` = sqrt(2 k - b^T H^+ b) >= 0;
  // `block_sizes` sum to n.
  FoldedPriorCost(Eigen::MatrixXd sqrt_information, Eigen::VectorXd offset,
                  double constant, const std::vector<int>& block_sizes)
      : sqrt_information_(std::move(sqrt_information)),
        offset_(std::move(offset)),
        constant_(constant) {
    set_num_residuals(static_cast<int>(offset_.size()) + 1);
    *mutable_parameter_block_sizes() = block_sizes;
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const Eigen::Index rows = offset_.size();
    Eigen::Map<Eigen::VectorXd> r(residuals, rows + 1);
    r.head(rows) = -offset_;
    const std::vector<int>& sizes = parameter_block_sizes();
    Eigen::Index column = 0;
    for (std::size_t j = 0; j < sizes.size(); ++j) {
      const auto a = sqrt_information_.middleCols(column, sizes[j]);
      r.head(rows) +=
          a * Eigen::Map<const Eigen::VectorXd>(parameters[j], sizes[j]);
      if (jacobians != nullptr && jacobians[j] != nullptr) {
        Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic,
                                 Eigen::RowMajor>>
            jacobian(jacobians[j], rows + 1, sizes[j]);
        jacobian.topRows(rows) = a;
        jacobian.row(rows).setZero();
      }
      column += sizes[j];
    }
    r[rows] = constant_;
    return true;
  }

 private:
  Eigen::MatrixXd sqrt_information_;
  Eigen::VectorXd offset_;
  double constant_;
};

}  // namespace rff

#endif  // RFF_COSTS_FOLDED_PRIOR_COST_H_
