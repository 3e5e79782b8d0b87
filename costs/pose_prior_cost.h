// Prior on the pose at time t (PRIOR_POSE):
//
//   r = [ (x - x0) / sigma_xy, (y - y0) / sigma_xy,
//         wrap(theta - theta0) / sigma_theta ].
#ifndef RFF_COSTS_POSE_PRIOR_COST_H_
#define RFF_COSTS_POSE_PRIOR_COST_H_

#include "costs/angle.h"
#include "costs/pose_cost.h"

namespace rff {

class PosePriorCost : public PoseCost<3, 1, false> {
 public:
  PosePriorCost(PoseMap map, const Eigen::Vector3d& prior,
                const Eigen::Vector3d& sigma)
      : PoseCost({std::move(map)}),
        prior_(prior),
        inv_sigma_(sigma.cwiseInverse()) {}

 protected:
  bool Residual(const std::array<Eigen::Vector3d, 1>& poses,
                const Eigen::Vector2d& /*landmark*/, Eigen::Map<Residuals>* r,
                std::array<PoseGradient, 1>* dr_dposes,
                LandmarkGradient* /*dr_dlandmark*/) const override {
    Eigen::Vector3d error = poses[0] - prior_;
    error.z() = WrapAngle(error.z());
    *r = inv_sigma_.cwiseProduct(error);
    if (dr_dposes != nullptr) {
      (*dr_dposes)[0] = inv_sigma_.asDiagonal();
    }
    return true;
  }

 private:
  Eigen::Vector3d prior_;
  Eigen::Vector3d inv_sigma_;
};

}  // namespace rff

#endif  // RFF_COSTS_POSE_PRIOR_COST_H_
