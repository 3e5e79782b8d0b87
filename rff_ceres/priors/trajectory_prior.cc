#include "rff_ceres/priors/trajectory_prior.h"

#include <algorithm>
#include <utility>

#include "glog/logging.h"
#include "rff_ceres/initialization.h"
#include "rff_ceres/mean_rotation.h"
#include "rff_ceres/option_error.h"

namespace rff {
namespace {

// The registry: one line per prior.
const std::vector<const TrajectoryPrior*>& Registry() {
  static const auto* registry = new std::vector<const TrajectoryPrior*>{
      &FeaturePrior(),
      &WnoaPrior(),
      &WnojPrior(),
  };
  return *registry;
}

}  // namespace

std::shared_ptr<const MeanFunction> UnitWindowMean() {
  return std::make_shared<PiecewiseLinearMean>(
      std::vector<TimedPose>{{0.0, 0.0, 0.0, 0.0}});
}

const TrajectoryPrior* FindPrior(const std::string& name) {
  for (const TrajectoryPrior* prior : Registry()) {
    if (name == prior->name()) return prior;
  }
  return nullptr;
}

const TrajectoryPrior& PriorOf(const SlamOptions& options) {
  const TrajectoryPrior* prior = FindPrior(options.prior);
  CHECK(prior != nullptr) << "unknown prior " << options.prior
                          << ": the options were not validated";
  return *prior;
}

std::vector<std::string> PriorNames() {
  std::vector<std::string> names;
  for (const TrajectoryPrior* prior : Registry()) {
    names.push_back(prior->name());
  }
  return names;
}

std::unique_ptr<TrajectoryModel> CreateTrajectoryModel(
    const Dataset& dataset, const SlamOptions& options,
    std::shared_ptr<const MeanFunction> mean, std::string* error) {
  if (!CheckOneOf(options.prior, "prior", "unknown prior", PriorNames(),
                  error)) {
    return nullptr;
  }
  const TrajectoryPrior& prior = PriorOf(options);
  const std::string mean_name = SettlePriorMean(options, dataset);
  std::unique_ptr<TrajectoryModel> model =
      prior.CreateModel(dataset, options, mean_name, mean, error);
  if (!model || mean_name != "odometry") return model;
  // Dead reckoning carries the error of its start heading: let it turn.
  const PosePrior& start = EarliestPosePrior(dataset);
  return std::make_unique<MeanRotationTrajectory>(
      std::move(model), std::move(mean), start.pose.t,
      std::min(start.sigma_theta, kLooseHeadingSigma));
}

}  // namespace rff
