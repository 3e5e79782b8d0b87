// Odometry preintegration: chains of consecutive ODOM records between the
// times the problem needs a pose at (observations, priors) are composed into
// one relative motion with its first-order covariance. The intermediate poses
// are seen by nothing else, so for the MAP this is the linearised
// marginalisation of them; the trajectory between the kept times still follows
// the odometry through the dead-reckoning prior mean. It cuts the number of
// odometry residuals to the number of observation times (3x on Plaza).
#ifndef RFF_CERES_ODOMETRY_PREINTEGRATION_H_
#define RFF_CERES_ODOMETRY_PREINTEGRATION_H_

#include <vector>

#include "Eigen/Core"
#include "rff_ceres/types.h"

namespace rff {

struct PreintegratedOdometry {
  double t0 = 0.0;
  double t1 = 0.0;
  Eigen::Vector3d motion = Eigen::Vector3d::Zero();  // In the frame at t0.
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  int num_records = 0;
};

// Composes runs of records that meet end to start (t1 == t0 of the next)
// and do not cross a time in `keep_times` (sorted); a chain ends at each kept
// time, at each gap, and before it would span more than `max_duration`
// seconds (long chains leave the trajectory between their ends free).
// `odometry` must be sorted by t0.
std::vector<PreintegratedOdometry> PreintegrateOdometry(
    const std::vector<Odometry>& odometry,
    const std::vector<double>& keep_times, double max_duration);

// Upper-triangular L with L^T L = covariance^-1 (the residual weight).
Eigen::Matrix3d SqrtInformation(const Eigen::Matrix3d& covariance);

}  // namespace rff

#endif  // RFF_CERES_ODOMETRY_PREINTEGRATION_H_
