// Depth and bearing to landmark l from the pose at time t: a camera that
// reads a landmark's range from its apparent size measures its depth along
// the optical axis (the robot's heading), not its distance,
//
//   r = [ (u(theta)^T (l - p) - z_d) / sigma_d,
//         wrap(atan2(l_y - y, l_x - x) - theta - z_b) / sigma_b ],
//
// u(theta) = (cos theta, sin theta), so the depth is |l - p| cos(bearing).
// Gradient of the depth: d/dp = -u^T, d/dtheta = v^T (l - p) with
// v = (-sin theta, cos theta), d/dl = u^T. The bearing row is BearingCost's.
#ifndef RFF_COSTS_DEPTH_BEARING_COST_H_
#define RFF_COSTS_DEPTH_BEARING_COST_H_

#include <cmath>

#include "costs/angle.h"
#include "costs/bearing_cost.h"
#include "costs/noise_weighted.h"
#include "costs/pose_cost.h"

namespace rff {

class DepthBearingCost : public PoseCost<2, 1, true>,
                         public ObservationWeighted {
 public:
  DepthBearingCost(PoseMap map, double depth, double bearing,
                   double sigma_depth, double sigma_bearing)
      : PoseCost({std::move(map)}),
        depth_(depth),
        bearing_(bearing),
        inv_sigma_depth_(1.0 / sigma_depth),
        inv_sigma_bearing_(1.0 / sigma_bearing) {}
  void SetSigmas(double sigma_range, double sigma_bearing) override {
    inv_sigma_depth_ = 1.0 / sigma_range;
    inv_sigma_bearing_ = 1.0 / sigma_bearing;
  }

 protected:
  bool Residual(const std::array<Eigen::Vector3d, 1>& poses,
                const Eigen::Vector2d& landmark, Eigen::Map<Residuals>* r,
                std::array<PoseGradient, 1>* dr_dposes,
                LandmarkGradient* dr_dlandmark) const override {
    const Eigen::Vector3d& pose = poses[0];
    const Eigen::Vector2d delta = landmark - pose.head<2>();
    const Eigen::Vector2d u(std::cos(pose.z()), std::sin(pose.z()));
    double bearing;
    Eigen::Vector3d db_pose;
    Eigen::Vector2d db_landmark;
    if (!BearingAndGradient(pose, landmark, &bearing, &db_pose, &db_landmark)) {
      return false;
    }
    (*r)(0) = (u.dot(delta) - depth_) * inv_sigma_depth_;
    (*r)(1) = WrapAngle(bearing - bearing_) * inv_sigma_bearing_;
    if (dr_dposes == nullptr) return true;
    const double d_theta = -u.y() * delta.x() + u.x() * delta.y();
    (*dr_dposes)[0].row(0) << -u.x() * inv_sigma_depth_,
        -u.y() * inv_sigma_depth_, d_theta * inv_sigma_depth_;
    (*dr_dposes)[0].row(1) = db_pose.transpose() * inv_sigma_bearing_;
    dr_dlandmark->row(0) = u.transpose() * inv_sigma_depth_;
    dr_dlandmark->row(1) = db_landmark.transpose() * inv_sigma_bearing_;
    return true;
  }

 private:
  double depth_;
  double bearing_;
  double inv_sigma_depth_;
  double inv_sigma_bearing_;
};

}  // namespace rff

#endif  // RFF_COSTS_DEPTH_BEARING_COST_H_
