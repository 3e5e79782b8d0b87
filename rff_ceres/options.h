// The options of a solve (SlamOptions), one nested struct per concern (the
// features, the WNOA states, the problem, the solver, the incremental mode,
// the localisation mean), built from flags in one place (apps/slam_flags.cc,
// which Python shares) and checked by one ValidateSlamOptions before any file
// is read.
#ifndef RFF_CERES_OPTIONS_H_
#define RFF_CERES_OPTIONS_H_

#include <map>
#include <string>
#include <vector>

#include "Eigen/Core"
#include "rff_ceres/ceres_solve.h"  // SolverOptions.
#include "rff_ceres/feature_trajectory.h"
#include "rff_ceres/hyperparameter_learning.h"
#include "rff_ceres/mean/localization_mean.h"
#include "rff_ceres/slam_problem.h"
#include "rff_ceres/types.h"
#include "rff_ceres/wnoa_trajectory.h"
#include "rff_ceres/wnoj_trajectory.h"

namespace rff {

// Incremental mode (the paper's Plaza protocol): measurements are fed in time
// order and the problem is re-solved, warm-started, after every `every` new
// range/bearing measurements.
struct IncrementalOptions {
  int every = 0;  // K; 0: one batch solve.
  // Trajectory blocks not touched by a measurement in the last `lag` seconds
  // are frozen (held constant); 0: none is frozen.
  double lag = 0.0;
};

// Through Ceres's covariance (WNOA, or RFF without the Schur form of
// posterior_covariance.cc) each landmark's covariance costs column solves of
// the whole information matrix (10000 landmarks on a 300-pose run: about
// 15 s); the Schur form is linear in the landmarks.
inline constexpr std::size_t kMaxCovarianceLandmarks = 10000;

// Refits of the spline mean stop changing it after a few rounds (III-B.2).
inline constexpr int kMaxOuterRounds = 100;

// The prior mean mu(t) and the paper's spline rounds about it.
struct MeanOptions {
  // Prior mean (prior_mean.h). "auto" settles per dataset (SettlePriorMean):
  // for the RFF prior in batch mode with odometry, "wnoa".
  std::string name = "auto";
  // Outer rounds of the paper's smoothing-spline prior (III-B.2): after each
  // solve, refit the mean to the estimate and solve again. 0: one solve; at
  // most kMaxOuterRounds.
  int outer_rounds = 0;
  double spline_smoothing = 0.98;  // De Boor's p.
};

// Where the solve starts.
struct StartOptions {
  // Initial value of the blocks: "auto" fits them to a localisation pilot
  // (initialization.h) when one can be built; "mean" starts at the mean.
  std::string trajectory = "auto";
  // A warm start that overrides `trajectory`: the blocks are fitted to these
  // poses (sorted by time) and these landmarks start here (the others are
  // initialised from their observations as usual).
  std::vector<TimedPose> poses;
  std::map<LandmarkId, Eigen::Vector2d> landmarks;
};

// What the solve reports besides the trajectory and the landmarks.
struct OutputOptions {
  // Posterior covariance of every output pose and landmark (see
  // posterior_covariance.h); for at most kMaxCovarianceLandmarks landmarks.
  bool covariance = false;
  // With it, what a feature basis's truncation adds (truncation_covariance.h):
  // off, the Laplace covariance of the truncated model alone.
  bool covariance_truncation = true;
  // The quality verdict (quality_report.h). Off only for the WNOA solve an
  // RFF prior's mean or start comes from: the RFF solve judges its own.
  bool quality = true;
};

struct SlamOptions {
  // Trajectory prior, by its registry name (priors/trajectory_prior.h):
  // "rff" (weight-space features), "wnoa" (LTV-SDE states, white noise on
  // acceleration) or "wnoj" (white noise on jerk).
  std::string prior = "rff";
  MeanOptions mean;
  StartOptions start;
  // Tuning of the "localization" mean and pilot (docs/prior_means.md).
  LocalizationOptions localization;
  // The RFF prior's features and kernels (FeatureTrajectory).
  FeatureTrajectoryOptions features;
  // Learn the prior's hyperparameters: the RFF kernels' lengthscales and
  // variances (batch mode), starting from `features`'
  // (hyperparameter_learning.h): "on", "off", or "auto", on for data without
  // odometry. With odometry the GP models the drift of dead reckoning, which
  // grows along the run: a stationary kernel learned on a window misjudges
  // it (docs/prior_means.md, "RFF with odometry"). WNOA and WNOJ learn Q_c
  // and the noise scales of the data unless "off".
  std::string learn_hyperparameters = "auto";
  LearningOptions learning;
  // The Markov-state priors; the first state's position, heading and
  // velocity sigmas in `wnoa` serve both.
  WnoaOptions wnoa;
  WnojOptions wnoj;
  // The data's residuals: noise scales, losses, odometry, calibration.
  ProblemOptions problem;
  SolverOptions solver;
  IncrementalOptions incremental;
  OutputOptions output;
};

// Checks every option, of both priors whatever the chosen one, with the
// message the user needs ("--flag=value: why; allowed range", option_error.h).
// RunSlam calls it first; apps call it before reading any file.
bool ValidateSlamOptions(const SlamOptions& options, std::string* error);

}  // namespace rff

#endif  // RFF_CERES_OPTIONS_H_
