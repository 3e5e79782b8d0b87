// Type-II maximum likelihood of the RFF prior's hyperparameters (lengthscale
// and variance of x, y and of theta) by the Laplace approximation of the
// marginal likelihood of the whole SLAM problem. With whitened weights
// b ~ N(0, I) and the MAP (b*, l*) of cost C = 1/2 sum ||r||^2,
//
//   log p(data | theta) ~ -C(b*, l*; theta) - 1/2 log det(J^T J) + const,
//
// J the whitened Jacobian at the MAP (Gauss-Newton Hessian; every weight has
// its prior row, so J^T J is positive definite), the constant independent of
// theta (MacKay 1992; Rasmussen & Williams 2006, 3.4). The capacity (number
// of features, segments) follows each candidate lengthscale (AutoCapacity),
// which whitening makes comparable across candidates.
#ifndef RFF_CERES_HYPERPARAMETER_LEARNING_H_
#define RFF_CERES_HYPERPARAMETER_LEARNING_H_

#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "Eigen/Core"
#include "ceres/problem.h"
#include "rff_ceres/feature_trajectory.h"
#include "rff_ceres/mean/mean_function.h"
#include "rff_ceres/slam_problem.h"
#include "rff_ceres/types.h"

namespace rff {

// -C - 1/2 log det(J^T J) at the problem's current values (call at a MAP).
// False when the Gauss-Newton Hessian is not positive definite.
bool LaplaceLogEvidence(ceres::Problem* problem, double* log_evidence,
                        std::string* error);

// Sets the kernels' variances to the mean square deviation of `initial` (a
// pilot) from `mean`, per kernel (x and y pooled; theta wrapped), where it
// deviates at all: the moment estimate that also starts the evidence search.
void MatchVariancesToSpread(const MeanFunction& mean,
                            const std::vector<TimedPose>& initial,
                            FeatureTrajectoryOptions* trajectory);

struct LearningOptions {
  // The evidence is computed on the first `window` seconds of the run (all
  // of it when shorter): hyperparameters are global, and the search costs a
  // MAP solve per candidate.
  double window = 300.0;
  // Search in log space: steps of `step` (log 2), at most `max_steps`
  // uphill per line, a parabolic refinement of each lengthscale.
  double step = std::log(2.0);
  int max_steps = 6;
  int sweeps = 1;
  // Each candidate's solve: iterations from the best candidate's MAP, and
  // the capacity sigmas relaxed by this factor (fewer features).
  int max_solver_iterations = 5;
  double capacity_relaxation = 2.0;
  // Bounds of the lengthscales (seconds) and variances (units^2).
  double min_lengthscale = 0.2;
  double max_variance = 1e6;
  double min_variance = 1e-6;
};

struct LearningReport {
  double log_evidence = 0.0;  // At the learned values.
  int evaluations = 0;        // MAP solves.
  double seconds = 0.0;
  double window_end = 0.0;  // The evidence covers [start, window_end].
};

// Learns the kernels' lengthscales and variances of `trajectory` in place,
// starting from its values. `initial` is the trajectory to start each
// candidate's solve from (fitted), `landmarks` the landmarks' initial values.
bool LearnHyperparameters(
    const Dataset& dataset, std::shared_ptr<const MeanFunction> mean,
    const std::vector<TimedPose>& initial,
    const std::map<LandmarkId, Eigen::Vector2d>& landmarks,
    const ProblemOptions& problem_options, const LearningOptions& options,
    FeatureTrajectoryOptions* trajectory, LearningReport* report,
    std::string* error);

}  // namespace rff

#endif  // RFF_CERES_HYPERPARAMETER_LEARNING_H_
