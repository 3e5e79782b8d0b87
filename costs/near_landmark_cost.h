// A landmark measured (range z_r, bearing z_b) so close to the robot that it
// may lie on either side of it (z_r < kNearRangeSigmas sigma_r), as its
// position in the robot's frame at time t, along and across the measured
// ray u = (cos z_b, sin z_b):
//
//   q = R(theta)^T (l - p),
//   r = [ u^T (q - z_r u) / sigma_r,  u_perp^T q / sigma_across ],
//   sigma_across = sqrt(z_r^2 + sigma_r^2) sigma_b,
//
// the bearing's error across the ray at a distance known to sigma_r. Linear
// in q, so smooth at l = p, where the bearing's gradient (~ 1 / |l - p|) and
// the range's direction are undefined. dq/dl = R^T, dq/dp = -R^T,
// dq/dtheta = (q_y, -q_x).
#ifndef RFF_COSTS_NEAR_LANDMARK_COST_H_
#define RFF_COSTS_NEAR_LANDMARK_COST_H_

#include <cmath>

#include "costs/noise_weighted.h"
#include "costs/pose_cost.h"

namespace rff {

// Range-bearing records with a range below this many range sigmas (any
// negative one too: the sensor measured the landmark on itself) are given
// as a NearLandmarkCost.
inline constexpr double kNearRangeSigmas = 2.0;

class NearLandmarkCost : public PoseCost<2, 1, true>,
                         public ObservationWeighted {
 public:
  // `sigma_range` and `sigma_bearing` weight the rows; the across-ray
  // sigma takes its distance scale from `stated_sigma_range`.
  NearLandmarkCost(PoseMap map, double range, double bearing,
                   double sigma_range, double sigma_bearing,
                   double stated_sigma_range)
      : PoseCost({std::move(map)}),
        range_(range),
        bearing_(bearing),
        stated_sigma_range_(stated_sigma_range) {
    SetSigmas(sigma_range, sigma_bearing);
  }
  void SetSigmas(double sigma_range, double sigma_bearing) override {
    const double across =
        std::hypot(range_, stated_sigma_range_) * sigma_bearing;
    const Eigen::Vector2d ray(std::cos(bearing_), std::sin(bearing_));
    whitening_.row(0) = ray.transpose() / sigma_range;
    whitening_.row(1) = Eigen::Vector2d(-ray.y(), ray.x()).transpose() / across;
    offset_ = Eigen::Vector2d(range_ / sigma_range, 0.0);
  }

 protected:
  bool Residual(const std::array<Eigen::Vector3d, 1>& poses,
                const Eigen::Vector2d& landmark, Eigen::Map<Residuals>* r,
                std::array<PoseGradient, 1>* dr_dposes,
                LandmarkGradient* dr_dlandmark) const override {
    const double c = std::cos(poses[0].z());
    const double s = std::sin(poses[0].z());
    Eigen::Matrix2d rotation_transpose;
    rotation_transpose << c, s, -s, c;
    const Eigen::Vector2d q =
        rotation_transpose * (landmark - poses[0].head<2>());
    *r = whitening_ * q - offset_;
    if (dr_dposes == nullptr) return true;
    const Eigen::Matrix2d dr_dq = whitening_ * rotation_transpose;
    (*dr_dposes)[0].leftCols<2>() = -dr_dq;
    (*dr_dposes)[0].col(2) = whitening_ * Eigen::Vector2d(q.y(), -q.x());
    *dr_dlandmark = dr_dq;
    return true;
  }

 private:
  double range_, bearing_, stated_sigma_range_;
  Eigen::Matrix2d whitening_;  // Rows u^T / sigma_r, u_perp^T / sigma_across.
  Eigen::Vector2d offset_;     // (z_r / sigma_r, 0).
};

}  // namespace rff

#endif  // RFF_COSTS_NEAR_LANDMARK_COST_H_
