// ValidateSlamOptions (slam_solver.h): every option checked once, before any
// file is read or any solve starts, whichever prior it belongs to.
#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "rff_ceres/feature_trajectory.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/mean/localization_mean.h"
#include "rff_ceres/mean/mean_function.h"
#include "rff_ceres/mean/prior_mean.h"
#include "rff_ceres/slam_solver.h"
#include "rff_ceres/wnoa_trajectory.h"

namespace rff {
namespace {

bool CheckOneOf(const std::string& value, const char* name,
                const std::vector<std::string>& allowed, std::string* error) {
  if (std::find(allowed.begin(), allowed.end(), value) != allowed.end()) {
    return true;
  }
  *error = std::string(name) + " must be " + JoinAlternatives(allowed) +
           ", got '" + value + "'";
  return false;
}

}  // namespace

bool ValidateSlamOptions(const SlamOptions& options, std::string* error) {
  ceres::Solver::Options ceres_options;
  if (!ToCeresOptions(options.solver, &ceres_options, error) ||
      !CheckOneOf(options.prior, "prior", {"rff", "wnoa"}, error) ||
      !CheckOneOf(options.prior_mean, "prior_mean", PriorMeanNames(), error) ||
      !CheckOneOf(options.learn_hyperparameters, "learn_hyperparameters",
                  {"auto", "on", "off"}, error) ||
      !CheckOneOf(options.initial_trajectory, "initial_trajectory",
                  {"auto", "mean"}, error)) {
    return false;
  }
  if (options.prior_mean == "wnoa" && options.prior != "rff") {
    *error = "prior mean 'wnoa' is for the rff prior";
    return false;
  }
  if (!(options.solver.max_memory_gb >= 0.0) ||
      !std::isfinite(options.solver.max_memory_gb)) {
    *error = "max_memory_gb must be finite and >= 0, got " +
             FormatNumber(options.solver.max_memory_gb);
    return false;
  }
  if (options.outer_rounds < 0 || options.outer_rounds > kMaxOuterRounds) {
    *error = "outer_rounds must be in [0, " + std::to_string(kMaxOuterRounds) +
             "], got " + std::to_string(options.outer_rounds);
    return false;
  }
  if (!(options.problem.max_preintegration_seconds >= 0.0) ||
      !std::isfinite(options.problem.max_preintegration_seconds)) {
    *error = "max_preintegration_seconds must be finite and >= 0, got " +
             FormatNumber(options.problem.max_preintegration_seconds);
    return false;
  }
  if (!(options.spline_smoothing >= 0.0 && options.spline_smoothing <= 1.0)) {
    *error = "spline_smoothing must be in [0, 1], got " +
             FormatNumber(options.spline_smoothing);
    return false;
  }
  const IncrementalOptions& incremental = options.incremental;
  if (incremental.every < 0) {
    *error = "incremental_every must be >= 0, got " +
             std::to_string(incremental.every);
    return false;
  }
  if (!(incremental.lag >= 0.0) || !std::isfinite(incremental.lag)) {
    *error = "incremental_lag must be finite and >= 0, got " +
             FormatNumber(incremental.lag);
    return false;
  }
  if (incremental.every > 0 && options.outer_rounds > 0) {
    *error =
        "outer_rounds (spline refits of the whole run) cannot be "
        "combined with the incremental mode";
    return false;
  }
  // Every mean and pilot uses these, in the user's terms.
  if (!CheckLocalizationOptions(options.localization, error)) {
    *error = "prior mean '" + options.prior_mean + "': " + *error;
    return false;
  }
  // Both priors' options, whichever is chosen (the RFF prior may start from
  // a WNOA solve): each model is built once on a unit window, so that the
  // checks are those of the real construction.
  const auto mean = std::make_shared<PiecewiseLinearMean>(
      std::vector<TimedPose>{{0.0, 0.0, 0.0, 0.0}});
  if (!FeatureTrajectory::Create(options.trajectory, mean, 0.0, 1.0, error) ||
      !WnoaTrajectory::Create(options.wnoa, mean, {0.0}, error)) {
    return false;
  }
  if (!CheckCalibrationOptions(options.problem, error)) return false;
  std::unique_ptr<ceres::LossFunction> loss;
  if (!CreateLoss(options.problem.loss, &loss, error)) return false;
  if (!CreateLoss(options.problem.odometry_loss, &loss, error)) {
    *error = "odometry loss: " + *error;
    return false;
  }
  return true;
}

}  // namespace rff
