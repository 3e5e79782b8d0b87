#include "slam_flags.h"

#include "gflags/gflags.h"
#include "rff_ceres/priors/trajectory_prior.h"

// Trajectory prior.
DEFINE_string(prior, "rff",
              "Trajectory prior: rff (weight-space GP features, the paper's "
              "method), wnoa (LTV-SDE white-noise-on-acceleration states, "
              "the gpslam baseline) or wnoj (white-noise-on-jerk states, "
              "STEAM's constant-acceleration prior).");
DEFINE_string(prior_mean, "auto",
              "Prior mean: auto, odometry, wnoa, localization, spline or "
              "constant. auto: with ODOM records in batch mode, wnoa for the "
              "RFF prior (the WNOA posterior mean, which RFF then corrects) "
              "and constant for WNOA (started from dead reckoning, the "
              "odometry counted once); incremental, odometry (dead "
              "reckoning, allowed to turn about its start); without ODOM "
              "records, constant.");
DEFINE_string(initial_trajectory, "auto",
              "Initial value of the trajectory: auto (fit to a localisation "
              "against the landmark priors when one can be built, else the "
              "prior mean) or mean.");
DEFINE_double(localization_position_smoothing, 0.2,
              "Localization mean: acceleration noise density of the position "
              "smoother (m^2/s^3), more than 0; larger follows the fixes more "
              "closely.");
DEFINE_double(localization_heading_smoothing, 0.005,
              "Localization mean: the same for the heading (rad^2/s^3), more "
              "than 0.");
DEFINE_double(localization_correction_smoothing, 1e-4,
              "Localization mean with odometry: density of the smoother of "
              "the correction to dead reckoning, more than 0.");
DEFINE_bool(localization_use_odometry, true,
            "Localization mean: fuse the ODOM records (dead reckoning "
            "corrected towards the fixes) when the dataset has them.");
DEFINE_string(kernel, "rbf",
              "Kernel of x and y: rbf, matern12, matern32, matern52, "
              "periodic.");
DEFINE_string(heading_kernel, "",
              "Kernel of theta: empty (--kernel), rbf, matern12, matern32, "
              "matern52, periodic.");
DEFINE_double(lengthscale, 10.0,
              "Kernel lengthscale of x and y (seconds), more than 0 up to "
              "1e12 (periodic: at least 0.001).");
DEFINE_double(heading_lengthscale, 0.0,
              "Kernel lengthscale of theta (0: --lengthscale); limits as "
              "--lengthscale.");
DEFINE_double(kernel_variance, 4.0,
              "Kernel variance of x and y (m^2): the prior spread of the "
              "trajectory around its mean. More than 0 up to 1e24.");
DEFINE_double(heading_kernel_variance, 0.1,
              "Kernel variance of theta (rad^2), more than 0 up to 1e24.");
DEFINE_double(period, 1.0,
              "Period of the periodic kernel (seconds), more than 0 up to "
              "1e12.");
DEFINE_string(features, "hilbert",
              "Feature family: rff, qmc, gauss_hermite, hilbert.");
DEFINE_int32(num_features, 0,
             "Features per coordinate of x and y (D) per segment; 0 (auto): "
             "D, the segment length and the overlap follow the lengthscales "
             "so that the motion the basis misses stays below 5 cm and "
             "0.005 rad. At most 512; even for rff, qmc and gauss_hermite, "
             "odd for the periodic kernel. Segments x (2 D^2 + D_theta^2) "
             "is at most 2e8 (the prior's memory).");
DEFINE_int32(num_heading_features, 0,
             "Features of theta (0: --num_features). At most 512; needs "
             "--num_features > 0.");
DEFINE_string(learn_hyperparameters, "auto",
              "Learn the prior's hyperparameters from the data: on, off or "
              "auto. RFF: lengthscales and variances of x, y and theta by the "
              "evidence of the exact kernel with the observations linearised "
              "about a WNOA solve (auto: without odometry), and the variances "
              "of the correction to a wnoa mean; WNOA and WNOJ: Q_c and the "
              "factors "
              "on the data's stated sigmas (range, bearing, odometry) by "
              "variance components (Q_c kept where the data leave the "
              "size loose), the RFF prior solving with those of its "
              "WNOA mean. Batch mode only. auto is off when a scale of the "
              "chosen prior is given (command line or flagfile; for rff its "
              "kernel hyperparameters and WNOA's Q_c): they are then the "
              "user's choice.");
DEFINE_uint64(seed, 1,
              "Seed of the random feature frequencies, 0 to 2^64 - 1.");
DEFINE_double(segment_length, 0.0,
              "Windowed weights: segment length in seconds (0: one global "
              "feature map over each stretch of data), 0 or more; at most "
              "100000 segments.");
