#include "rff_ceres/convert/pose_graph.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "rff_ceres/dead_reckoning.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/se2.h"

namespace rff {

std::vector<double> PoseVertexTimes(const Dataset& dataset) {
  std::vector<double> times;
  for (const PosePrior& p : dataset.pose_priors) times.push_back(p.pose.t);
  for (const Odometry& o : dataset.odometry) {
    times.push_back(o.t0);
    times.push_back(o.t1);
  }
  for (const Observation& o : dataset.observations) times.push_back(o.t);
  std::sort(times.begin(), times.end());
  times.erase(std::unique(times.begin(), times.end()), times.end());
  return times;
}

std::vector<TimedPose> DeadReckonedPoses(const Dataset& dataset,
                                         const std::vector<double>& times) {
  DeadReckoningOptions options;
  options.hold_through_gaps = true;
  DeadReckoningResult result;
  std::string error;
  std::vector<TimedPose> chain;
  if (!dataset.odometry.empty() &&
      DeadReckon(dataset, options, &result, &error)) {
    chain = result.poses;
  } else {
    chain = {EarliestPosePrior(dataset).pose};  // Nothing to compose.
  }
  std::vector<TimedPose> poses;
  for (const double t : times) poses.push_back(PoseAtTime(chain, t));
  return poses;
}

bool ToRelativePosition(const Observation& range_bearing,
                        RelativePosition* position, std::string* error) {
  const double r = range_bearing.range;
  if (!(r > 0.0)) {
    *error = "RANGE_BEARING at t = " + FormatNumber(range_bearing.t) +
             " to landmark " + std::to_string(range_bearing.id) + ": range " +
             FormatNumber(r) +
             " is not > 0: no relative position with a covariance";
    return false;
  }
  const Eigen::Vector2d along(std::cos(range_bearing.bearing),
                              std::sin(range_bearing.bearing));
  const Eigen::Vector2d across(-along.y(), along.x());
  position->x = r * along.x();
  position->y = r * along.y();
  // J = [along, r * across]: the range moves the point along the ray, the
  // bearing across it at r metres per radian.
  const double sr = range_bearing.sigma_range;
  const double sb = r * range_bearing.sigma_bearing;
  position->covariance = sr * sr * along * along.transpose() +
                         sb * sb * across * across.transpose();
  return true;
}

bool ToRangeBearing(const RelativePosition& position, Observation* observation,
                    std::string* error) {
  const double r = std::hypot(position.x, position.y);
  if (!(r > 0.0)) {
    *error = "relative position (0, 0) has no bearing";
    return false;
  }
  const Eigen::Matrix2d& c = position.covariance;
  if (!(c(0, 0) > 0.0 && c(1, 1) > 0.0 && c.determinant() > 0.0)) {
    *error = "covariance is not positive definite";
    return false;
  }
  Eigen::Matrix2d g;  // d(r, b) / d(x, y).
  g << position.x / r, position.y / r, -position.y / (r * r),
      position.x / (r * r);
  const Eigen::Matrix2d range_bearing = g * c * g.transpose();
  const double correlation =
      range_bearing(0, 1) /
      std::sqrt(range_bearing(0, 0) * range_bearing(1, 1));
  if (std::abs(correlation) > kMaxRangeBearingCorrelation) {
    *error = "as range and bearing the covariance has correlation " +
             FormatNumber(correlation) +
             " (.rffd RANGE_BEARING sigmas are independent; at most " +
             FormatNumber(kMaxRangeBearingCorrelation) + ")";
    return false;
  }
  observation->type = ObservationType::kRangeBearing;
  observation->range = r;
  observation->bearing = std::atan2(position.y, position.x);
  observation->sigma_range = std::sqrt(range_bearing(0, 0));
  observation->sigma_bearing = std::sqrt(range_bearing(1, 1));
  return true;
}

bool DiagonalSigmas(const double* upper_triangle, int n, bool information,
                    std::vector<double>* sigmas, std::string* error) {
  sigmas->clear();
  int k = 0;
  for (int i = 0; i < n; ++i) {
    for (int j = i; j < n; ++j, ++k) {
      const double v = upper_triangle[k];
      const std::string entry = "(" + std::to_string(i + 1) + "," +
                                std::to_string(j + 1) +
                                ") = " + FormatNumber(v);
      if (i != j && v != 0.0) {
        *error = std::string(information ? "information" : "covariance") +
                 " entry " + entry + " is not 0 (.rffd sigmas are independent)";
        return false;
      }
      if (i == j && !(v > 0.0)) {
        *error = std::string(information ? "information" : "variance") +
                 " entry " + entry + " is not > 0";
        return false;
      }
      if (i == j) {
        sigmas->push_back(information ? 1.0 / std::sqrt(v) : std::sqrt(v));
      }
    }
  }
  return true;
}

std::vector<double> DiagonalUpperTriangle(const std::vector<double>& sigmas,
                                          bool information) {
  std::vector<double> upper;
  for (std::size_t i = 0; i < sigmas.size(); ++i) {
    for (std::size_t j = i; j < sigmas.size(); ++j) {
      const double variance = sigmas[i] * sigmas[i];
      upper.push_back(i != j ? 0.0 : information ? 1.0 / variance : variance);
    }
  }
  return upper;
}

std::string JoinNumbers(const std::vector<double>& values) {
  std::string text;
  for (std::size_t i = 0; i < values.size(); ++i) {
    text += (i == 0 ? "" : " ") + FormatNumber(values[i]);
  }
  return text;
}

}  // namespace rff
