// Relative motion between the poses at t0 and t1, expressed in the frame of
// the pose at t0 (the ODOM record):
//
//   [dx^, dy^] = R(theta0)^T (p1 - p0),   dtheta^ = theta1 - theta0,
//   r = [ (dx^ - dx) / sigma_x, (dy^ - dy) / sigma_y,
//         wrap(dtheta^ - dtheta) / sigma_theta ].
//
// Both poses come through their pose maps (they usually share weight blocks).
#ifndef RFF_COSTS_ODOMETRY_COST_H_
#define RFF_COSTS_ODOMETRY_COST_H_

#include <cmath>

#include "costs/angle.h"
#include "costs/pose_cost.h"

namespace rff {

class OdometryCost : public PoseCost<3, 2, false> {
 public:
  OdometryCost(PoseMap map0, PoseMap map1, const Eigen::Vector3d& motion,
               const Eigen::Vector3d& sigma)
      : PoseCost({std::move(map0), std::move(map1)}),
        motion_(motion),
        inv_sigma_(sigma.cwiseInverse()) {}

 protected:
  bool Residual(const std::array<Eigen::Vector3d, 2>& poses,
                const Eigen::Vector2d& /*landmark*/, Eigen::Map<Residuals>* r,
                std::array<PoseGradient, 2>* dr_dposes,
                LandmarkGradient* /*dr_dlandmark*/) const override {
    const double c = std::cos(poses[0].z());
    const double s = std::sin(poses[0].z());
    const Eigen::Vector2d d = poses[1].head<2>() - poses[0].head<2>();
    const double dx = c * d.x() + s * d.y();
    const double dy = -s * d.x() + c * d.y();
    (*r)(0) = (dx - motion_.x()) * inv_sigma_.x();
    (*r)(1) = (dy - motion_.y()) * inv_sigma_.y();
    (*r)(2) = WrapAngleResidual(poses[1].z() - poses[0].z() - motion_.z()) *
              inv_sigma_.z();
    if (dr_dposes == nullptr) return true;
    // d(dx, dy)/d p1 = R^T, d/d p0 = -R^T, d/d theta0 = (dy, -dx).
    PoseGradient& j0 = (*dr_dposes)[0];
    PoseGradient& j1 = (*dr_dposes)[1];
    j1 << c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0;
    j0 << -c, -s, dy, s, -c, -dx, 0.0, 0.0, -1.0;
    j0 = inv_sigma_.asDiagonal() * j0;
    j1 = inv_sigma_.asDiagonal() * j1;
    return true;
  }

 private:
  Eigen::Vector3d motion_;
  Eigen::Vector3d inv_sigma_;
};

}  // namespace rff

#endif  // RFF_COSTS_ODOMETRY_COST_H_
