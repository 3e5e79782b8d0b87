// Odometry through a sensor with unknown scales: the recorded motion is the
// true one with its translation scaled by s and its turn by w (one
// calibration block c = (s, w) for the whole run; commanded velocities that
// the robot does not quite follow, a wheel radius that is off):
//
//   e = [s dx^ - dx, s dy^ - dy, wrap(w dtheta^ - dtheta)],   r = L e,
//
// with (dx^, dy^, dtheta^) the motion between the poses as in OdometryCost.
// For a preintegrated chain this scales the composed motion, which equals
// composing the scaled steps to first order in the chain's turn.
// With h = (dx^, dy^, dtheta^) and its gradient J_h (an OdometryCost with
// zero motion and unit information): dr/d(poses) = L S J_h with
// S = diag(s, s, w), dr/ds = L (dx^, dy^, 0), dr/dw = L (0, 0, dtheta^).
#ifndef RFF_COSTS_CALIBRATED_ODOMETRY_COST_H_
#define RFF_COSTS_CALIBRATED_ODOMETRY_COST_H_

#include <utility>
#include <vector>

#include "Eigen/Core"
#include "ceres/cost_function.h"
#include "costs/angle.h"
#include "costs/odometry_cost.h"

namespace rff {

class CalibratedOdometryCost : public ceres::CostFunction,
                               public OdometryWeighted {
 public:
  CalibratedOdometryCost(PoseMap map0, PoseMap map1,
                         const Eigen::Vector3d& motion,
                         const Eigen::Matrix3d& sqrt_information)
      : motion_cost_(std::move(map0), std::move(map1),
                     Eigen::Vector3d(Eigen::Vector3d::Zero()),
                     Eigen::Matrix3d(Eigen::Matrix3d::Identity())),
        motion_(motion),
        sqrt_information_(sqrt_information) {
    set_num_residuals(3);
    *mutable_parameter_block_sizes() = motion_cost_.parameter_block_sizes();
    mutable_parameter_block_sizes()->push_back(2);  // (s, w)
  }

  void SetSqrtInformation(const Eigen::Matrix3d& sqrt_information) override {
    sqrt_information_ = sqrt_information;
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const int calibration =
        static_cast<int>(parameter_block_sizes().size()) - 1;
    const double s = parameters[calibration][0];
    const double w = parameters[calibration][1];
    Eigen::Vector3d h;
    if (!motion_cost_.Evaluate(parameters, h.data(), jacobians)) return false;
    const Eigen::Vector3d error(s * h.x() - motion_.x(),
                                s * h.y() - motion_.y(),
                                WrapAngle(w * h.z() - motion_.z()));
    Eigen::Map<Eigen::Vector3d> r(residuals);
    r = sqrt_information_ * error;
    if (jacobians == nullptr) return true;
    const Eigen::Matrix3d ls =
        sqrt_information_ * Eigen::Vector3d(s, s, w).asDiagonal();
    const std::vector<int32_t>& sizes = parameter_block_sizes();
    using RowMajor = Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::RowMajor>;
    for (int b = 0; b < calibration; ++b) {
      if (jacobians[b] == nullptr) continue;
      Eigen::Map<RowMajor> jacobian(jacobians[b], 3, sizes[b]);
      jacobian = ls * jacobian;
    }
    if (jacobians[calibration] != nullptr) {
      Eigen::Matrix<double, 3, 2> dh_dc;
      dh_dc << h.x(), 0.0, h.y(), 0.0, 0.0, h.z();
      Eigen::Map<Eigen::Matrix<double, 3, 2, Eigen::RowMajor>> jacobian(
          jacobians[calibration]);
      jacobian = sqrt_information_ * dh_dc;
    }
    return true;
  }

 private:
  OdometryCost motion_cost_;  // Residual h, the motion between the poses.
  Eigen::Vector3d motion_;
  Eigen::Matrix3d sqrt_information_;
};

}  // namespace rff

#endif  // RFF_COSTS_CALIBRATED_ODOMETRY_COST_H_
