// The whole RFF-SLAM solve: prior mean, feature trajectory, landmark
// initialisation, the Ceres problem, Levenberg-Marquardt with the landmarks
// eliminated by Schur complement, and the trajectory queried at the output
// times. Apps only translate flags into SlamOptions and print the result.
#ifndef RFF_CERES_SLAM_SOLVER_H_
#define RFF_CERES_SLAM_SOLVER_H_

#include <limits>
#include <map>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "Eigen/Core"
#include "ceres/solver.h"
#include "rff_ceres/ceres_solve.h"  // ToCeresOptions.
#include "rff_ceres/feature_trajectory.h"
#include "rff_ceres/hyperparameter_learning.h"
#include "rff_ceres/initialization.h"
#include "rff_ceres/options.h"
#include "rff_ceres/priors/odometry_diffusion.h"
#include "rff_ceres/quality_report.h"
#include "rff_ceres/range_reading.h"
#include "rff_ceres/residual_drift.h"
#include "rff_ceres/slam_problem.h"
#include "rff_ceres/types.h"
#include "rff_ceres/wnoa_trajectory.h"

namespace rff {

// One re-solve of the incremental mode.
struct IncrementalUpdate {
  double t = 0.0;            // Time of the newest measurement.
  int num_measurements = 0;  // Range/bearing measurements so far.
  int iterations = 0;
  int active_blocks = 0;  // Trajectory blocks not frozen.
  // Residuals of frozen blocks folded into the past's prior so far.
  int folded_residuals = 0;
  double seconds = 0.0;   // Wall time of the update (building + solving).
};

struct SlamResult {
  // Poses at every distinct observation and ground-truth time (the solver
  // reads the GT times, never the GT poses), headings wrapped.
  std::vector<TimedPose> trajectory;
  std::vector<Landmark> landmarks;  // Sorted by id.
  // With output.covariance: the covariance of (x, y, theta) at each
  // trajectory time, and has_covariance set on every landmark.
  std::vector<Eigen::Matrix3d> pose_covariances;
  // What the feature basis's truncation added to them
  // (truncation_covariance.h), or why nothing.
  std::string covariance_truncation;
  // With output.covariance: whether each sensor value's residuals drift
  // together over a landmark's sightings (residual_drift.h), which the
  // covariances, computed for white errors, do not count.
  std::vector<ResidualDrift> residual_drift;
  ceres::Solver::Summary summary;          // Of the last solve.
  int total_iterations = 0;                // Over all outer rounds.
  double solve_seconds = 0.0;              // Wall time of the whole RunSlam.
  bool converged = false;                  // Ceres reported CONVERGENCE.
  std::vector<IncrementalUpdate> updates;  // Incremental mode only.
  StartHeading start_heading;
  // The models as solved: learned kernels and settled capacity (RFF),
  // learned Q_c (WNOA, WNOJ).
  FeatureTrajectoryOptions trajectory_options;
  WnoaOptions wnoa_options;
  WnojOptions wnoj_options;
  bool learned = false;
  LearningReport learning;
  // Rounds of variance-component rescaling of the prior's scales, and the
  // last round's factors (position, heading): about 1 at the fixed point.
  int learning_rounds = 0;
  // The last round's factors were all within 10% of 1 (not the round cap).
  bool learning_converged = false;
  // The Laplace log evidence (variance_components.h) at each round's MAP,
  // and whether the rounds ended at the scales of the round before a fall.
  // Empty under a robust loss, where it guards nothing.
  std::vector<double> scale_log_evidence;
  bool learning_evidence_fell = false;
  // The Laplace log evidence of the data at the scales the learning rounds
  // kept, with the prior's normaliser (TrajectoryModel::PriorLogNormaliser):
  // comparable between the Markov priors on one file, where the rounds
  // measured it (every loss settled to none, every round factorised) about
  // a "constant" mean no outer round refitted; NaN otherwise (a mean built
  // from the data counts them twice).
  double model_log_evidence = std::numeric_limits<double>::quiet_NaN();
  // The rounds that learned the noise sigmas (the WNOA mean's, for an RFF
  // prior about one) ended so.
  bool noise_evidence_fell = false;
  // Noise kinds whose sigma was still falling by more than 10% a round when
  // the rounds reached their cap.
  std::vector<std::string> noise_unsettled;
  // Groups of a correction's variances the data leave at zero (their factor
  // under 0.01): learned by one step down, no further rounds.
  std::vector<std::string> scales_at_boundary;
  // Why the scales kept their values although learning was on (the
  // information matrix numerically singular); empty otherwise.
  std::string scales_not_learned;
  // Why the prior's scales kept their given values while the noise factors
  // were learned (the data hold the trajectory's size too loosely,
  // LearnScales); empty otherwise.
  std::string prior_scales_kept;
  // The same for the WNOA solve a feature prior's solve started from.
  std::string start_prior_scales_kept;
  // The Q_c the WNOA learning rounds started from, where the odometry gave
  // it (windows > 0; TrajectoryPrior::StartLearnedScales), else why the
  // odometry's was not taken (empty without odometry or where not asked).
  OdometryDiffusion qc_from_odometry;
  std::string qc_start_kept;
  Eigen::Vector2d prior_scale_factors = Eigen::Vector2d::Ones();
  // The factors on the data's sigmas the solve ended with: learned with the
  // WNOA prior's scales (and passed on to an RFF solve about it), else 1.
  NoiseScales noise;
  // Kinds whose learned sigma ran towards 0 and went back to the stated one.
  std::vector<std::string> noise_kept;
  // Kinds whose factor the data estimated (others, such as the bearings of a
  // range-only run, keep 1 because nothing measured them).
  std::vector<std::string> noise_learned;
  // The linear solver used and why ("auto" settles on one per problem).
  std::string linear_solver;
  std::string linear_solver_reason;
  std::string initial_trajectory;  // "localization" (the pilot) or "mean".
  std::string prior_mean;          // The mean "auto" settled on.
  double mean_seconds = 0.0;       // Time to build the mean (a "wnoa" solve).
  // What the RANGE_BEARING ranges were read as, "distance" or "depth", and
  // the first solve's evidence where "auto" decided (range_reading.h).
  std::string range_bearing_ranges;
  bool range_reading_judged = false;
  DepthEvidence depth_evidence;
  // The evidence said depths, but read so the first solve's cost was not
  // lower: read as distances.
  bool depth_rejected = false;
  // Why "auto" was not judged (the reading is then distances); empty if it
  // was or a reading was given.
  std::string range_reading_note;
  // (scale, offset) of the range sensor; (1, 0) unless estimated, which
  // the options or a depth reading ask for.
  bool range_calibrated = false;
  Eigen::Vector2d range_calibration = Eigen::Vector2d(1.0, 0.0);
  // (translation scale, turn scale) of the odometry; (1, 1) unless estimated.
  Eigen::Vector2d odometry_calibration = Eigen::Vector2d(1.0, 1.0);
  // Stretches where the solve's heading wound whole turns against the
  // odometry and a solve from the unwound poses ended lower
  // (heading_winding.h), and those the solution still has.
  std::vector<std::string> heading_windings_unwound;
  std::vector<std::string> heading_windings;
  // The whitened residuals at the solution and the verdict on them.
  QualityReport quality;
  // The observation and odometry losses as solved: an "auto" loss settles on
  // "cauchy" or, where its residuals show no outlier, "none".
  std::string loss;
  std::string odometry_loss;
};

// The prior mean "auto" stands for on `dataset`: for the RFF prior in batch
// mode with odometry "wnoa" (the LTV-SDE posterior mean: dead reckoning's
// drift grows along the run, which a non-stationary prior models and a
// stationary kernel about dead reckoning does not; docs/prior_means.md has
// the held-out table), else "odometry" with odometry and "constant" without.
// Any other name is returned as it is.
std::string SettlePriorMean(const SlamOptions& options, const Dataset& dataset);

// Runs the solve. Returns false with a message on bad options or input, and
// when the solve fails or its result is not finite (divergence).
bool RunSlam(const Dataset& dataset, const SlamOptions& options,
             SlamResult* result, std::string* error);

// Times at which RunSlam reports the trajectory: every distinct observation
// and GT_POSE time, or, when there are none, the odometry and prior times.
std::vector<double> OutputTimes(const Dataset& dataset);

}  // namespace rff

#endif  // RFF_CERES_SLAM_SOLVER_H_
