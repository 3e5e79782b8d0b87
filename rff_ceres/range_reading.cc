#include "rff_ceres/range_reading.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "Eigen/Cholesky"
#include "costs/angle.h"
#include "costs/near_landmark_cost.h"
#include "rff_ceres/statistics.h"

namespace rff {

DepthEvidence MeasureDepthEvidence(
    const Dataset& dataset,
    const std::function<Eigen::Vector3d(double)>& pose_at,
    const std::map<LandmarkId, Eigen::Vector2d>& landmarks) {
  // Rows (1 / sigma, d / sigma, g) and r: an offset and a scale, which a
  // range calibration takes, beside what reading depths changes.
  std::vector<Eigen::Vector3d> rows;
  std::vector<double> residuals;
  for (const Observation& o : dataset.observations) {
    const auto landmark = landmarks.find(o.id);
    if (o.type != ObservationType::kRangeBearing ||
        landmark == landmarks.end() ||
        o.range < kNearRangeSigmas * o.sigma_range) {
      continue;
    }
    const Eigen::Vector3d pose = pose_at(o.t);
    const Eigen::Vector2d delta = landmark->second - pose.head<2>();
    const double distance = delta.norm();
    const double bearing =
        WrapAngle(std::atan2(delta.y(), delta.x()) - pose.z());
    residuals.push_back((o.range - distance) / o.sigma_range);
    rows.emplace_back(1.0 / o.sigma_range, distance / o.sigma_range,
                      -distance * (1.0 - std::cos(bearing)) / o.sigma_range);
  }
  std::vector<double> sizes;
  for (const double r : residuals) sizes.push_back(std::abs(r));
  // A floor for residuals that are nearly all zero (noise-free data).
  const double level = std::max(5.0 * 1.4826 * Median(sizes), 1e-6);
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d projected = Eigen::Vector3d::Zero();
  double rr = 0.0;
  DepthEvidence evidence;
  for (std::size_t i = 0; i < residuals.size(); ++i) {
    if (!(std::abs(residuals[i]) <= level)) continue;
    normal += rows[i] * rows[i].transpose();
    projected += rows[i] * residuals[i];
    rr += residuals[i] * residuals[i];
    ++evidence.rows;
  }
  if (evidence.rows < 4) return evidence;
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(normal);
  const Eigen::Vector3d coefficients = ldlt.solve(projected);
  const Eigen::Matrix3d inverse = ldlt.solve(Eigen::Matrix3d::Identity());
  // The last coefficient's standard error: residual variance on n - 3
  // degrees of freedom times (N^-1)_33.
  const double misfit =
      std::max(0.0, rr - coefficients.dot(projected)) / (evidence.rows - 3);
  if (ldlt.info() != Eigen::Success || !coefficients.allFinite() ||
      !(inverse(2, 2) > 0.0) || !(misfit > 0.0)) {
    return evidence;  // Collinear columns or an exact fit: nothing told.
  }
  evidence.slope = coefficients[2];
  evidence.t_statistic = evidence.slope / std::sqrt(misfit * inverse(2, 2));
  return evidence;
}

bool SettleRangeReading(const DepthEvidence& evidence,
                        ProblemOptions* options) {
  if (options->range_bearing_ranges != "auto") return false;
  const bool depth =
      evidence.slope > 0.0 && evidence.t_statistic > kMinDepthEvidence;
  options->range_bearing_ranges = depth ? "depth" : "distance";
  if (depth) options->range_calibration.estimate = true;
  return depth;
}

}  // namespace rff
