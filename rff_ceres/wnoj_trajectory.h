// The white-noise-on-jerk (constant-acceleration) prior of Tang, Yoon and
// Barfoot (2019), STEAM's: the deviation of the trajectory from the prior
// mean, d^3 p / dt^3 = w(t), w ~ GP(0, Q_c delta(t - t')), per coordinate,
// with the Markov state gamma = (p, v, a) at each state time, a 9-vector
// block (p_x, p_y, p_theta, v_x, v_y, v_theta, a_x, a_y, a_theta).
// Consecutive states are tied by WnojPriorCost; between them the pose is the
// GP interpolation, the quintic Hermite polynomial in s = (tau - t_i) / dt
// that matches both states (the minimum-jerk-energy path):
//
//   p(tau) = H0 p_i + dt H1 v_i + dt^2 H2 a_i + H3 p_i+1 + dt H4 v_i+1
//            + dt^2 H5 a_i+1,
//   H0 = 1 - 10 s^3 + 15 s^4 - 6 s^5,  H1 = s - 6 s^3 + 8 s^4 - 3 s^5,
//   H2 = (s^2 - 3 s^3 + 3 s^4 - s^5) / 2,  H3 = 10 s^3 - 15 s^4 + 6 s^5,
//   H4 = -4 s^3 + 7 s^4 - 3 s^5,  H5 = (s^3 - 2 s^4 + s^5) / 2.
//
// Its acceleration is smooth: where the motion is (a vehicle's), it expects
// less motion at the highest frequencies than WNOA does, so white odometry
// noise is not taken for motion (docs/uncertainty.md).
#ifndef RFF_CERES_WNOJ_TRAJECTORY_H_
#define RFF_CERES_WNOJ_TRAJECTORY_H_

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "rff_ceres/mean/mean_function.h"
#include "rff_ceres/state_trajectory.h"
#include "rff_ceres/wnoa_trajectory.h"

namespace rff {

struct WnojOptions {
  // Power spectral density Q_c of the white-noise jerk: x and y in m^2/s^5,
  // theta in rad^2/s^5.
  double position_qc = 1.0;
  double heading_qc = 0.1;
  // Prior on the first state's accelerations (m/s^2, rad/s^2), > 0; its
  // position, heading and velocities take WnoaOptions's sigmas.
  double initial_acceleration_sigma = 1.0;
  double initial_angular_acceleration_sigma = 1.0;
  // States closer than this in time are merged into one (seconds, >= 0).
  // The prior's information between two states grows as dt^-5: states a
  // millisecond apart (cameras' paired frames) leave the normal equations
  // unfactorisable in double precision.
  double min_state_spacing = 0.01;
};

class WnojTrajectory : public StateTrajectory {
 public:
  static constexpr int kStateSize = 9;

  // States at the distinct `state_times` (any order, at least one; thinned by
  // options.min_state_spacing), all zero. `states` gives the first state's
  // position, heading and velocity sigmas. Returns nullptr
  // and sets `error` on bad options (non-positive Q_c or sigma, non-finite
  // times).
  static std::unique_ptr<WnojTrajectory> Create(
      const WnojOptions& options, const WnoaOptions& states,
      std::shared_ptr<const MeanFunction> mean, std::vector<double> state_times,
      std::string* error);

  // The quintic Hermite weights above at `elapsed` = tau - t_i in an
  // interval of length `dt` > 0: p(tau) = lambda . (p_i, v_i, a_i) +
  // psi . (p_i+1, v_i+1, a_i+1).
  static void PositionWeights(double elapsed, double dt, double* lambda,
                              double* psi);

 private:
  WnojTrajectory(const WnojOptions& options, const WnoaOptions& states,
                 std::shared_ptr<const MeanFunction> mean,
                 std::vector<double> times)
      : StateTrajectory(3, std::move(mean), std::move(times)),
        options_(options),
        states_options_(states) {}
  void PositionRows(double elapsed, double dt, double* lambda,
                    double* psi) const override {
    PositionWeights(elapsed, dt, lambda, psi);
  }
  // Velocities as WNOA's smoothest, then the accelerations that minimise
  // the WNOJ energy with positions and velocities held.
  void SetSmoothestDerivatives(int c,
                               const std::vector<double>& positions) override;
  // WNOA's six sigmas, then the accelerations'.
  Eigen::VectorXd InitialStateSigmas() const override;
  // A DiagonalPriorCost on the first state and WnojPriorCost.
  ceres::CostFunction* NewInitialStateCost() const override;
  ceres::CostFunction* NewMotionCost(double dt) const override;
  void SetMotionQc(ceres::CostFunction* cost) const override;
  bool TakeScales(const StateTrajectory& rescaled) override;
  double MotionLogDet(double dt) const override;

  WnojOptions options_;
  WnoaOptions states_options_;
};

}  // namespace rff

#endif  // RFF_CERES_WNOJ_TRAJECTORY_H_
