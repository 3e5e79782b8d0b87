// The trajectory's deviation from the prior mean as Markov states of an
// integrated white-noise prior (the LTV-SDE family of Barfoot, Tong and
// Sarkka, RSS 2014), independent per coordinate (x, y, theta):
//
//   x(t) = mu(t) + p(t),   d^n p / dt^n = w(t),   w ~ GP(0, Q_c delta(t - t')),
//
// n = 2 (white noise on acceleration, WnoaTrajectory) or 3 (on jerk,
// WnojTrajectory). The state (p, dp/dt, ..., d^(n-1)p/dt^(n-1)) is kept at
// discrete state times t_0 < ... < t_K as one block of 3 n values, derivative
// by derivative: (p_x, p_y, p_theta, v_x, v_y, v_theta, ...). Between two
// states the pose is the GP interpolation (Barfoot et al. 2014, eq. 10)
//
//   p(tau) = Lambda(tau) gamma_i + Psi(tau) gamma_{i+1},
//
// affine in two blocks, so every observation cost serves these models
// unchanged through its PoseMap. Before t_0 and after t_K the state is
// extrapolated by its Taylor polynomial (the posterior mean there).
#ifndef RFF_CERES_STATE_TRAJECTORY_H_
#define RFF_CERES_STATE_TRAJECTORY_H_

#include <array>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "Eigen/Core"
#include "rff_ceres/mean/mean_function.h"
#include "rff_ceres/trajectory_model.h"

namespace rff {

class StateTrajectory : public TrajectoryModel {
 public:
  // Values per state: 3 coordinates times `order` derivatives (0 to n - 1).
  int state_size() const { return 3 * order_; }
  int order() const { return order_; }

  int num_blocks() const override;
  int block_size(int /*block*/) const override { return state_size(); }
  double* mutable_block(int block) override;
  PoseMap PoseAt(double t) const override;
  Eigen::Vector3d Pose(double t) const override;
  // The interpolations of `previous` where it is a model of the same kind
  // with these state times (Q_c cancels out of them).
  void AdoptCaches(const TrajectoryModel& previous) override;
  const MeanFunction& mean() const override;
  void set_mean(std::shared_ptr<const MeanFunction> mean) override;
  // The initial-state prior on block 0 and one motion prior cost between
  // every pair of consecutive states (a pair belongs to its later state).
  using TrajectoryModel::AddPriorCosts;
  void AddPriorCosts(ceres::Problem* problem, int begin, int end) override;
  // Q_c of `rescaled` where it is a model of this kind with these states,
  // mean and other options: the interpolations do not depend on Q_c, the
  // motion prior's costs do (UpdatePriorCosts).
  bool AdoptScales(TrajectoryModel* rescaled) override;
  double PriorLogNormaliser() const override;
  void UpdatePriorCosts(
      const std::vector<ceres::CostFunction*>& costs) const override;
  // The motion prior's rows follow the state (position, position, heading,
  // ...); the initial-state prior has a fixed scale.
  std::vector<PriorScale> PriorRowScales(const std::vector<double*>& blocks,
                                         int num_rows) const override;
  bool PriorScalesWhitenRows() const override { return true; }

  const std::vector<double>& state_times() const;

  // Sets every state to follow `poses` (sorted by time, at least one):
  // positions from their linear interpolation minus the mean, the
  // derivatives the smoothest under the prior given those positions.
  void SetStatesFromPoses(const std::vector<TimedPose>& poses);
  bool SetBlocksFromPoses(const std::vector<TimedPose>& poses) override {
    SetStatesFromPoses(poses);
    return true;
  }

 protected:
  // `name` prefixes the errors ("wnoa needs ..."). Returns false and sets
  // `error` where `mean` is null or `state_times` are empty or not finite;
  // else the distinct sorted times, the first of each cluster closer than
  // `min_spacing`, in `kept`.
  static bool ThinStateTimes(const std::string& name, const MeanFunction* mean,
                             std::vector<double> state_times,
                             double min_spacing, std::vector<double>* kept,
                             std::string* error);
  // All states zero.
  StateTrajectory(int order, std::shared_ptr<const MeanFunction> mean,
                  std::vector<double> times);

  // The position rows of Lambda and Psi (per coordinate, `order` weights on
  // p, v, ... of the state before and after) at `elapsed` = tau - t_i in an
  // interval of length `dt` = t_{i+1} - t_i > 0.
  virtual void PositionRows(double elapsed, double dt, double* lambda,
                            double* psi) const = 0;
  // Sets the derivatives of coordinate `c` at every state, whose
  // `positions` are set, to the smoothest under the prior.
  virtual void SetSmoothestDerivatives(
      int c, const std::vector<double>& positions) = 0;
  // The first state's prior sigmas, in state layout.
  virtual Eigen::VectorXd InitialStateSigmas() const = 0;
  // The prior's costs: on the first state (of InitialStateSigmas), and
  // between two states `dt` > 0 apart with the current Q_c.
  virtual ceres::CostFunction* NewInitialStateCost() const = 0;
  virtual ceres::CostFunction* NewMotionCost(double dt) const = 0;
  // Gives `cost`, where it is one of this model's motion costs, the current
  // Q_c.
  virtual void SetMotionQc(ceres::CostFunction* cost) const = 0;
  // Takes the Q_c of `rescaled`, of this model's type, where its other
  // options equal these; false, nothing changed, otherwise.
  virtual bool TakeScales(const StateTrajectory& rescaled) = 0;
  // log |det S| of a motion cost `dt` apart at Q_c = 1 (PriorLogNormaliser).
  virtual double MotionLogDet(double dt) const = 0;

  std::shared_ptr<const MeanFunction> mean_;
  std::vector<double> times_;   // Sorted, thinned state times.
  std::vector<double> states_;  // state_size() values per state, contiguous.

 private:
  // The blocks and per-coordinate phi vectors that give the pose at one time.
  struct Interpolation {
    int num_blocks = 0;  // 1 (at a state time or outside the span) or 2.
    std::array<int, 2> blocks = {0, 0};
    // phi[k][c]: coordinate c's state-sized vector on blocks[k].
    std::array<std::array<std::shared_ptr<const Eigen::VectorXd>, 3>, 2> phi;
  };
  const Interpolation& InterpolationAt(double t) const;
  // The state-sized vector that reads sum_j weights[j] d^j p_c from a state.
  std::shared_ptr<const Eigen::VectorXd> RowPhi(int c,
                                                const double* weights) const;

  int order_;
  // e_c, shared by the poses at every state time.
  std::array<std::shared_ptr<const Eigen::VectorXd>, 3> unit_phi_;
  // Observations at the same time share their phi vectors; so do the
  // models of a learning's rounds (AdoptCaches).
  std::shared_ptr<std::map<double, Interpolation>> cache_ =
      std::make_shared<std::map<double, Interpolation>>();
};

// The scalars x_0..x_{n-1} minimising sum_k |W_k (r_k + J_k (x_k, x_{k+1}))|^2,
// the problem given per interval k < n - 1 by its normal-equation terms
// h_k = (W J)^T (W J) and g_k = (W J)^T W r_k (`interval(k, &h, &g)`): a
// symmetric tridiagonal system, solved by elimination; zeros for n < 2.
std::vector<double> SmoothestChain(
    int n, const std::function<void(int, Eigen::Matrix2d*, Eigen::Vector2d*)>&
               interval);

}  // namespace rff

#endif  // RFF_CERES_STATE_TRAJECTORY_H_
