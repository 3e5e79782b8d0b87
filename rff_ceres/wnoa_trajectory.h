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

#include <array>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "Eigen/Core"
#include "rff_ceres/mean/mean_function.h"
#include "rff_ceres/trajectory_model.h"

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
};

class WnoaTrajectory : public TrajectoryModel {
 public:
  static constexpr int kStateSize = 6;

  // States at the distinct `state_times` (any order, at least one; thinned by
  // options.min_state_spacing), all zero. Returns nullptr and sets `error` on
  // bad options (non-positive Q_c or sigma, non-finite times).
  static std::unique_ptr<WnoaTrajectory> Create(
      const WnoaOptions& options, std::shared_ptr<const MeanFunction> mean,
      std::vector<double> state_times, std::string* error);

  int num_blocks() const override;
  int block_size(int /*block*/) const override { return kStateSize; }
  double* mutable_block(int block) override;
  PoseMap PoseAt(double t) const override;
  Eigen::Vector3d Pose(double t) const override;
  // The interpolations of `previous` where its state times are these (Q_c
  // cancels out of them).
  void AdoptCaches(const TrajectoryModel& previous) override;
  // Q_c of `rescaled` where its states and mean are these: the
  // interpolations do not depend on it, the motion prior's costs do
  // (UpdatePriorCosts).
  bool AdoptScales(TrajectoryModel* rescaled) override;
  void UpdatePriorCosts(
      const std::vector<ceres::CostFunction*>& costs) const override;
  // The initial-state prior on block 0 and one WnoaPriorCost between every
  // pair of consecutive states (a pair belongs to its later state).
  using TrajectoryModel::AddPriorCosts;
  void AddPriorCosts(ceres::Problem* problem, int begin, int end) override;
  const MeanFunction& mean() const override;
  void set_mean(std::shared_ptr<const MeanFunction> mean) override;
  // The motion prior's rows follow the state (position, position, heading,
  // ...); the initial-state prior has a fixed scale.
  std::vector<PriorScale> PriorRowScales(const std::vector<double*>& blocks,
                                         int num_rows) const override;
  bool PriorScalesWhitenRows() const override { return true; }

  const std::vector<double>& state_times() const;

  // Sets every state to follow `poses` (sorted by time, at least one):
  // positions from their linear interpolation minus the mean, velocities the
  // smoothest under the prior given those positions (one tridiagonal solve
  // per coordinate).
  void SetStatesFromPoses(const std::vector<TimedPose>& poses);
  bool SetBlocksFromPoses(const std::vector<TimedPose>& poses) override {
    SetStatesFromPoses(poses);
    return true;
  }

  // The per-coordinate 2x2 interpolation matrices at `elapsed` = tau - t_i
  // in an interval of length `dt` = t_{i+1} - t_i > 0, in closed form
  // (cubic Hermite basis in s = elapsed / dt; Q_c cancels out):
  //   (p, v)(tau) = lambda (p_i, v_i) + psi (p_{i+1}, v_{i+1}).
  static void InterpolationMatrices(double elapsed, double dt,
                                    Eigen::Matrix2d* lambda,
                                    Eigen::Matrix2d* psi);

 private:
  WnoaTrajectory() = default;

  // The blocks and per-coordinate phi vectors that give the pose at one time.
  struct Interpolation {
    int num_blocks = 0;  // 1 (at a state time or outside the span) or 2.
    std::array<int, 2> blocks = {0, 0};
    // phi[k][c]: coordinate c's 6-vector on blocks[k].
    std::array<std::array<std::shared_ptr<const Eigen::VectorXd>, 3>, 2> phi;
  };
  const Interpolation& InterpolationAt(double t) const;

  WnoaOptions options_;
  std::shared_ptr<const MeanFunction> mean_;
  std::vector<double> times_;   // Sorted, thinned state times.
  std::vector<double> states_;  // kStateSize values per state, contiguous.
  // e_c, shared by the poses at every state time.
  std::array<std::shared_ptr<const Eigen::VectorXd>, 3> unit_phi_;
  // Observations at the same time share their phi vectors; so do the
  // models of a learning's rounds (AdoptCaches).
  std::shared_ptr<std::map<double, Interpolation>> cache_ =
      std::make_shared<std::map<double, Interpolation>>();
};

}  // namespace rff

#endif  // RFF_CERES_WNOA_TRAJECTORY_H_
