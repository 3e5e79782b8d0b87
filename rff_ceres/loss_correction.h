// For BandedProblem's own evaluation of residual blocks (banded_problem.cc,
// banded_pose_runs.cc), in place of Ceres's.
#ifndef RFF_CERES_LOSS_CORRECTION_H_
#define RFF_CERES_LOSS_CORRECTION_H_

#include <cmath>

#include "Eigen/Core"
#include "ceres/loss_function.h"

namespace rff {

// A robust loss's correction of one term's residual and Jacobian rows
// (Triggs et al. 2000, 4.3, clamped as Ceres's Corrector clamps it where
// rho'' <= 0), at the residual's squared norm.
struct LossCorrection {
  double cost = 0.0;
  double sqrt_rho1 = 1.0, residual_scaling = 1.0, alpha_over_norm = 0.0;

  LossCorrection(const ceres::LossFunction* loss, double squared_norm) {
    double rho[3] = {squared_norm, 1.0, 0.0};
    if (loss != nullptr) loss->Evaluate(squared_norm, rho);
    cost = 0.5 * rho[0];
    sqrt_rho1 = residual_scaling = std::sqrt(rho[1]);
    if (squared_norm > 0.0 && rho[2] > 0.0) {
      const double alpha =
          1.0 - std::sqrt(1.0 + 2.0 * squared_norm * rho[2] / rho[1]);
      residual_scaling = sqrt_rho1 / (1.0 - alpha);
      alpha_over_norm = alpha / squared_norm;
    }
  }

  // Corrects the row-major rows (residual.size() x cols) of a Jacobian
  // block against the uncorrected residual; false where one is not finite.
  bool CorrectRows(const Eigen::Map<Eigen::VectorXd>& residual, double* data,
                   int cols) const {
    Eigen::Map<
        Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>
        j(data, residual.size(), cols);
    if (!j.allFinite()) return false;
    if (alpha_over_norm != 0.0) {
      const Eigen::RowVectorXd rj = residual.transpose() * j;
      j -= alpha_over_norm * residual * rj;
    }
    j *= sqrt_rho1;
    return true;
  }
};

}  // namespace rff

#endif  // RFF_CERES_LOSS_CORRECTION_H_
