// Motion prior between two consecutive WNOJ states (white noise on jerk, a
// constant-acceleration prior; Tang et al. 2019), states gamma = (p_x, p_y,
// p_theta, v_x, v_y, v_theta, a_x, a_y, a_theta):
//
//   e_c = [p_c' - p_c - dt v_c - dt^2/2 a_c;  v_c' - v_c - dt a_c;  a_c' -
//   a_c], Q_c(dt) = qc [dt^5/20 dt^4/8 dt^3/6; dt^4/8 dt^3/3 dt^2/2;
//                 dt^3/6 dt^2/2 dt],   r_c = S_c e_c,
//   S_c = L_c^-1 (L_c L_c^T = Q_c) = qc^-1/2 M D^-1,
//   D = diag(dt^5/2, dt^3/2, dt^1/2),
//   M = [2 sqrt(5) 0 0; -10 sqrt(3) 4 sqrt(3) 0; 20 -12 3],
//
// M the inverse Cholesky factor of Q at dt = 1, so S_c^T S_c = Q_c^-1 =
// qc^-1 [720/dt^5 -360/dt^4 60/dt^3; -360/dt^4 192/dt^3 -36/dt^2;
// 60/dt^3 -36/dt^2 9/dt]. The closed form stays accurate for tiny dt.
// Residual layout follows the state. Blocks: gamma_i, gamma_{i+1}.
#ifndef RFF_COSTS_WNOJ_PRIOR_COST_H_
#define RFF_COSTS_WNOJ_PRIOR_COST_H_

#include <cmath>

#include "Eigen/Core"
#include "ceres/sized_cost_function.h"

namespace rff {

class WnojPriorCost : public ceres::SizedCostFunction<9, 9, 9> {
 public:
  using Matrix9 = Eigen::Matrix<double, 9, 9, Eigen::RowMajor>;
  using Vector9 = Eigen::Matrix<double, 9, 1>;

  // `dt` > 0 seconds; `qc_*` > 0 the power spectral densities per coordinate.
  WnojPriorCost(double dt, double qc_x, double qc_y, double qc_theta)
      : dt_(dt) {
    SetQc(qc_x, qc_y, qc_theta);
  }

  // One coordinate's S_c = qc^-1/2 M D^-1, acting on (p, v, a).
  static Eigen::Matrix3d CoordinateSqrtInformation(double dt, double qc) {
    const double sqrt_dt = std::sqrt(dt);
    // D^-1 = diag(dt^-5/2, dt^-3/2, dt^-1/2).
    const double inv_d[3] = {1.0 / (dt * dt * sqrt_dt), 1.0 / (dt * sqrt_dt),
                             1.0 / sqrt_dt};
    const double m[3][3] = {{2.0 * std::sqrt(5.0), 0.0, 0.0},
                            {-10.0 * std::sqrt(3.0), 4.0 * std::sqrt(3.0), 0.0},
                            {20.0, -12.0, 3.0}};
    const double scale = 1.0 / std::sqrt(qc);
    Eigen::Matrix3d s = Eigen::Matrix3d::Zero();
    for (int row = 0; row < 3; ++row) {
      for (int col = 0; col <= row; ++col) {
        s(row, col) = scale * m[row][col] * inv_d[col];
      }
    }
    return s;
  }

  // The cost the constructor builds with these densities (a learning
  // round's rescale, in place).
  void SetQc(double qc_x, double qc_y, double qc_theta) {
    const double qc[3] = {qc_x, qc_y, qc_theta};
    sqrt_information_.setZero();
    for (int c = 0; c < 3; ++c) {
      const Eigen::Matrix3d s = CoordinateSqrtInformation(dt_, qc[c]);
      for (int row = 0; row < 3; ++row) {
        for (int col = 0; col <= row; ++col) {
          sqrt_information_(c + 3 * row, c + 3 * col) = s(row, col);
        }
      }
    }
    // d e / d gamma_i = -Phi, so d r / d gamma_i = -S Phi.
    Matrix9 phi = Matrix9::Identity();
    for (int c = 0; c < 3; ++c) {
      phi(c, c + 3) = dt_;
      phi(c, c + 6) = 0.5 * dt_ * dt_;
      phi(c + 3, c + 6) = dt_;
    }
    previous_jacobian_ = -sqrt_information_ * phi;
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const Eigen::Map<const Vector9> previous(parameters[0]);
    const Eigen::Map<const Vector9> next(parameters[1]);
    Vector9 error = next - previous;
    error.head<3>() -=
        dt_ * previous.segment<3>(3) + (0.5 * dt_ * dt_) * previous.tail<3>();
    error.segment<3>(3) -= dt_ * previous.tail<3>();
    Eigen::Map<Vector9> r(residuals);
    r = sqrt_information_ * error;
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      Eigen::Map<Matrix9> jacobian(jacobians[0]);
      jacobian = previous_jacobian_;
    }
    if (jacobians != nullptr && jacobians[1] != nullptr) {
      Eigen::Map<Matrix9> jacobian(jacobians[1]);
      jacobian = sqrt_information_;
    }
    return true;
  }

  double dt() const { return dt_; }
  // S with S^T S = Q_i^-1 (block lower triangular per coordinate).
  const Matrix9& sqrt_information() const { return sqrt_information_; }

 private:
  double dt_;
  Matrix9 sqrt_information_;
  Matrix9 previous_jacobian_;
};

}  // namespace rff

#endif  // RFF_COSTS_WNOJ_PRIOR_COST_H_
