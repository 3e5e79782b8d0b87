#include "rff_ceres/consistency.h"

#include <algorithm>
#include <cmath>

#include "Eigen/Core"
#include "Eigen/Geometry"
#include "Eigen/LU"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/se2.h"

namespace rff {
namespace {

// Chi-square quantiles at kCoverageLevels for 2 and 1 degrees of freedom.
constexpr std::array<double, 3> kChi2Quantile2 = {2.2958, 5.9915, 9.2103};
constexpr std::array<double, 3> kChi2Quantile1 = {1.0, 3.8415, 6.6349};

}  // namespace

Eigen::Matrix3d CovarianceAt(const std::vector<PoseCovariance>& covariances,
                             double t) {
  const auto upper = std::lower_bound(
      covariances.begin(), covariances.end(), t,
      [](const PoseCovariance& c, double time) { return c.t < time; });
  if (upper == covariances.begin()) return upper->covariance;
  if (upper == covariances.end()) return covariances.back().covariance;
  const auto lower = upper - 1;
  const double alpha = (t - lower->t) / (upper->t - lower->t);
  return (1.0 - alpha) * lower->covariance + alpha * upper->covariance;
}

bool EvaluateConsistency(const std::vector<TimedPose>& ground_truth,
                         const std::vector<TimedPose>& estimate,
                         const std::vector<PoseCovariance>& covariances,
                         Evaluation* evaluation, std::string* error) {
  ConsistencySummary& summary = evaluation->consistency;
  summary = ConsistencySummary();
  if (ground_truth.empty()) {
    *error = "no ground-truth pose to measure the consistency at";
    return false;
  }
  if (covariances.size() != estimate.size()) {
    *error = "the covariances have " + std::to_string(covariances.size()) +
             " entries, the trajectory " + std::to_string(estimate.size()) +
             " poses: they must be at the same times";
    return false;
  }
  for (std::size_t i = 0; i < estimate.size(); ++i) {
    if (std::abs(covariances[i].t - estimate[i].t) > kTimeToleranceSeconds) {
      *error = "covariance entry " + std::to_string(i + 1) + " is at t " +
               FormatNumber(covariances[i].t) + ", the trajectory's pose at " +
               FormatNumber(estimate[i].t);
      return false;
    }
  }
  std::vector<double> times;
  for (const TimedPose& p : ground_truth) times.push_back(p.t);
  std::vector<TimedPose> at_truth;
  if (!InterpolateTrajectory(estimate, times, &at_truth, error,
                             "ground-truth")) {
    return false;
  }
  const Pose2& alignment = evaluation->alignment;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  if (evaluation->aligned) {
    rotation.topLeftCorner<2, 2>() =
        Eigen::Rotation2Dd(alignment.theta).toRotationMatrix();
  }
  for (std::size_t i = 0; i < ground_truth.size(); ++i) {
    Pose2 pose{at_truth[i].x, at_truth[i].y, at_truth[i].theta};
    if (evaluation->aligned) pose = Compose(alignment, pose);
    const Eigen::Matrix3d covariance =
        rotation * CovarianceAt(covariances, times[i]) * rotation.transpose();
    const Eigen::Matrix2d position = covariance.topLeftCorner<2, 2>();
    const double heading = covariance(2, 2);
    if (!(position.determinant() > 0.0) || !(heading > 0.0)) {
      *error = "the covariance at t " + FormatNumber(times[i]) +
               " is singular: no consistency to measure";
      return false;
    }
    const Eigen::Vector2d e(ground_truth[i].x - pose.x,
                            ground_truth[i].y - pose.y);
    const double position_nees = e.dot(position.inverse() * e);
    const double heading_nees =
        std::pow(WrapAngle(ground_truth[i].theta - pose.theta), 2) / heading;
    summary.mean_position_nees += position_nees;
    summary.mean_heading_nees += heading_nees;
    for (int k = 0; k < 3; ++k) {
      summary.position_coverage[k] += position_nees <= kChi2Quantile2[k];
      summary.heading_coverage[k] += heading_nees <= kChi2Quantile1[k];
    }
  }
  const double n = static_cast<double>(ground_truth.size());
  summary.count = static_cast<int>(ground_truth.size());
  summary.mean_position_nees /= n;
  summary.mean_heading_nees /= n;
  for (int k = 0; k < 3; ++k) {
    summary.position_coverage[k] /= n;
    summary.heading_coverage[k] /= n;
  }
  if (!std::isfinite(summary.mean_position_nees) ||
      !std::isfinite(summary.mean_heading_nees)) {
    *error =
        "the NEES overflows double precision: the errors are too large for "
        "the covariances";
    return false;
  }
  summary.evaluated = true;
  return true;
}

}  // namespace rff
