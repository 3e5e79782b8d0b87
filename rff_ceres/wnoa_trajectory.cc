#include "rff_ceres/wnoa_trajectory.h"

#include <algorithm>
#include <cmath>

#include "costs/wnoa_initial_state_cost.h"
#include "costs/wnoa_prior_cost.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/option_error.h"

namespace rff {

std::unique_ptr<WnoaTrajectory> WnoaTrajectory::Create(
    const WnoaOptions& options, std::shared_ptr<const MeanFunction> mean,
    std::vector<double> state_times, std::string* error) {
  std::vector<double> times;
  if (!CheckPositiveOption(options.position_qc, "wnoa_position_qc", error) ||
      !CheckPositiveOption(options.heading_qc, "wnoa_heading_qc", error) ||
      !CheckPositiveOption(options.initial_position_sigma,
                           "wnoa_initial_position_sigma", error) ||
      !CheckPositiveOption(options.initial_heading_sigma,
                           "wnoa_initial_heading_sigma", error) ||
      !CheckPositiveOption(options.initial_velocity_sigma,
                           "wnoa_initial_velocity_sigma", error) ||
      !CheckPositiveOption(options.initial_angular_velocity_sigma,
                           "wnoa_initial_angular_velocity_sigma", error) ||
      !CheckNonNegativeOption(options.min_state_spacing,
                              "wnoa_min_state_spacing", error) ||
      !ThinStateTimes("wnoa", mean.get(), std::move(state_times),
                      options.min_state_spacing, &times, error)) {
    return nullptr;
  }
  return std::unique_ptr<WnoaTrajectory>(
      new WnoaTrajectory(options, std::move(mean), std::move(times)));
}

std::vector<double> WnoaTrajectory::SmoothestVelocities(
    const std::vector<double>& times, const std::vector<double>& positions) {
  return SmoothestChain(
      static_cast<int>(times.size()),
      [&](int k, Eigen::Matrix2d* h, Eigen::Vector2d* g) {
        const double dt = times[k + 1] - times[k];
        const double d = positions[k + 1] - positions[k];
        // e = (d - dt v_k, v_k+1 - v_k); Q^-1 = [12/dt^3 -6/dt^2; -6/dt^2
        // 4/dt]; e = r0 + J (v_k, v_k+1) with r0 = (d, 0), J = [-dt 0; -1 1].
        const double a = 12.0 / (dt * dt * dt), b = -6.0 / (dt * dt),
                     c = 4.0 / dt;
        const Eigen::Matrix2d q_inverse =
            (Eigen::Matrix2d() << a, b, b, c).finished();
        const Eigen::Matrix2d jacobian =
            (Eigen::Matrix2d() << -dt, 0.0, -1.0, 1.0).finished();
        *h = jacobian.transpose() * q_inverse * jacobian;
        *g = jacobian.transpose() * q_inverse * Eigen::Vector2d(d, 0.0);
      });
}

void WnoaTrajectory::SetSmoothestDerivatives(
    int c, const std::vector<double>& positions) {
  const std::vector<double> velocity = SmoothestVelocities(times_, positions);
  for (int i = 0; i < num_blocks(); ++i) mutable_block(i)[3 + c] = velocity[i];
}

void WnoaTrajectory::InterpolationMatrices(double elapsed, double dt,
                                           Eigen::Matrix2d* lambda,
                                           Eigen::Matrix2d* psi) {
  // Psi = Q_tau Phi(t_{i+1}, tau)^T Q_i^-1 and Lambda = Phi(tau, t_i) -
  // Psi Phi(dt) multiplied out: the cubic Hermite basis, with no inverse of
  // the ill-conditioned Q_i.
  const double s = elapsed / dt;
  const double r = 1.0 - s;
  const double h01 = s * s * (3.0 - 2.0 * s);
  *lambda << 1.0 - h01, elapsed * r * r, -6.0 * s * r / dt, r * (1.0 - 3.0 * s);
  *psi << h01, -elapsed * s * r, 6.0 * s * r / dt, s * (3.0 * s - 2.0);
}

void WnoaTrajectory::PositionRows(double elapsed, double dt, double* lambda,
                                  double* psi) const {
  Eigen::Matrix2d lambda_matrix, psi_matrix;
  InterpolationMatrices(elapsed, dt, &lambda_matrix, &psi_matrix);
  for (int j = 0; j < 2; ++j) {
    lambda[j] = lambda_matrix(0, j);
    psi[j] = psi_matrix(0, j);
  }
}

bool WnoaTrajectory::TakeScales(const StateTrajectory& rescaled) {
  const WnoaOptions& o = static_cast<const WnoaTrajectory&>(rescaled).options_;
  if (o.initial_position_sigma != options_.initial_position_sigma ||
      o.initial_heading_sigma != options_.initial_heading_sigma ||
      o.initial_velocity_sigma != options_.initial_velocity_sigma ||
      o.initial_angular_velocity_sigma !=
          options_.initial_angular_velocity_sigma ||
      o.min_state_spacing != options_.min_state_spacing) {
    return false;
  }
  options_.position_qc = o.position_qc;
  options_.heading_qc = o.heading_qc;
  return true;
}

void WnoaTrajectory::SetMotionQc(ceres::CostFunction* cost) const {
  if (auto* motion = dynamic_cast<WnoaPriorCost*>(cost)) {
    motion->SetQc(options_.position_qc, options_.position_qc,
                  options_.heading_qc);
  }
}

Eigen::VectorXd WnoaTrajectory::InitialStateSigmas(const WnoaOptions& o) {
  Eigen::VectorXd sigma(kStateSize);
  sigma << o.initial_position_sigma, o.initial_position_sigma,
      o.initial_heading_sigma, o.initial_velocity_sigma,
      o.initial_velocity_sigma, o.initial_angular_velocity_sigma;
  return sigma;
}

Eigen::VectorXd WnoaTrajectory::InitialStateSigmas() const {
  return InitialStateSigmas(options_);
}

ceres::CostFunction* WnoaTrajectory::NewInitialStateCost() const {
  return new WnoaInitialStateCost(InitialStateSigmas());
}

double WnoaTrajectory::MotionLogDet(double dt) const {
  // det S_c = sqrt(3) / dt^3/2 * 2 / dt^1/2 per coordinate (wnoa_prior_cost.h).
  return 3.0 * (std::log(2.0 * std::sqrt(3.0)) - 2.0 * std::log(dt));
}

ceres::CostFunction* WnoaTrajectory::NewMotionCost(double dt) const {
  return new WnoaPriorCost(dt, options_.position_qc, options_.position_qc,
                           options_.heading_qc);
}

}  // namespace rff
