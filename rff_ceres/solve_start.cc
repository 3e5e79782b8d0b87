#include "rff_ceres/solve_start.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <utility>

#include "glog/logging.h"
#include "rff_ceres/batch_solver.h"
#include "rff_ceres/dead_reckoning.h"
#include "rff_ceres/initialization.h"
#include "rff_ceres/mean/prior_mean.h"
#include "rff_ceres/priors/trajectory_prior.h"

namespace rff {
namespace {

// The WNOA solve the RFF prior starts from: a batch solve of its own with
// the same problem options, with its covariance when `covariance`.
bool SolveWnoa(const Dataset& dataset, const SlamOptions& options,
               bool covariance, bool judged, SlamResult* solve,
               std::string* error) {
  SlamOptions wnoa = options;
  wnoa.prior = WnoaPrior().name();
  wnoa.mean.name = "auto";
  wnoa.mean.outer_rounds = 0;
  wnoa.output.covariance = covariance;
  // A mean the estimate corrects is judged with it (SolveFacts).
  wnoa.output.quality = judged && options.output.quality;
  // The user's linear solver is for the RFF solve; banded states want their
  // own (AutoLinearSolverType).
  wnoa.solver.linear_solver = "auto";
  wnoa.solver.preconditioner = "auto";
  return RunSlam(dataset, wnoa, solve, error);
}

}  // namespace

bool InitializeBlocks(const Dataset& start, const SlamOptions& options,
                      TrajectoryModel* model, SlamResult* result,
                      std::string* error) {
  result->initial_trajectory = "mean";
  if (!options.start.poses.empty()) {
    result->initial_trajectory = "given";
    return FitModelToPoses(options.start.poses, model, error);
  }
  if (options.start.trajectory == "mean" || result->prior_mean == "wnoa") {
    return true;
  }
  if (result->prior_mean == "constant" && options.problem.use_odometry &&
      !start.odometry.empty()) {
    // Dead reckoning from the resolved start threads stretches without
    // observations, where a localisation has nothing to go on.
    DeadReckoningResult dead_reckoning;
    DeadReckoningOptions through_gaps;
    through_gaps.hold_through_gaps = true;
    if (!DeadReckon(start, through_gaps, &dead_reckoning, error) ||
        !FitModelToPoses(dead_reckoning.poses, model, error)) {
      return false;
    }
    result->initial_trajectory = "dead reckoning";
    return true;
  }
  if (result->prior_mean == "localization") {
    // The mean is the pilot, localised from the same data with the same
    // options: the model starts on it with its blocks at zero.
    result->initial_trajectory = "localization";
    return true;
  }
  std::vector<TimedPose> pilot;
  std::string why;
  if (!BuildPilotTrajectory(start, options.localization, OutputTimes(start),
                            &pilot, &why)) {
    VLOG(1) << "no pilot trajectory, starting from the mean: " << why;
    return true;
  }
  if (!FitModelToPoses(pilot, model, error)) return false;
  result->initial_trajectory = "localization";
  return true;
}

std::shared_ptr<const MeanFunction> BuildMean(
    const Dataset& dataset, const Dataset& resolved, const SlamOptions& options,
    SlamOptions* warm, SlamOptions* settled, SlamResult* wnoa_mean_solve,
    SlamResult* result, std::string* error) {
  std::shared_ptr<const MeanFunction> mean;
  if (PriorOf(options).has_features() && options.incremental.every == 0 &&
      (result->prior_mean == "wnoa" ||
       (dataset.odometry.empty() && options.start.trajectory == "auto" &&
        options.start.poses.empty()))) {
    SlamResult wnoa;
    const bool wnoa_mean = result->prior_mean == "wnoa";
    if (!SolveWnoa(dataset, options, wnoa_mean && options.output.covariance,
                   wnoa_mean, &wnoa, error)) {
      return nullptr;
    }
    // The same data: a loss the WNOA solve found no outlier for is dropped
    // here too. Its outliers may be its own misfit: the RFF solve decides.
    if (wnoa.loss == "none") settled->problem.loss.name = "none";
    if (wnoa.odometry_loss == "none") {
      settled->problem.odometry_loss.name = "none";
    }
    settled->problem.noise = wnoa.noise;  // Learned from the same data.
    // The same sensors: their ranges read as that solve settled them.
    if (options.problem.range_bearing_ranges == "auto") {
      settled->problem.range_bearing_ranges = wnoa.range_bearing_ranges;
      settled->problem.range_calibration.estimate |=
          wnoa.range_bearing_ranges == "depth";
      result->range_reading_judged = wnoa.range_reading_judged;
      result->depth_evidence = wnoa.depth_evidence;
      result->depth_rejected = wnoa.depth_rejected;
      result->range_reading_note = wnoa.range_reading_note;
    }
    result->noise_kept = wnoa.noise_kept;
    result->noise_learned = wnoa.noise_learned;
    result->noise_unsettled = wnoa.noise_unsettled;
    result->noise_evidence_fell = wnoa.noise_evidence_fell;
    // The solve's landmarks start the RFF solve either way: as a mean, the
    // trajectory is already where the correction starts.
    for (const Landmark& l : wnoa.landmarks) {
      warm->start.landmarks[l.id] = Eigen::Vector2d(l.x, l.y);
    }
    result->qc_from_odometry = wnoa.qc_from_odometry;
    result->qc_start_kept = wnoa.qc_start_kept;
    if (wnoa_mean) {
      // Its Q_c is the mean's; a start only leaves the prior its own.
      result->prior_scales_kept = wnoa.prior_scales_kept;
      mean = std::make_shared<PiecewiseLinearMean>(wnoa.trajectory);
      *wnoa_mean_solve = std::move(wnoa);
    } else {
      warm->start.poses = wnoa.trajectory;
      result->start_prior_scales_kept = wnoa.prior_scales_kept;
    }
  }
  if (!mean) {
    mean = BuildPriorMean(result->prior_mean, resolved, options.localization,
                          options.mean.spline_smoothing, error);
  }
  return mean;
}

double InitialExtent(const Dataset& dataset,
                     const std::vector<TimedPose>& initial,
                     const std::map<LandmarkId, Eigen::Vector2d>& landmarks) {
  double initial_extent = Extent(initial, landmarks);
  for (const LandmarkPrior& p : dataset.landmark_priors) {
    initial_extent = std::max(initial_extent, std::hypot(p.x, p.y));
  }
  double longest_range = 0.0;
  for (const Observation& o : dataset.observations) {
    if (o.HasRange()) {
      longest_range = std::max(longest_range, std::abs(o.range));
    }
  }
  return initial_extent + longest_range;
}

}  // namespace rff
