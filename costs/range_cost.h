// Range from the robot at time t to landmark l:
//
//   r = (|l - p(t)| - z) / sigma,
//
// with p(t) = (x(t), y(t)) given by the pose map. Gradient: dr/dp = -u/sigma,
// dr/dl = u/sigma with u = (l - p)/|l - p|; theta does not enter.
#ifndef RFF_COSTS_RANGE_COST_H_
#define RFF_COSTS_RANGE_COST_H_

#include <cmath>

#include "costs/noise_weighted.h"
#include "costs/pose_cost.h"

namespace rff {

// The range and its gradients, shared by RangeCost and RangeBearingCost.
inline void RangeAndGradient(const Eigen::Vector3d& pose,
                             const Eigen::Vector2d& landmark, double* range,
                             Eigen::Vector3d* d_pose,
                             Eigen::Vector2d* d_landmark) {
  const Eigen::Vector2d delta = landmark - pose.head<2>();
  *range = delta.norm();
  // At zero distance the direction is undefined; any unit vector is a valid
  // subgradient, and a zero one would stall the solver.
  const Eigen::Vector2d u = *range > 1e-12 ? Eigen::Vector2d(delta / *range)
                                           : Eigen::Vector2d(1.0, 0.0);
  *d_pose << -u.x(), -u.y(), 0.0;
  *d_landmark = u;
}

class RangeCost : public PoseCost<1, 1, true>, public ObservationWeighted {
 public:
  RangeCost(PoseMap map, double range, double sigma)
      : PoseCost({std::move(map)}), range_(range), inv_sigma_(1.0 / sigma) {}
  void SetSigmas(double sigma_range, double /*sigma_bearing*/) override {
    inv_sigma_ = 1.0 / sigma_range;
  }

 protected:
  bool Residual(const std::array<Eigen::Vector3d, 1>& poses,
                const Eigen::Vector2d& landmark, Eigen::Map<Residuals>* r,
                std::array<PoseGradient, 1>* dr_dposes,
                LandmarkGradient* dr_dlandmark) const override {
    double predicted;
    Eigen::Vector3d d_pose;
    Eigen::Vector2d d_landmark;
    RangeAndGradient(poses[0], landmark, &predicted, &d_pose, &d_landmark);
    (*r)(0) = (predicted - range_) * inv_sigma_;
    if (dr_dposes == nullptr) return true;
    (*dr_dposes)[0] = d_pose.transpose() * inv_sigma_;
    *dr_dlandmark = d_landmark.transpose() * inv_sigma_;
    return true;
  }

 private:
  double range_;
  double inv_sigma_;
};

}  // namespace rff

#endif  // RFF_COSTS_RANGE_COST_H_
