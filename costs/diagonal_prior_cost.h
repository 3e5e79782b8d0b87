// Independent Gaussian priors on the entries of one parameter block (the
// range calibration's scale and offset):
//
//   r_i = (x_i - mu_i) / sigma_i,   dr/dx = diag(1 / sigma).
#ifndef RFF_COSTS_DIAGONAL_PRIOR_COST_H_
#define RFF_COSTS_DIAGONAL_PRIOR_COST_H_

#include <utility>

#include "Eigen/Core"
#include "ceres/cost_function.h"

namespace rff {

class DiagonalPriorCost : public ceres::CostFunction {
 public:
  DiagonalPriorCost(Eigen::VectorXd mean, const Eigen::VectorXd& sigma)
      : mean_(std::move(mean)), inv_sigma_(sigma.cwiseInverse()) {
    set_num_residuals(static_cast<int>(mean_.size()));
    mutable_parameter_block_sizes()->push_back(static_cast<int>(mean_.size()));
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const Eigen::Index n = mean_.size();
    Eigen::Map<Eigen::VectorXd>(residuals, n) =
        (Eigen::Map<const Eigen::VectorXd>(parameters[0], n) - mean_)
            .cwiseProduct(inv_sigma_);
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      Eigen::Map<Eigen::MatrixXd>(jacobians[0], n, n) = inv_sigma_.asDiagonal();
    }
    return true;
  }

 private:
  Eigen::VectorXd mean_;
  Eigen::VectorXd inv_sigma_;
};

}  // namespace rff

#endif  // RFF_COSTS_DIAGONAL_PRIOR_COST_H_
