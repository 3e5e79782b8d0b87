// Relative motion between the poses at t0 and t1, expressed in the frame of
// the pose at t0 (the ODOM record):
//
//   [dx^, dy^] = R(theta0)^T (p1 - p0),   dtheta^ = theta1 - theta0,
//   r = L [ dx^ - dx, dy^ - dy, wrap(dtheta^ - dtheta) ],
//
// with L the square-root information (diag(1/sigma) for one ODOM record, a
// full matrix for a preintegrated chain). Both poses come through their pose
// maps (they usually share weight blocks).
#ifndef RFF_COSTS_ODOMETRY_COST_H_
#define RFF_COSTS_ODOMETRY_COST_H_

#include <cmath>

#include "costs/angle.h"
#include "costs/noise_weighted.h"
#include "costs/pose_cost.h"

namespace rff {

class OdometryCost : public PoseCost<3, 2, false>, public OdometryWeighted {
 public:
  OdometryCost(PoseMap map0, PoseMap map1, const Eigen::Vector3d& motion,
               const Eigen::Matrix3d& sqrt_information)
      : PoseCost({std::move(map0), std::move(map1)}),
        motion_(motion),
        sqrt_information_(sqrt_information) {}
  // Independent noise per component (one ODOM record).
  OdometryCost(PoseMap map0, PoseMap map1, const Eigen::Vector3d& motion,
               const Eigen::Vector3d& sigma)
      : OdometryCost(std::move(map0), std::move(map1), motion,
                     Eigen::Matrix3d(sigma.cwiseInverse().asDiagonal())) {}
  void SetSqrtInformation(const Eigen::Matrix3d& sqrt_information) override {
    sqrt_information_ = sqrt_information;
  }

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
    const Eigen::Vector3d error(
        dx - motion_.x(), dy - motion_.y(),
        WrapAngle(poses[1].z() - poses[0].z() - motion_.z()));
    *r = sqrt_information_ * error;
    if (dr_dposes == nullptr) return true;
    // d(dx, dy)/d p1 = R^T, d/d p0 = -R^T, d/d theta0 = (dy, -dx).
    PoseGradient& j0 = (*dr_dposes)[0];
    PoseGradient& j1 = (*dr_dposes)[1];
    j1 << c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0;
    j0 << -c, -s, dy, s, -c, -dx, 0.0, 0.0, -1.0;
    j0 = sqrt_information_ * j0;
    j1 = sqrt_information_ * j1;
    return true;
  }

 private:
  Eigen::Vector3d motion_;
  Eigen::Matrix3d sqrt_information_;
};

}  // namespace rff

#endif  // RFF_COSTS_ODOMETRY_COST_H_