DEFINE_double(segment_overlap, 0.0,
              "Windowed weights: blend overlap between segments (seconds), 0 "
              "or more, less than --segment_length.");

// WNOA (LTV-SDE) prior.
DEFINE_double(wnoa_position_qc, 1.0,
              "WNOA: power spectral density Q_c of the x and y acceleration "
              "(m^2/s^3), more than 0.");
DEFINE_double(
    wnoa_heading_qc, 0.1,
    "WNOA: Q_c of the heading acceleration (rad^2/s^3), more than 0.");
DEFINE_double(wnoa_initial_position_sigma, 10.0,
              "WNOA and WNOJ: prior sigma of the first state's position "
              "deviation (m), "
              "more than 0.");
DEFINE_double(wnoa_initial_heading_sigma, 1.0,
              "WNOA and WNOJ: prior sigma of the first state's heading "
              "deviation (rad), "
              "more than 0.");
DEFINE_double(wnoa_initial_velocity_sigma, 1.0,
              "WNOA and WNOJ: prior sigma of the first state's velocity "
              "(m/s), more "
              "than 0.");
DEFINE_double(wnoa_initial_angular_velocity_sigma, 1.0,
              "WNOA and WNOJ: prior sigma of the first state's angular "
              "velocity "
              "(rad/s), more than 0.");
DEFINE_string(wnoa_qc_start, "odometry",
              "WNOA: where learning starts Q_c: odometry (the diffusion the "
              "dead reckoning's second differences imply, where the run has "
              "odometry) or given (--wnoa_position_qc, --wnoa_heading_qc).");
DEFINE_double(wnoa_min_state_spacing, 0.0,
              "WNOA: merge states closer than this (seconds), 0 or more; 0 "
              "keeps one per observation time.");

// WNOJ (white-noise-on-jerk) prior.
DEFINE_double(wnoj_position_qc, 1.0,
              "WNOJ: power spectral density Q_c of the x and y jerk "
              "(m^2/s^5), more than 0.");
DEFINE_double(wnoj_heading_qc, 0.1,
              "WNOJ: Q_c of the heading jerk (rad^2/s^5), more than 0.");
DEFINE_double(wnoj_initial_acceleration_sigma, 1.0,
              "WNOJ: prior sigma of the first state's acceleration (m/s^2), "
              "more than 0.");
DEFINE_double(wnoj_initial_angular_acceleration_sigma, 1.0,
              "WNOJ: prior sigma of the first state's angular acceleration "
              "(rad/s^2), more than 0.");
DEFINE_double(wnoj_min_state_spacing, 0.01,
              "WNOJ: merge states closer than this (seconds), 0 or more. Its "
              "prior's information grows as dt^-5: states milliseconds apart "
              "make the system unfactorisable in double precision.");

// Incremental mode.
DEFINE_int32(incremental_every, 0,
             "Incremental mode: feed measurements in time order and re-solve "
             "after every K new range/bearing measurements (0: batch). 0 or "
             "more.");
DEFINE_double(incremental_lag, 0.0,
              "Incremental mode: freeze trajectory blocks untouched for this "
              "many seconds, 0 or more (0: never freeze).");

DEFINE_int32(outer_rounds, 0,
             "Smoothing-spline prior rounds (paper III-B.2): refit the mean "
             "to the estimate and re-solve this many times (at most 100; "
             "0 in incremental mode).");
DEFINE_double(spline_smoothing, 0.98,
              "Smoothing parameter p of the spline mean (De Boor), 0 to 1.");

// Problem.
DEFINE_string(loss, "auto",
              "Robust loss on observations: none, huber, cauchy, auto (cauchy, "
              "then none where no residual is an outlier).");
DEFINE_double(loss_scale, 2.0, "Robust loss scale, in sigmas (0.001 to 1000).");
DEFINE_string(odometry_loss, "auto",
              "Robust loss on odometry residuals: none, huber, cauchy, auto.");
DEFINE_double(odometry_loss_scale, 2.0,
              "Robust odometry loss scale, in sigmas (0.001 to 1000).");
DEFINE_string(range_bearing_ranges, "auto",
              "What the range of a RANGE_BEARING record measures: distance, "
              "depth (along the robot's heading: a camera's range from a "
              "landmark's apparent size) or auto (depth, with the range "
              "calibration estimated, where the first solve's residuals "
              "follow -distance * (1 - cos bearing); batch solves).");
DEFINE_bool(estimate_range_calibration, false,
            "Estimate a range sensor model scale * distance + offset jointly "
            "(one per run) for the ranges of RANGE and RANGE_BEARING records, "
            "for ranges with a systematic bias.");
DEFINE_double(range_scale_sigma, 0.1,
              "Prior sigma of the range scale around 1, more than 0.");
DEFINE_double(range_offset_sigma, 1.0,
              "Prior sigma of the range offset around 0 (m), more than 0.");
