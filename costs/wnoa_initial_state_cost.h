// Prior on the first WNOA state's deviation from the mean, gamma_0 ~
// N(0, diag(sigma^2)), whitened:
//
//   r_j = gamma_j / sigma_j,   dr/dgamma = diag(1 / sigma).
//
// State layout (p_x, p_y, p_theta, v_x, v_y, v_theta).
#ifndef RFF_COSTS_WNOA_INITIAL_STATE_COST_H_
#define RFF_COSTS_WNOA_INITIAL_STATE_COST_H_

#include "Eigen/Core"
#include "ceres/sized_cost_function.h"

namespace rff {

class WnoaInitialStateCost : public ceres::SizedCostFunction<6, 6> {
 public:
  using Vector6 = Eigen::Matrix<double, 6, 1>;

  // `sigma`: standard deviations, all > 0.
  explicit WnoaInitialStateCost(const Vector6& sigma)
      : inv_sigma_(sigma.cwiseInverse()) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    Eigen::Map<Vector6> r(residuals);
    r = inv_sigma_.cwiseProduct(Eigen::Map<const Vector6>(parameters[0]));
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      Eigen::Map<Eigen::Matrix<double, 6, 6, Eigen::RowMajor>> jacobian(
          jacobians[0]);
      jacobian = inv_sigma_.asDiagonal();
    }
    return true;
  }

 private:
  Vector6 inv_sigma_;
};

}  // namespace rff

#endif  // RFF_COSTS_WNOA_INITIAL_STATE_COST_H_
