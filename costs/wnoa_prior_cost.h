// Motion prior between two consecutive WNOA states (white noise on
// acceleration, Barfoot et al. 2014), states gamma = (p_x, p_y, p_theta,
// v_x, v_y, v_theta):
//
//   e_c = [p_c' - p_c - dt v_c;  v_c' - v_c]   per coordinate c,
//   Q_c(dt) = qc [dt^3/3 dt^2/2; dt^2/2 dt],   r_c = S_c e_c,
//   S_c = L_c^-1 (L_c L_c^T = Q_c)
//       = qc^-1/2 [sqrt(3) / dt^{3/2}  0;  -3 / dt^{3/2}  2 / dt^{1/2}],
//
// so S_c^T S_c = Q_c^-1 = qc^-1 [12/dt^3 -6/dt^2; -6/dt^2 4/dt]. The closed
// form stays accurate for tiny dt, where inverting Q_c numerically would not.
// Residual layout follows the state: (r_px, r_py, r_ptheta, r_vx, r_vy,
// r_vtheta). Blocks: gamma_i (previous), gamma_{i+1} (next).
#ifndef RFF_COSTS_WNOA_PRIOR_COST_H_
#define RFF_COSTS_WNOA_PRIOR_COST_H_

#include <cmath>

#include "Eigen/Core"
#include "ceres/sized_cost_function.h"

namespace rff {

class WnoaPriorCost : public ceres::SizedCostFunction<6, 6, 6> {
 public:
  using Matrix6 = Eigen::Matrix<double, 6, 6, Eigen::RowMajor>;

  // `dt` > 0 seconds; `qc_*` > 0 the power spectral densities per coordinate.
  WnoaPriorCost(double dt, double qc_x, double qc_y, double qc_theta)
      : dt_(dt) {
    SetQc(qc_x, qc_y, qc_theta);
  }

  // The cost the constructor builds with these densities (a learning
  // round's rescale, in place).
  void SetQc(double qc_x, double qc_y, double qc_theta) {
    const double dt = dt_;
    const double qc[3] = {qc_x, qc_y, qc_theta};
    const double inv_dt_sqrt = 1.0 / std::sqrt(dt);
    const double inv_dt_3_2 = inv_dt_sqrt / dt;
    sqrt_information_.setZero();
    for (int c = 0; c < 3; ++c) {
      const double scale = 1.0 / std::sqrt(qc[c]);
      sqrt_information_(c, c) = scale * std::sqrt(3.0) * inv_dt_3_2;
      sqrt_information_(c + 3, c) = -scale * 3.0 * inv_dt_3_2;
      sqrt_information_(c + 3, c + 3) = scale * 2.0 * inv_dt_sqrt;
    }
    // d e / d gamma_i = -Phi, so d r / d gamma_i = -S Phi.
    Matrix6 phi = Matrix6::Identity();
    for (int c = 0; c < 3; ++c) phi(c, c + 3) = dt;
    previous_jacobian_ = -sqrt_information_ * phi;
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    using Vector6 = Eigen::Matrix<double, 6, 1>;
    const Eigen::Map<const Vector6> previous(parameters[0]);
    const Eigen::Map<const Vector6> next(parameters[1]);
    Vector6 error = next - previous;
    error.head<3>() -= dt_ * previous.tail<3>();
    Eigen::Map<Vector6> r(residuals);
    r = sqrt_information_ * error;
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      Eigen::Map<Matrix6> jacobian(jacobians[0]);
      jacobian = previous_jacobian_;
    }
    if (jacobians != nullptr && jacobians[1] != nullptr) {
      Eigen::Map<Matrix6> jacobian(jacobians[1]);
      jacobian = sqrt_information_;
    }
    return true;
  }

  double dt() const { return dt_; }
  // S with S^T S = Q_i^-1 (block diagonal per coordinate, in state layout).
  const Matrix6& sqrt_information() const { return sqrt_information_; }

 private:
  double dt_;
  Matrix6 sqrt_information_;
  Matrix6 previous_jacobian_;
};

}  // namespace rff

#endif  // RFF_COSTS_WNOA_PRIOR_COST_H_
