#include "rff_ceres/options.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/mean/localization_mean.h"
#include "rff_ceres/mean/prior_mean.h"
#include "rff_ceres/option_error.h"
#include "rff_ceres/priors/trajectory_prior.h"

namespace rff {

bool ValidateSlamOptions(const SlamOptions& options, std::string* error) {
  ceres::Solver::Options ceres_options;
  if (!ToCeresOptions(options.solver, &ceres_options, error) ||
      !CheckOneOf(options.prior, "prior", "unknown prior", PriorNames(),
                  error) ||
      !CheckOneOf(options.mean.name, "prior_mean", "unknown prior mean",
                  PriorMeanNames(), error) ||
      !CheckOneOf(options.learn_hyperparameters, "learn_hyperparameters", "",
                  {"auto", "on", "off"}, error) ||
      !CheckOneOf(options.start.trajectory, "initial_trajectory", "",
                  {"auto", "mean"}, error)) {
    return false;
  }
  if (options.mean.name == "wnoa" && !PriorOf(options).has_features()) {
    std::vector<std::string> with_features;
    for (const std::string& name : PriorNames()) {
      if (FindPrior(name)->has_features()) with_features.push_back(name);
    }
    *error = OptionError("prior_mean", "wnoa",
                         "a WNOA-solve mean is for --prior=" +
                             JoinAlternatives(with_features) + " only");
    return false;
  }
  if (!CheckNonNegativeOption(options.solver.max_memory_gb, "max_memory_gb",
                              error)) {
    return false;
  }
  if (options.mean.outer_rounds < 0 ||
      options.mean.outer_rounds > kMaxOuterRounds) {
    *error = OptionError(
        "outer_rounds", std::to_string(options.mean.outer_rounds),
        options.mean.outer_rounds > 0 ? "more spline refits than supported"
                                      : "",
        "0 to " + std::to_string(kMaxOuterRounds));
    return false;
  }
  if (!CheckNonNegativeOption(options.problem.max_preintegration_seconds,
                              "max_preintegration_seconds", error)) {
    return false;
  }
  if (!(options.mean.spline_smoothing >= 0.0 &&
        options.mean.spline_smoothing <= 1.0)) {
    *error =
        OptionError("spline_smoothing",
                    FormatNumber(options.mean.spline_smoothing), "", "0 to 1");
    return false;
  }
  const IncrementalOptions& incremental = options.incremental;
  if (incremental.every < 0) {
    *error = OptionError("incremental_every", std::to_string(incremental.every),
                         "", "0 (batch) or more");
    return false;
  }
  if (!CheckNonNegativeOption(incremental.lag, "incremental_lag", error)) {
    return false;
  }
  if (incremental.every > 0 && options.mean.outer_rounds > 0) {
    *error =
        OptionError("outer_rounds", std::to_string(options.mean.outer_rounds),
                    "refits the whole run, which the incremental mode "
                    "(--incremental_every=" +
                        std::to_string(incremental.every) + ") does not do",
                    "0 there");
    return false;
  }
  if (incremental.every > 0 && options.learn_hyperparameters == "on") {
    *error =
        OptionError("learn_hyperparameters", "on",
                    "learns from a solve of the whole run, which the "
                    "incremental mode (--incremental_every=" +
                        std::to_string(incremental.every) + ") does not do",
                    "off or auto");
    return false;
  }
  // Every mean and pilot uses these, in the user's terms.
  if (!CheckLocalizationOptions(options.localization, error)) return false;
  for (const std::string& name : PriorNames()) {
    if (!FindPrior(name)->CheckOptions(options, error)) return false;
  }
  if (!CheckCalibrationOptions(options.problem, error)) return false;
  std::unique_ptr<ceres::LossFunction> loss;
  return CreateLoss(options.problem.loss, "loss", &loss, error) &&
         CreateLoss(options.problem.odometry_loss, "odometry_loss", &loss,
                    error);
}

}  // namespace rff
