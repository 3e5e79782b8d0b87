#include "rff_ceres/wnoj_trajectory.h"

#include <algorithm>
#include <cmath>

#include "Eigen/Core"
#include "costs/diagonal_prior_cost.h"
#include "costs/wnoj_prior_cost.h"
#include "rff_ceres/option_error.h"

namespace rff {

std::unique_ptr<WnojTrajectory> WnojTrajectory::Create(
    const WnojOptions& options, const WnoaOptions& states,
    std::shared_ptr<const MeanFunction> mean, std::vector<double> state_times,
    std::string* error) {
  std::vector<double> times;
  if (!CheckPositiveOption(options.position_qc, "wnoj_position_qc", error) ||
      !CheckPositiveOption(options.heading_qc, "wnoj_heading_qc", error) ||
      !CheckPositiveOption(options.initial_acceleration_sigma,
                           "wnoj_initial_acceleration_sigma", error) ||
      !CheckPositiveOption(options.initial_angular_acceleration_sigma,
                           "wnoj_initial_angular_acceleration_sigma", error) ||
      !CheckPositiveOption(states.initial_position_sigma,
                           "wnoa_initial_position_sigma", error) ||
      !CheckPositiveOption(states.initial_heading_sigma,
                           "wnoa_initial_heading_sigma", error) ||
      !CheckPositiveOption(states.initial_velocity_sigma,
                           "wnoa_initial_velocity_sigma", error) ||
      !CheckPositiveOption(states.initial_angular_velocity_sigma,
                           "wnoa_initial_angular_velocity_sigma", error) ||
      !CheckNonNegativeOption(options.min_state_spacing,
                              "wnoj_min_state_spacing", error) ||
      !ThinStateTimes("wnoj", mean.get(), std::move(state_times),
                      options.min_state_spacing, &times, error)) {
    return nullptr;
  }
  return std::unique_ptr<WnojTrajectory>(
      new WnojTrajectory(options, states, std::move(mean), std::move(times)));
}

void WnojTrajectory::PositionWeights(double elapsed, double dt, double* lambda,
                                     double* psi) {
  const double s = elapsed / dt;
  const double s2 = s * s, s3 = s2 * s, s4 = s3 * s, s5 = s4 * s;
  const double h3 = 10.0 * s3 - 15.0 * s4 + 6.0 * s5;
  lambda[0] = 1.0 - h3;
  lambda[1] = dt * (s - 6.0 * s3 + 8.0 * s4 - 3.0 * s5);
  lambda[2] = dt * dt * 0.5 * (s2 - 3.0 * s3 + 3.0 * s4 - s5);
  psi[0] = h3;
  psi[1] = dt * (-4.0 * s3 + 7.0 * s4 - 3.0 * s5);
  psi[2] = dt * dt * 0.5 * (s3 - 2.0 * s4 + s5);
}

void WnojTrajectory::SetSmoothestDerivatives(
    int c, const std::vector<double>& positions) {
  const int n = num_blocks();
  const std::vector<double> velocity =
      WnoaTrajectory::SmoothestVelocities(times_, positions);
  // e = r0 + J (a_k, a_k+1), r0 = (d - dt v_k, v_k+1 - v_k, 0), J = [-dt^2/2
  // 0; -dt 0; -1 1], whitened by one coordinate's S (wnoj_prior_cost.h).
  const std::vector<double> acceleration =
      SmoothestChain(n, [&](int k, Eigen::Matrix2d* h, Eigen::Vector2d* g) {
        const double dt = times_[k + 1] - times_[k];
        const Eigen::Matrix3d w =
            WnojPriorCost::CoordinateSqrtInformation(dt, 1.0);
        Eigen::Matrix<double, 3, 2> jacobian;
        jacobian << -0.5 * dt * dt, 0.0, -dt, 0.0, -1.0, 1.0;
        const Eigen::Vector3d r0(
            positions[k + 1] - positions[k] - dt * velocity[k],
            velocity[k + 1] - velocity[k], 0.0);
        const Eigen::Matrix<double, 3, 2> whitened = w * jacobian;
        *h = whitened.transpose() * whitened;
        *g = whitened.transpose() * (w * r0);
      });
  for (int i = 0; i < n; ++i) {
    mutable_block(i)[3 + c] = velocity[i];
    mutable_block(i)[6 + c] = acceleration[i];
  }
}

bool WnojTrajectory::TakeScales(const StateTrajectory& rescaled) {
  const auto& wnoj = static_cast<const WnojTrajectory&>(rescaled);
  const WnoaOptions& s = wnoj.states_options_;
  const WnojOptions& o = wnoj.options_;
  if (s.initial_position_sigma != states_options_.initial_position_sigma ||
      s.initial_heading_sigma != states_options_.initial_heading_sigma ||
      s.initial_velocity_sigma != states_options_.initial_velocity_sigma ||
      s.initial_angular_velocity_sigma !=
          states_options_.initial_angular_velocity_sigma ||
      o.min_state_spacing != options_.min_state_spacing ||
      o.initial_acceleration_sigma != options_.initial_acceleration_sigma ||
      o.initial_angular_acceleration_sigma !=
          options_.initial_angular_acceleration_sigma) {
    return false;
  }
  options_.position_qc = o.position_qc;
  options_.heading_qc = o.heading_qc;
  return true;
}

void WnojTrajectory::SetMotionQc(ceres::CostFunction* cost) const {
  if (auto* motion = dynamic_cast<WnojPriorCost*>(cost)) {
    motion->SetQc(options_.position_qc, options_.position_qc,
                  options_.heading_qc);
  }
}

Eigen::VectorXd WnojTrajectory::InitialStateSigmas() const {
  Eigen::VectorXd sigma(kStateSize);
  sigma << WnoaTrajectory::InitialStateSigmas(states_options_),
      options_.initial_acceleration_sigma, options_.initial_acceleration_sigma,
      options_.initial_angular_acceleration_sigma;
  return sigma;
}

ceres::CostFunction* WnojTrajectory::NewInitialStateCost() const {
  return new DiagonalPriorCost(Eigen::VectorXd::Zero(kStateSize),
                               InitialStateSigmas());
}

double WnojTrajectory::MotionLogDet(double dt) const {
  // S_c is triangular: log det is the sum of its diagonal's logs.
  return 3.0 * WnojPriorCost::CoordinateSqrtInformation(dt, 1.0)
                   .diagonal()
                   .array()
                   .log()
                   .sum();
}

ceres::CostFunction* WnojTrajectory::NewMotionCost(double dt) const {
  return new WnojPriorCost(dt, options_.position_qc, options_.position_qc,
                           options_.heading_qc);
}

}  // namespace rff
