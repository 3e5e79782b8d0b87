#include "rff_ceres/mean/mean_function.h"

#include <algorithm>

#include "rff_ceres/io/text_parser.h"

namespace rff {

PiecewiseLinearMean::PiecewiseLinearMean(const std::vector<TimedPose>& poses) {
  times_.reserve(poses.size());
  values_.reserve(poses.size());
  for (const TimedPose& p : poses) {
    double theta = p.theta;
    if (!values_.empty()) {
      // Unwrap: take the heading closest to the previous one.
      theta = values_.back().z() + WrapAngle(p.theta - values_.back().z());
    }
    times_.push_back(p.t);
    values_.emplace_back(p.x, p.y, theta);
  }
}

Eigen::Vector3d PiecewiseLinearMean::Evaluate(double t) const {
  if (t <= times_.front()) return values_.front();
  if (t >= times_.back()) return values_.back();
  const auto upper = std::upper_bound(times_.begin(), times_.end(), t);
  const std::size_t i = upper - times_.begin();
  const double alpha = (t - times_[i - 1]) / (times_[i] - times_[i - 1]);
  return values_[i - 1] + alpha * (values_[i] - values_[i - 1]);
}

}  // namespace rff
