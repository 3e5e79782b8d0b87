// Range and bearing to landmark l from the pose at time t:
//
//   r = [ (|l - p| - z_r) / sigma_r,
//         wrap(atan2(l_y - y, l_x - x) - theta - z_b) / sigma_b ],
//
// the stacked RangeCost and BearingCost residuals (same gradients).
#ifndef RFF_COSTS_RANGE_BEARING_COST_H_
#define RFF_COSTS_RANGE_BEARING_COST_H_

#include "costs/angle.h"
#include "costs/bearing_cost.h"
#include "costs/noise_weighted.h"
#include "costs/pose_cost.h"
#include "costs/range_cost.h"

namespace rff {

class RangeBearingCost : public PoseCost<2, 1, true>,
                         public ObservationWeighted {
 public:
  RangeBearingCost(PoseMap map, double range, double bearing,
                   double sigma_range, double sigma_bearing)
      : PoseCost({std::move(map)}),
        range_(range),
        bearing_(bearing),
        inv_sigma_range_(1.0 / sigma_range),
        inv_sigma_bearing_(1.0 / sigma_bearing) {}
  void SetSigmas(double sigma_range, double sigma_bearing) override {
    inv_sigma_range_ = 1.0 / sigma_range;
    inv_sigma_bearing_ = 1.0 / sigma_bearing;
  }

 protected:
  bool Residual(const std::array<Eigen::Vector3d, 1>& poses,
                const Eigen::Vector2d& landmark, Eigen::Map<Residuals>* r,
                std::array<PoseGradient, 1>* dr_dposes,
                LandmarkGradient* dr_dlandmark) const override {
    double range, bearing;
    Eigen::Vector3d dr_pose, db_pose;
    Eigen::Vector2d dr_landmark, db_landmark;
    RangeAndGradient(poses[0], landmark, &range, &dr_pose, &dr_landmark);
    if (!BearingAndGradient(poses[0], landmark, &bearing, &db_pose,
                            &db_landmark)) {
      return false;
    }
    (*r)(0) = (range - range_) * inv_sigma_range_;
    (*r)(1) = WrapAngle(bearing - bearing_) * inv_sigma_bearing_;
    if (dr_dposes == nullptr) return true;
    (*dr_dposes)[0].row(0) = dr_pose.transpose() * inv_sigma_range_;
    (*dr_dposes)[0].row(1) = db_pose.transpose() * inv_sigma_bearing_;
    dr_dlandmark->row(0) = dr_landmark.transpose() * inv_sigma_range_;
    dr_dlandmark->row(1) = db_landmark.transpose() * inv_sigma_bearing_;
    return true;
  }

 private:
  double range_;
  double bearing_;
  double inv_sigma_range_;
  double inv_sigma_bearing_;
};

}  // namespace rff

#endif  // RFF_COSTS_RANGE_BEARING_COST_H_
