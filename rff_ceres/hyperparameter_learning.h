// Type-II maximum likelihood of the RFF prior's hyperparameters (lengthscale
// and variance of x, y and of theta): the evidence of the exact kernel with
// the observations linearised in pose space about an estimate of the run
// (pose_evidence.h; a Laplace approximation of the data's likelihood, MacKay
// 1992), maximised by a line search per lengthscale with its variance
// profiled out. The capacity (number of features, segments) then follows the
// learned lengthscale (AutoCapacity).
#ifndef RFF_CERES_HYPERPARAMETER_LEARNING_H_
#define RFF_CERES_HYPERPARAMETER_LEARNING_H_

#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "Eigen/Core"
#include "rff_ceres/feature_trajectory.h"
#include "rff_ceres/mean/mean_function.h"
#include "rff_ceres/slam_problem.h"
#include "rff_ceres/types.h"

namespace rff {

// Sets the kernels' variances to the mean square deviation of `initial` (a
// pilot) from `mean`, per kernel (x and y pooled; theta wrapped), where it
// deviates at all: the moment estimate that also starts the evidence search.
void MatchVariancesToSpread(const MeanFunction& mean,
                            const std::vector<TimedPose>& initial,
                            FeatureTrajectoryOptions* trajectory);

struct LearningOptions {
  // The evidence is computed on the first `window` seconds of the run (all
  // of it when shorter) and at most `max_times` observation times:
  // hyperparameters are global, and an evaluation is cubic in the times.
  double window = 300.0;
  int max_times = 400;
  // Search in log space: `sweeps` sweeps over the kernels, the first with
  // steps of `step` (log 2), each next with steps `step_reduction` times
  // shorter; at most `max_steps` uphill per line, a parabolic refinement of
  // each line's maximum.
  double step = std::log(2.0);
  double step_reduction = 4.0;
  int max_steps = 6;
  int sweeps = 2;
  // Bounds of the lengthscales (seconds) and variances (units^2).
  double min_lengthscale = 0.2;
  double max_variance = 1e6;
  double min_variance = 1e-6;
};

struct LearningReport {
  double log_evidence = 0.0;  // At the learned values.
  int evaluations = 0;        // Of the evidence.
  double seconds = 0.0;
  double window_end = 0.0;  // The evidence covers [start, window_end].
  // The data's level (x, y, theta) relative to the mean at the learned
  // values (PoseLogEvidence): where the stationary GP is centred.
  Eigen::Vector3d level = Eigen::Vector3d::Zero();
};

// Learns the kernels' lengthscales and variances of `trajectory` in place,
// starting from its values. `initial` (a solve of the run, such as the WNOA
// one) and `landmarks` are where the observations are linearised.
bool LearnHyperparameters(
    const Dataset& dataset, std::shared_ptr<const MeanFunction> mean,
    const std::vector<TimedPose>& initial,
    const std::map<LandmarkId, Eigen::Vector2d>& landmarks,
    const ProblemOptions& problem_options, const LearningOptions& options,
    FeatureTrajectoryOptions* trajectory, LearningReport* report,
    std::string* error);

}  // namespace rff

#endif  // RFF_CERES_HYPERPARAMETER_LEARNING_H_
