#include "rff_ceres/range_reading.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "costs/angle.h"
#include "costs/near_landmark_cost.h"
#include "rff_ceres/statistics.h"

namespace rff {

DepthEvidence MeasureDepthEvidence(
    const Dataset& dataset,
    const std::function<Eigen::Vector3d(double)>& pose_at,
    const std::map<LandmarkId, Eigen::Vector2d>& landmarks) {
  std::vector<double> residuals;
  std::vector<double> regressors;
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
    regressors.push_back(-distance * (1.0 - std::cos(bearing)) / o.sigma_range);
  }
  std::vector<double> sizes;
  for (const double r : residuals) sizes.push_back(std::abs(r));
  const double level = 5.0 * 1.4826 * Median(sizes);
  double rg = 0.0, gg = 0.0, rr = 0.0;
  DepthEvidence evidence;
  for (std::size_t i = 0; i < residuals.size(); ++i) {
    if (!(std::abs(residuals[i]) <= level)) continue;
    rg += residuals[i] * regressors[i];
    gg += regressors[i] * regressors[i];
    rr += residuals[i] * residuals[i];
    ++evidence.rows;
  }
  if (evidence.rows < 3 || !(gg > 0.0)) return evidence;
  evidence.slope = rg / gg;
  // Residual variance of the fit r = slope g, with n - 1 degrees of freedom.
  const double misfit =
      std::max(0.0, rr - evidence.slope * rg) / (evidence.rows - 1);
  evidence.t_statistic =
      misfit > 0.0 ? evidence.slope / std::sqrt(misfit / gg)
                   : std::copysign(std::numeric_limits<double>::infinity(),
                                   evidence.slope);
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