DEFINE_bool(estimate_odometry_calibration, false,
            "Estimate the odometry's translation scale and turn scale jointly "
            "(one each per run): the ODOM motion is modelled as the true one "
            "scaled, as commanded velocities and wheel radii have it.");
DEFINE_double(odometry_scale_sigma, 0.1,
              "Prior sigma of both odometry scales around 1, more than 0.");
DEFINE_bool(use_odometry, true, "Add the ODOM records as residuals.");
DEFINE_bool(covariance_truncation, true,
            "With the covariance, add the motion the RFF prior's Hilbert "
            "basis leaves out, through the estimate's response to its next "
            "modes (docs/uncertainty.md); false: the truncated model's "
            "Laplace covariance alone.");
DEFINE_bool(preintegrate_odometry, true,
            "Compose ODOM chains between observation times into one residual "
            "each (first-order covariance).");
DEFINE_double(max_preintegration_seconds, 1.0,
              "Longest time one preintegrated odometry chain may span "
              "(seconds), 0 or more.");

// Ceres.
DEFINE_double(max_memory_gb, 0.0,
              "Largest linear system a solve may form, in GB, 0 or more (0: "
              "half of the machine's memory or of the address-space limit); "
              "a solver whose system is larger is refused before the solve, "
              "naming the size.");
DEFINE_string(linear_solver, "auto",
              "Linear solver: auto (DENSE_SCHUR when at most 2000 "
              "trajectory parameters remain after eliminating the landmarks, "
              "else BANDED_CHOLESKY where its factorisation is cheap and "
              "nothing is bounded, else SPARSE_NORMAL_CHOLESKY), "
              "BANDED_CHOLESKY (our Levenberg-Marquardt on a Cholesky of the "
              "time-ordered system, no bounds), or a Ceres solver: "
              "DENSE_SCHUR, SPARSE_SCHUR, ITERATIVE_SCHUR, DENSE_QR, "
              "DENSE_NORMAL_CHOLESKY, SPARSE_NORMAL_CHOLESKY or CGNR.");
DEFINE_string(preconditioner, "auto",
              "Ceres preconditioner of ITERATIVE_SCHUR and CGNR (the direct "
              "solvers use none and leave it unused): IDENTITY, JACOBI, "
              "SCHUR_JACOBI, CLUSTER_JACOBI, CLUSTER_TRIDIAGONAL; auto picks "
              "SCHUR_JACOBI, or JACOBI for CGNR.");
DEFINE_string(trust_region_strategy, "LEVENBERG_MARQUARDT",
              "LEVENBERG_MARQUARDT or DOGLEG.");
DEFINE_int32(num_threads, 1,
             "Threads for Jacobians and linear algebra. With 1 the outputs "
             "are byte-identical from run to run; with more, Ceres sums in "
             "thread-scheduling order and results differ in the last bits. "
             "1 or more.");
DEFINE_int32(max_iterations, 100,
             "Maximum number of solver iterations (1 or more).");
DEFINE_double(function_tolerance, 1e-8, "Ceres function tolerance, 0 or more.");
DEFINE_double(gradient_tolerance, 1e-10,
              "Ceres gradient tolerance, 0 or more.");
DEFINE_double(parameter_tolerance, 1e-8,
              "Ceres parameter tolerance, 0 or more.");
DEFINE_double(decrement_tolerance, 0.01,
              "BANDED_CHOLESKY: also converged once an undamped step leaves "
              "less than this to gain by the Gauss-Newton model (the cost's "
              "units), 0 or more; 0: Ceres's stopping rules only.");

