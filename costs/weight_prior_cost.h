// Whitened prior on a block of feature weights, b ~ N(0, I) (paper eq. 4):
//
//   r = b,   dr/db = I.
//
// The kernel's variance and spectrum live in the features, so the prior on
// the weights is the standard normal whatever the kernel.
#ifndef RFF_COSTS_WEIGHT_PRIOR_COST_H_
#define RFF_COSTS_WEIGHT_PRIOR_COST_H_

#include "Eigen/Core"
#include "ceres/cost_function.h"

namespace rff {

class WeightPriorCost : public ceres::CostFunction {
 public:
  explicit WeightPriorCost(int num_weights) {
    set_num_residuals(num_weights);
    mutable_parameter_block_sizes()->push_back(num_weights);
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const int n = num_residuals();
    Eigen::Map<Eigen::VectorXd>(residuals, n) =
        Eigen::Map<const Eigen::VectorXd>(parameters[0], n);
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      Eigen::Map<Eigen::MatrixXd>(jacobians[0], n, n).setIdentity();
    }
    return true;
  }
};

}  // namespace rff

#endif  // RFF_COSTS_WEIGHT_PRIOR_COST_H_
