// Isotropic Gaussian prior on a landmark position (PRIOR_LANDMARK):
//
//   r = (l - l0) / sigma.
#ifndef RFF_COSTS_LANDMARK_PRIOR_COST_H_
#define RFF_COSTS_LANDMARK_PRIOR_COST_H_

#include "Eigen/Core"
#include "ceres/sized_cost_function.h"

namespace rff {

class LandmarkPriorCost : public ceres::SizedCostFunction<2, 2> {
 public:
  LandmarkPriorCost(const Eigen::Vector2d& prior, double sigma)
      : prior_(prior), inv_sigma_(1.0 / sigma) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    residuals[0] = (parameters[0][0] - prior_.x()) * inv_sigma_;
    residuals[1] = (parameters[0][1] - prior_.y()) * inv_sigma_;
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      jacobians[0][0] = inv_sigma_;
      jacobians[0][1] = 0.0;
      jacobians[0][2] = 0.0;
      jacobians[0][3] = inv_sigma_;
    }
    return true;
  }

 private:
  Eigen::Vector2d prior_;
  double inv_sigma_;
};

}  // namespace rff

#endif  // RFF_COSTS_LANDMARK_PRIOR_COST_H_
