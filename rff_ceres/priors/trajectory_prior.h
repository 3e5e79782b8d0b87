// A trajectory prior as the solve sees it: how its model is built from the
// options, which options hold the scales that variance components
// re-estimate, and how the summary describes it. Adding a prior is one file
// in priors/ (a class and the function that returns it), its declaration
// below and one line in the registry (trajectory_prior.cc); no other code
// names a prior.
#ifndef RFF_CERES_PRIORS_TRAJECTORY_PRIOR_H_
#define RFF_CERES_PRIORS_TRAJECTORY_PRIOR_H_

#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "rff_ceres/mean/mean_function.h"
#include "rff_ceres/slam_solver.h"
#include "rff_ceres/trajectory_model.h"
#include "rff_ceres/types.h"

namespace rff {

class TrajectoryPrior {
 public:
  virtual ~TrajectoryPrior() = default;

  // The registry name: the value of --prior.
  virtual const char* name() const = 0;

  // Weights over feature maps with kernel hyperparameters: learned by the
  // evidence (hyperparameter_learning.h), sized from the kernel variance
  // (capacity), and able to correct a WNOA solve taken as their mean.
  // Otherwise Markov states whose only hyperparameters are diffusion scales.
  virtual bool has_features() const = 0;

  // Checks the prior's own options with the checks of the real construction
  // (its model built once on a unit window). Every prior's options are
  // checked whichever is chosen: a feature prior may start from a WNOA solve.
  virtual bool CheckOptions(const SlamOptions& options,
                            std::string* error) const = 0;

  // The model over every time of `dataset`, around `mean`, which "auto"
  // settled as `mean_name` (SettlePriorMean).
  virtual std::unique_ptr<TrajectoryModel> CreateModel(
      const Dataset& dataset, const SlamOptions& options,
      const std::string& mean_name, std::shared_ptr<const MeanFunction> mean,
      std::string* error) const = 0;

  // The option values variance components rescale (the position and the
  // heading scale of the prior), and what the summary calls them.
  virtual double* PositionScale(SlamOptions* options) const = 0;
  virtual double* HeadingScale(SlamOptions* options) const = 0;
  virtual const char* scales_name() const = 0;
  // The flags that set those scales, and any other solve's the prior
  // starts from (an RFF prior's WNOA mean): given by the user, "auto"
  // learning keeps them.
  virtual std::vector<std::string> scale_flags() const = 0;

  // Moves the scales the learning rounds start from (PositionScale,
  // HeadingScale) to what `dataset` implies before any solve, and records
  // it in `result`; the given ones by default.
  virtual void StartLearnedScales(const Dataset& /*dataset*/,
                                  SlamOptions* /*options*/,
                                  SlamResult* /*result*/) const {}

  // Copies into `result` what the model settled when it was built (a
  // feature count the capacity rule chose); nothing by default.
  virtual void RecordModel(const TrajectoryModel& /*model*/,
                           SlamResult* /*result*/) const {}

  // The summary's lines on the model as solved.
  virtual void PrintModel(const SlamResult& result,
                          std::ostream* out) const = 0;
};

// The registered priors, one file each: "rff" (feature_prior.cc), "wnoa"
// (wnoa_prior.cc) and "wnoj" (wnoj_prior.cc).
const TrajectoryPrior& FeaturePrior();
const TrajectoryPrior& WnoaPrior();
const TrajectoryPrior& WnojPrior();

// The times the Markov-state priors (wnoa, wnoj) keep a state at: every
// observation time and both ends of the data; about a "constant" mean
// (`mean_name` as settled) both ends of every odometry chain too. False
// with `error` where the odometry does not chain.
bool StateTimes(const Dataset& dataset, const SlamOptions& options,
                const std::string& mean_name, std::vector<double>* times,
                std::string* error);

// The mean at the origin the priors' CheckOptions build on.
std::shared_ptr<const MeanFunction> UnitWindowMean();

// The prior registered as `name`, or nullptr.
const TrajectoryPrior* FindPrior(const std::string& name);

// The prior `options` name; they must have passed ValidateSlamOptions.
const TrajectoryPrior& PriorOf(const SlamOptions& options);

// The registered names, in registry order.
std::vector<std::string> PriorNames();

// The trajectory model the options ask for, around `mean`, covering every
// time of `dataset`: the prior's model, turned by the start heading's
// uncertainty about an "odometry" mean (mean_rotation.h).
std::unique_ptr<TrajectoryModel> CreateTrajectoryModel(
    const Dataset& dataset, const SlamOptions& options,
    std::shared_ptr<const MeanFunction> mean, std::string* error);

}  // namespace rff

#endif  // RFF_CERES_PRIORS_TRAJECTORY_PRIOR_H_
