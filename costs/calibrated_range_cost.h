// Ranges through an affine sensor model with unknown scale s and offset o
// (one calibration block c = (s, o) shared by every range of the run; raw UWB
// ranges of the Plaza runs read about 7% long):
//
//   r_range = (s |l - p(t)| + o - z) / sigma,
//
// the range row of a RangeCost or RangeBearingCost; any other row (the
// bearing) is the inner cost's, unchanged. With r0 = |l - p| / sigma and its
// gradient J0 (the inner cost's range row with z = 0):
// dr/d(pose, l) = s J0, dr/ds = r0, dr/do = 1 / sigma.
#ifndef RFF_COSTS_CALIBRATED_RANGE_COST_H_
#define RFF_COSTS_CALIBRATED_RANGE_COST_H_

#include <algorithm>
#include <utility>
#include <vector>

#include "Eigen/Core"
#include "ceres/cost_function.h"
#include "costs/depth_bearing_cost.h"
#include "costs/noise_weighted.h"
#include "costs/range_bearing_cost.h"
#include "costs/range_cost.h"

namespace rff {

// `Inner` is a cost whose residual 0 is the range residual; it is built with
// a zero range reading so that residual 0 is |l - p| / sigma.
template <class Inner>
class RangeCalibratedCost : public ceres::CostFunction,
                            public ObservationWeighted {
 public:
  void SetSigmas(double sigma_range, double sigma_bearing) override {
    inner_.SetSigmas(sigma_range, sigma_bearing);
    inv_sigma_ = 1.0 / sigma_range;
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const int calibration =
        static_cast<int>(parameter_block_sizes().size()) - 1;
    const double scale = parameters[calibration][0];
    const double offset = parameters[calibration][1];
    if (!inner_.Evaluate(parameters, residuals, jacobians)) return false;
    const double r0 = residuals[0];
    residuals[0] = scale * r0 + (offset - range_) * inv_sigma_;
    if (jacobians == nullptr) return true;
    const std::vector<int32_t>& sizes = parameter_block_sizes();
    for (int b = 0; b < calibration; ++b) {
      if (jacobians[b] == nullptr) continue;
      // Row 0 of a row-major block Jacobian: its first sizes[b] entries.
      for (int i = 0; i < sizes[b]; ++i) jacobians[b][i] *= scale;
    }
    if (jacobians[calibration] != nullptr) {
      double* jacobian = jacobians[calibration];
      std::fill(jacobian, jacobian + 2 * num_residuals(), 0.0);
      jacobian[0] = r0;
      jacobian[1] = inv_sigma_;
    }
    return true;
  }

 protected:
  template <typename... InnerArguments>
  RangeCalibratedCost(double range, double sigma,
                      InnerArguments&&... inner_arguments)
      : inner_(std::forward<InnerArguments>(inner_arguments)...),
        range_(range),
        inv_sigma_(1.0 / sigma) {
    set_num_residuals(inner_.num_residuals());
    *mutable_parameter_block_sizes() = inner_.parameter_block_sizes();
    mutable_parameter_block_sizes()->push_back(2);  // (scale, offset)
  }

 private:
  Inner inner_;
  double range_;
  double inv_sigma_;
};

// A RANGE record through the calibration.
class CalibratedRangeCost : public RangeCalibratedCost<RangeCost> {
 public:
  CalibratedRangeCost(PoseMap map, double range, double sigma)
      : RangeCalibratedCost(range, sigma, std::move(map), 0.0, sigma) {}
};

// A RANGE_BEARING record: its range through the calibration, its bearing as
// measured.
class CalibratedRangeBearingCost
    : public RangeCalibratedCost<RangeBearingCost> {
 public:
  CalibratedRangeBearingCost(PoseMap map, double range, double bearing,
                             double sigma_range, double sigma_bearing)
      : RangeCalibratedCost(range, sigma_range, std::move(map), 0.0, bearing,
                            sigma_range, sigma_bearing) {}
};

// A RANGE_BEARING record whose range is a depth (depth_bearing_cost.h):
// s u^T (l - p) + o, its bearing as measured.
class CalibratedDepthBearingCost
    : public RangeCalibratedCost<DepthBearingCost> {
 public:
  CalibratedDepthBearingCost(PoseMap map, double depth, double bearing,
                             double sigma_depth, double sigma_bearing)
      : RangeCalibratedCost(depth, sigma_depth, std::move(map), 0.0, bearing,
                            sigma_depth, sigma_bearing) {}
};

}  // namespace rff

#endif  // RFF_COSTS_CALIBRATED_RANGE_COST_H_
