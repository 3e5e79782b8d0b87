#include "rff_ceres/mean/prior_mean.h"

#include <algorithm>

#include "rff_ceres/dead_reckoning.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/mean/localization_mean.h"
#include "rff_ceres/mean/spline_mean.h"
#include "rff_ceres/option_error.h"

namespace rff {

std::vector<std::string> PriorMeanNames() {
  return {"auto", "odometry", "wnoa", "localization", "spline", "constant"};
}

std::shared_ptr<const MeanFunction> BuildPriorMean(const std::string& name,
                                                   const Dataset& dataset,
                                                   std::string* error) {
  return BuildPriorMean(name, dataset, LocalizationOptions(),
                        kPaperSplineSmoothing, error);
}

std::shared_ptr<const MeanFunction> BuildPriorMean(
    const std::string& name, const Dataset& dataset,
    const LocalizationOptions& localization, double spline_smoothing,
    std::string* error) {
  if (!CheckOneOf(name, "prior_mean", "unknown prior mean", PriorMeanNames(),
                  error)) {
    return nullptr;
  }
  // Checked whatever the name: "auto" and "spline" may localise.
  if (!CheckLocalizationOptions(localization, error)) return nullptr;
  if (dataset.pose_priors.empty()) {
    *error = "prior mean '" + name + "': the dataset has no PRIOR_POSE record";
    return nullptr;
  }
  if (name == "wnoa") {
    *error = OptionError("prior_mean", name,
                         "a solve of the WNOA prior, which RunSlam builds");
    return nullptr;
  }
  // From the inputs only: observations in the mean would count twice.
  if (name == "auto") {
    return BuildPriorMean(dataset.odometry.empty() ? "constant" : "odometry",
                          dataset, localization, spline_smoothing, error);
  }
  if (name == "constant") {
    return std::make_shared<PiecewiseLinearMean>(
        std::vector<TimedPose>{EarliestPosePrior(dataset).pose});
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
  if (name == "localization") {
    LocalizationReport report;
    return BuildLocalizationMean(dataset, localization, &report, error);
  }
  // "spline": the paper's smoothing spline (III-B.2) through the
  // localisation at every observation and prior time.
  std::shared_ptr<const MeanFunction> base = BuildPriorMean(
      "localization", dataset, localization, spline_smoothing, error);
  if (!base) return nullptr;
  std::vector<double> times;
  for (const Observation& o : dataset.observations) times.push_back(o.t);
  for (const PosePrior& p : dataset.pose_priors) times.push_back(p.pose.t);
  std::sort(times.begin(), times.end());
  times.erase(std::unique(times.begin(), times.end()), times.end());
  std::vector<TimedPose> poses;
  for (const double t : times) {
    const Eigen::Vector3d p = base->Evaluate(t);
    poses.push_back({t, p.x(), p.y(), p.z()});
  }
  std::shared_ptr<const MeanFunction> mean =
      RefitSplineMean(poses, {}, spline_smoothing, error);
  if (!mean) *error = "prior mean 'spline': " + *error;
  return mean;
}

}  // namespace rff
