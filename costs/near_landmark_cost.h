// A landmark measured (range z_r, bearing z_b) so close to the robot that it
// may lie on either side of it (z_r < kNearRangeSigmas sigma_r), as its
// position in the robot's frame at time t:
//
//   r = (R(theta)^T (l - p) - z_r (cos z_b, sin z_b)) / sigma_r,
//
// smooth at l = p, where the bearing's gradient (~ 1 / |l - p|) and the
// range's direction are undefined. With q = R(theta)^T (l - p):
// dq/dl = R^T, dq/dp = -R^T, dq/dtheta = (q_y, -q_x).
#ifndef RFF_COSTS_NEAR_LANDMARK_COST_H_
#define RFF_COSTS_NEAR_LANDMARK_COST_H_

#include <cmath>

#include "costs/pose_cost.h"

namespace rff {

// Range-bearing records with a range below this many range sigmas are
// given as a NearLandmarkCost.
inline constexpr double kNearRangeSigmas = 2.0;

class NearLandmarkCost : public PoseCost<2, 1, true> {
 public:
  NearLandmarkCost(PoseMap map, double range, double bearing,
                   double sigma_range)
      : PoseCost({std::move(map)}),
        measured_(range * std::cos(bearing), range * std::sin(bearing)),
        inv_sigma_(1.0 / sigma_range) {}

 protected:
  bool Residual(const std::array<Eigen::Vector3d, 1>& poses,
                const Eigen::Vector2d& landmark, Eigen::Map<Residuals>* r,
                std::array<PoseGradient, 1>* dr_dposes,
                LandmarkGradient* dr_dlandmark) const override {
    const double c = std::cos(poses[0].z()), s = std::sin(poses[0].z());
    Eigen::Matrix2d rotation_transpose;
    rotation_transpose << c, s, -s, c;
    const Eigen::Vector2d q =
        rotation_transpose * (landmark - poses[0].head<2>());
    *r = (q - measured_) * inv_sigma_;
    if (dr_dposes == nullptr) return true;
    (*dr_dposes)[0].leftCols<2>() = -rotation_transpose * inv_sigma_;
    (*dr_dposes)[0].col(2) = Eigen::Vector2d(q.y(), -q.x()) * inv_sigma_;
    *dr_dlandmark = rotation_transpose * inv_sigma_;
    return true;
  }

 private:
  Eigen::Vector2d measured_;
  double inv_sigma_;
};

}  // namespace rff

#endif  // RFF_COSTS_NEAR_LANDMARK_COST_H_
