#include "rff_ceres/mean/prior_mean.h"

#include <algorithm>

#include "rff_ceres/dead_reckoning.h"

namespace rff {

std::vector<std::string> PriorMeanNames() {
  return {"auto", "odometry", "constant"};
}

namespace {

const PosePrior& EarliestPrior(const Dataset& dataset) {
  return *std::min_element(dataset.pose_priors.begin(),
                           dataset.pose_priors.end(),
                           [](const PosePrior& a, const PosePrior& b) {
                             return a.pose.t < b.pose.t;
                           });
}

}  // namespace

std::shared_ptr<const MeanFunction> BuildPriorMean(const std::string& name,
                                                   const Dataset& dataset,
                                                   std::string* error) {
  if (name == "auto") {
    return BuildPriorMean(dataset.odometry.empty() ? "constant" : "odometry",
                          dataset, error);
  }
  if (name == "constant") {
    return std::make_shared<PiecewiseLinearMean>(
        std::vector<TimedPose>{EarliestPrior(dataset).pose});
  }
  if (name == "odometry") {
    DeadReckoningResult result;
    DeadReckoningOptions options;
    options.hold_through_gaps = true;
    if (!DeadReckon(dataset, options, &result, error)) {
      *error = "prior mean 'odometry': " + *error;
      return nullptr;
    }
    return std::make_shared<PiecewiseLinearMean>(result.poses);
  }
  *error =
      "unknown prior mean '" + name + "' (expected auto, odometry or constant)";
  return nullptr;
}

}  // namespace rff
