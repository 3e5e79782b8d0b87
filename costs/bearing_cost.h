// Bearing to landmark l in the robot frame at time t:
//
//   r = wrap(atan2(l_y - y, l_x - x) - theta - z) / sigma.
//
// With d = l - p and q = |d|^2: d atan2 / d p = (d_y, -d_x) / q,
// d atan2 / d l = (-d_y, d_x) / q, and d r / d theta = -1 / sigma.
#ifndef RFF_COSTS_BEARING_COST_H_
#define RFF_COSTS_BEARING_COST_H_

#include <cmath>

#include "costs/angle.h"
#include "costs/noise_weighted.h"
#include "costs/pose_cost.h"

namespace rff {

// Within this squared distance of the robot a landmark has no bearing.
inline constexpr double kMinBearingSquaredDistance = 1e-24;

// The bearing and its gradients, shared by BearingCost and RangeBearingCost.
// Returns false when the landmark sits on the robot (bearing undefined).
inline bool BearingAndGradient(const Eigen::Vector3d& pose,
                               const Eigen::Vector2d& landmark, double* bearing,
                               Eigen::Vector3d* d_pose,
                               Eigen::Vector2d* d_landmark) {
  const Eigen::Vector2d d = landmark - pose.head<2>();
  const double q = d.squaredNorm();
  if (!(q > kMinBearingSquaredDistance)) return false;
  *bearing = std::atan2(d.y(), d.x()) - pose.z();
  *d_pose << d.y() / q, -d.x() / q, -1.0;
  *d_landmark << -d.y() / q, d.x() / q;
  return true;
}

class BearingCost : public PoseCost<1, 1, true>, public ObservationWeighted {
 public:
  BearingCost(PoseMap map, double bearing, double sigma)
      : PoseCost({std::move(map)}),
        bearing_(bearing),
        inv_sigma_(1.0 / sigma) {}
  void SetSigmas(double /*sigma_range*/, double sigma_bearing) override {
    inv_sigma_ = 1.0 / sigma_bearing;
  }

 protected:
  bool Residual(const std::array<Eigen::Vector3d, 1>& poses,
                const Eigen::Vector2d& landmark, Eigen::Map<Residuals>* r,
                std::array<PoseGradient, 1>* dr_dposes,
                LandmarkGradient* dr_dlandmark) const override {
    double predicted;
    Eigen::Vector3d d_pose;
    Eigen::Vector2d d_landmark;
    if (!BearingAndGradient(poses[0], landmark, &predicted, &d_pose,
                            &d_landmark)) {
      return false;
    }
    (*r)(0) = WrapAngle(predicted - bearing_) * inv_sigma_;
    if (dr_dposes == nullptr) return true;
    (*dr_dposes)[0] = d_pose.transpose() * inv_sigma_;
    *dr_dlandmark = d_landmark.transpose() * inv_sigma_;
    return true;
  }

 private:
  double bearing_;
  double inv_sigma_;
};

}  // namespace rff

#endif  // RFF_COSTS_BEARING_COST_H_
