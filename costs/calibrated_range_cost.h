// Range from the robot at time t to landmark l through an affine sensor
// model with unknown scale s and offset o (one calibration block c = (s, o)
// shared by every range; raw UWB ranges of the Plaza runs read about 7%
// long):
//
//   r = (s |l - p(t)| + o - z) / sigma.
//
// With r0 = |l - p| / sigma and its gradient J0 (RangeCost with z = 0):
// dr/d(pose, l) = s J0, dr/ds = r0, dr/do = 1 / sigma.
#ifndef RFF_COSTS_CALIBRATED_RANGE_COST_H_
#define RFF_COSTS_CALIBRATED_RANGE_COST_H_

#include <vector>

#include "Eigen/Core"
#include "ceres/cost_function.h"
#include "costs/range_cost.h"

namespace rff {

class CalibratedRangeCost : public ceres::CostFunction {
 public:
  CalibratedRangeCost(PoseMap map, double range, double sigma)
      : distance_(std::move(map), 0.0, sigma),
        range_(range),
        inv_sigma_(1.0 / sigma) {
    set_num_residuals(1);
    *mutable_parameter_block_sizes() = distance_.parameter_block_sizes();
    mutable_parameter_block_sizes()->push_back(2);  // (scale, offset)
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const int calibration =
        static_cast<int>(parameter_block_sizes().size()) - 1;
    const double scale = parameters[calibration][0];
    const double offset = parameters[calibration][1];
    double r0;
    if (!distance_.Evaluate(parameters, &r0, jacobians)) return false;
    residuals[0] = scale * r0 + (offset - range_) * inv_sigma_;
    if (jacobians == nullptr) return true;
    const std::vector<int32_t>& sizes = parameter_block_sizes();
    for (int b = 0; b < calibration; ++b) {
      if (jacobians[b] == nullptr) continue;
      for (int i = 0; i < sizes[b]; ++i) jacobians[b][i] *= scale;
    }
    if (jacobians[calibration] != nullptr) {
      jacobians[calibration][0] = r0;
      jacobians[calibration][1] = inv_sigma_;
    }
    return true;
  }

 private:
  RangeCost distance_;  // |l - p| / sigma and its Jacobians.
  double range_;
  double inv_sigma_;
};

}  // namespace rff

#endif  // RFF_COSTS_CALIBRATED_RANGE_COST_H_
