#include "rff_ceres/odometry_preintegration.h"

#include <algorithm>
#include <cmath>

#include "Eigen/Cholesky"
#include "Eigen/LU"

namespace rff {
namespace {

// z = a (+) b for relative motions, with Jacobians of z wrt a and b.
Eigen::Vector3d Compose(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                        Eigen::Matrix3d* j_a, Eigen::Matrix3d* j_b) {
  const double c = std::cos(a.z()), s = std::sin(a.z());
  *j_a << 1.0, 0.0, -s * b.x() - c * b.y(), 0.0, 1.0, c * b.x() - s * b.y(),
      0.0, 0.0, 1.0;
  *j_b << c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0;
  return Eigen::Vector3d(a.x() + c * b.x() - s * b.y(),
                         a.y() + s * b.x() + c * b.y(), a.z() + b.z());
}

}  // namespace

std::vector<PreintegratedOdometry> PreintegrateOdometry(
    const std::vector<Odometry>& odometry,
    const std::vector<double>& keep_times, double max_duration) {
  std::vector<PreintegratedOdometry> chains;
  for (const Odometry& o : odometry) {
    const Eigen::Vector3d motion(o.dx, o.dy, o.dtheta);
    const Eigen::Vector3d variance(o.sigma_x * o.sigma_x, o.sigma_y * o.sigma_y,
                                   o.sigma_theta * o.sigma_theta);
    const bool extend =
        !chains.empty() && chains.back().t1 == o.t0 &&
        o.t1 - chains.back().t0 <= max_duration &&
        !std::binary_search(keep_times.begin(), keep_times.end(), o.t0);
    if (!extend) {
      chains.push_back({o.t0, o.t1, motion, variance.asDiagonal(), 1});
      continue;
    }
    PreintegratedOdometry& chain = chains.back();
    Eigen::Matrix3d j_a, j_b;
    chain.motion = Compose(chain.motion, motion, &j_a, &j_b);
    chain.covariance = j_a * chain.covariance * j_a.transpose() +
                       j_b * variance.asDiagonal() * j_b.transpose();
    chain.t1 = o.t1;
    ++chain.num_records;
  }
  return chains;
}

Eigen::Matrix3d SqrtInformation(const Eigen::Matrix3d& covariance) {
  const Eigen::Matrix3d information = covariance.inverse();
  // LLT gives information = L L^T; the residual weight is L^T.
  return Eigen::Matrix3d(information.llt().matrixL().transpose());
}

}  // namespace rff