namespace rff {
namespace {

// True when the user set a scale of the chosen prior, or of the WNOA solve an
// RFF prior starts from (command line or flagfile): "auto" learning then
// keeps the user's values. Another prior's scales leave it alone.
bool PriorScalesGiven() {
  const TrajectoryPrior* prior = FindPrior(FLAGS_prior);
  if (prior == nullptr) return false;  // Validation names the prior.
  for (const std::string& flag : prior->scale_flags()) {
    if (!gflags::GetCommandLineFlagInfoOrDie(flag.c_str()).is_default) {
      return true;
    }
  }
  return false;
}

}  // namespace

SlamOptions SlamOptionsFromFlags() {
  SlamOptions options;
  options.prior = FLAGS_prior;
  options.mean.name = FLAGS_prior_mean;
  options.start.trajectory = FLAGS_initial_trajectory;
  LocalizationOptions& localization = options.localization;
  localization.position_smoothing = FLAGS_localization_position_smoothing;
  localization.heading_smoothing = FLAGS_localization_heading_smoothing;
  localization.correction_smoothing = FLAGS_localization_correction_smoothing;
  localization.use_odometry = FLAGS_localization_use_odometry;
  WnoaOptions& w = options.wnoa;
  w.position_qc = FLAGS_wnoa_position_qc;
  w.heading_qc = FLAGS_wnoa_heading_qc;
  w.initial_position_sigma = FLAGS_wnoa_initial_position_sigma;
  w.initial_heading_sigma = FLAGS_wnoa_initial_heading_sigma;
  w.initial_velocity_sigma = FLAGS_wnoa_initial_velocity_sigma;
  w.initial_angular_velocity_sigma = FLAGS_wnoa_initial_angular_velocity_sigma;
  w.min_state_spacing = FLAGS_wnoa_min_state_spacing;
  w.qc_start = FLAGS_wnoa_qc_start;
  WnojOptions& j = options.wnoj;
  j.position_qc = FLAGS_wnoj_position_qc;
  j.heading_qc = FLAGS_wnoj_heading_qc;
  j.initial_acceleration_sigma = FLAGS_wnoj_initial_acceleration_sigma;
  j.initial_angular_acceleration_sigma =
      FLAGS_wnoj_initial_angular_acceleration_sigma;
  j.min_state_spacing = FLAGS_wnoj_min_state_spacing;
  options.incremental.every = FLAGS_incremental_every;
  options.incremental.lag = FLAGS_incremental_lag;
  options.mean.outer_rounds = FLAGS_outer_rounds;
  options.learn_hyperparameters = FLAGS_learn_hyperparameters;
  if (options.learn_hyperparameters == "auto" && PriorScalesGiven()) {
    options.learn_hyperparameters = "off";
  }
  options.mean.spline_smoothing = FLAGS_spline_smoothing;
  FeatureTrajectoryOptions& t = options.features;
  t.position_kernel.name = FLAGS_kernel;
  t.position_kernel.lengthscale = FLAGS_lengthscale;
  t.position_kernel.variance = FLAGS_kernel_variance;
  t.position_kernel.period = FLAGS_period;
  t.heading_kernel = t.position_kernel;
  if (!FLAGS_heading_kernel.empty())
    t.heading_kernel.name = FLAGS_heading_kernel;
  if (FLAGS_heading_lengthscale != 0.0) {
    t.heading_kernel.lengthscale = FLAGS_heading_lengthscale;
  }
  t.heading_kernel.variance = FLAGS_heading_kernel_variance;
  t.family = FLAGS_features;
  t.num_position_features = FLAGS_num_features;
  t.num_heading_features = FLAGS_num_heading_features != 0
                               ? FLAGS_num_heading_features
                               : FLAGS_num_features;
  t.seed = FLAGS_seed;
  t.segment_length = FLAGS_segment_length;
  t.segment_overlap = FLAGS_segment_overlap;
  options.problem.loss.name = FLAGS_loss;
  options.problem.loss.scale = FLAGS_loss_scale;
  options.problem.odometry_loss.name = FLAGS_odometry_loss;
  options.problem.odometry_loss.scale = FLAGS_odometry_loss_scale;
  options.problem.use_odometry = FLAGS_use_odometry;
  options.problem.range_bearing_ranges = FLAGS_range_bearing_ranges;
  options.output.covariance_truncation = FLAGS_covariance_truncation;
  RangeCalibrationOptions& calibration = options.problem.range_calibration;
  calibration.estimate = FLAGS_estimate_range_calibration;
  calibration.scale_sigma = FLAGS_range_scale_sigma;
  calibration.offset_sigma = FLAGS_range_offset_sigma;
  options.problem.odometry_calibration.estimate =
      FLAGS_estimate_odometry_calibration;
  options.problem.odometry_calibration.scale_sigma = FLAGS_odometry_scale_sigma;
  options.problem.preintegrate_odometry = FLAGS_preintegrate_odometry;
  options.problem.max_preintegration_seconds = FLAGS_max_preintegration_seconds;
  SolverOptions& s = options.solver;
  s.linear_solver = FLAGS_linear_solver;
  s.preconditioner = FLAGS_preconditioner;
  s.trust_region_strategy = FLAGS_trust_region_strategy;
  s.num_threads = FLAGS_num_threads;
  s.max_iterations = FLAGS_max_iterations;
  s.function_tolerance = FLAGS_function_tolerance;
  s.gradient_tolerance = FLAGS_gradient_tolerance;
  s.parameter_tolerance = FLAGS_parameter_tolerance;
  s.decrement_tolerance = FLAGS_decrement_tolerance;
  s.log_progress = true;
  s.max_memory_gb = FLAGS_max_memory_gb;
  return options;
}

bool IsSlamFlag(const std::string& name) {
  // gflags records the file that defines each flag.
  gflags::CommandLineFlagInfo info;
  return gflags::GetCommandLineFlagInfo(name.c_str(), &info) &&
         info.filename == __FILE__;
}

}  // namespace rff
