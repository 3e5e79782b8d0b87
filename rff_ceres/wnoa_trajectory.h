// The LTV-SDE baseline of Barfoot, Tong and Sarkka (RSS 2014) as in gpslam:
// the deviation of the trajectory from the prior mean,
//
//   x(t) = mu(t) + p(t),   d^2 p / dt^2 = w(t),   w ~ GP(0, Q_c delta(t - t')),
//
// a white-noise-on-acceleration (constant-velocity) prior, independent per
// coordinate (x, y, theta). Its Markov state gamma = (p, dp/dt) is kept at
// discrete state times t_0 < ... < t_K; each state is one 6-vector block
// (p_x, p_y, p_theta, v_x, v_y, v_theta). Between consecutive states the prior
// is the residual
//
//   e_i = gamma_{i+1} - Phi(dt) gamma_i,   e_i ~ N(0, Q_i(dt)),
//   Phi = [1 dt; 0 1],  Q_i = Q_c [dt^3/3 dt^2/2; dt^2/2 dt]
//
// per coordinate,
//
// and the pose at any time tau in [t_i, t_{i+1}] is the GP interpolation
// (Barfoot et al. 2014, eq. 10; Anderson et al. 2015)
//
//   p(tau) = Lambda(tau) gamma_i + Psi(tau) gamma_{i+1},
//   Psi = Q_tau Phi(t_{i+1}, tau)^T Q_i^-1,
//   Lambda = Phi(tau, t_i) - Psi Phi(dt),
//
// which is affine in two blocks, so every observation cost of the RFF model
// serves this model unchanged through its PoseMap. Before t_0 and after t_K
// the state is extrapolated with the constant-velocity model.
#ifndef RFF_CERES_WNOA_TRAJECTORY_H_
#define RFF_CERES_WNOA_TRAJECTORY_H_

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "Eigen/Core"
#include "rff_ceres/mean/mean_function.h"
#include "rff_ceres/state_trajectory.h"

namespace rff {

struct WnoaOptions {
  // Power spectral density Q_c of the white-noise acceleration: x and y in
  // m^2/s^3, theta in rad^2/s^3.
  double position_qc = 1.0;
  double heading_qc = 0.1;
  // Prior on the first state's deviation from the mean: position (m),
  // heading (rad), velocities (m/s, rad/s). Standard deviations, > 0.
  double initial_position_sigma = 10.0;
  double initial_heading_sigma = 1.0;
  double initial_velocity_sigma = 1.0;
  double initial_angular_velocity_sigma = 1.0;
  // States closer than this in time are merged into one (seconds, >= 0);
  // 0 keeps a state at every distinct requested time.
  double min_state_spacing = 0.0;
  // Where the learning rounds start Q_c: "odometry", the diffusion the
  // dead reckoning implies (priors/odometry_diffusion.h) where the run has
  // odometry, else the values above; "given", the values above.
  std::string qc_start = "odometry";
};

class WnoaTrajectory : public StateTrajectory {
 public:
  static constexpr int kStateSize = 6;

  // States at the distinct `state_times` (any order, at least one; thinned by
  // options.min_state_spacing), all zero. Returns nullptr and sets `error` on
  // bad options (non-positive Q_c or sigma, non-finite times).
  static std::unique_ptr<WnoaTrajectory> Create(
      const WnoaOptions& options, std::shared_ptr<const MeanFunction> mean,
      std::vector<double> state_times, std::string* error);

  // The per-coordinate 2x2 interpolation matrices at `elapsed` = tau - t_i
  // in an interval of length `dt` = t_{i+1} - t_i > 0, in closed form
  // (cubic Hermite basis in s = elapsed / dt; Q_c cancels out):
  //   (p, v)(tau) = lambda (p_i, v_i) + psi (p_{i+1}, v_{i+1}).
  static void InterpolationMatrices(double elapsed, double dt,
                                    Eigen::Matrix2d* lambda,
                                    Eigen::Matrix2d* psi);

  // The velocities at `times` (sorted, distinct) that minimise the WNOA
  // energy sum_k e_k^T Q_k^-1 e_k of one coordinate with its `positions`
  // held (wnoa_prior_cost.h; q_c cancels). Central differences would
  // disagree across states microseconds apart, where Q^-1 ~ dt^-3 turns
  // that into a prior cost of 10^5 and a solve that leaves its start.
  static std::vector<double> SmoothestVelocities(
      const std::vector<double>& times, const std::vector<double>& positions);
  // The first state's prior sigmas, (p_x, p_y, p_theta, v_x, v_y, v_theta).
  static Eigen::VectorXd InitialStateSigmas(const WnoaOptions& options);

 private:
  WnoaTrajectory(const WnoaOptions& options,
                 std::shared_ptr<const MeanFunction> mean,
                 std::vector<double> times)
      : StateTrajectory(2, std::move(mean), std::move(times)),
        options_(options) {}
  void PositionRows(double elapsed, double dt, double* lambda,
                    double* psi) const override;
  // SmoothestVelocities of the coordinate's positions.
  void SetSmoothestDerivatives(int c,
                               const std::vector<double>& positions) override;
  Eigen::VectorXd InitialStateSigmas() const override;
  // WnoaInitialStateCost and WnoaPriorCost.
  ceres::CostFunction* NewInitialStateCost() const override;
  ceres::CostFunction* NewMotionCost(double dt) const override;
  void SetMotionQc(ceres::CostFunction* cost) const override;
  bool TakeScales(const StateTrajectory& rescaled) override;
  double MotionLogDet(double dt) const override;

  WnoaOptions options_;
};

}  // namespace rff

#endif  // RFF_CERES_WNOA_TRAJECTORY_H_
