#include "rff_ceres/slam_solver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <set>
#include <utility>

#include "ceres/types.h"
#include "glog/logging.h"
#include "rff_ceres/batch_solver.h"
#include "rff_ceres/dead_reckoning.h"
#include "rff_ceres/gauss_newton_system.h"
#include "rff_ceres/heading_winding.h"
#include "rff_ceres/incremental_solver.h"
#include "rff_ceres/initialization.h"
#include "rff_ceres/landmark_init.h"
#include "rff_ceres/posterior_covariance.h"
#include "rff_ceres/priors/trajectory_prior.h"
#include "rff_ceres/scale_learning.h"
#include "rff_ceres/solve_start.h"
#include "rff_ceres/truncation_covariance.h"
#include "rff_ceres/variance_components.h"

namespace rff {

std::vector<double> OutputTimes(const Dataset& dataset) {
  std::vector<double> times;
  for (const Observation& o : dataset.observations) times.push_back(o.t);
  for (const TimedPose& p : dataset.ground_truth) times.push_back(p.t);
  if (times.empty()) {
    for (const Odometry& o : dataset.odometry) {
      times.push_back(o.t0);
      times.push_back(o.t1);
    }
    for (const PosePrior& p : dataset.pose_priors) times.push_back(p.pose.t);
  }
  std::sort(times.begin(), times.end());
  times.erase(std::unique(times.begin(), times.end()), times.end());
  return times;
}

namespace {

// What the quality report needs from the solve besides the residuals.
SolveFacts SolveFactsOf(const SlamOptions& options, const SlamResult& result) {
  SolveFacts facts;
  facts.heading_windings = result.heading_windings;
  facts.converged = result.converged;
  facts.termination =
      ceres::TerminationTypeToString(result.summary.termination_type);
  facts.range_calibration = result.range_calibration;
  const double scale = result.range_calibration[0];
  const double offset_bound =
      kMaxOffsetSigmas * options.problem.range_calibration.offset_sigma;
  constexpr double kAtBound = 1e-6;
  // Judged where estimated (settled: depths turn it on).
  facts.range_calibration_at_bound =
      options.problem.range_calibration.estimate &&
      (scale < kMinRangeScale + kAtBound || scale > kMaxRangeScale - kAtBound ||
       std::abs(result.range_calibration[1]) > offset_bound * (1.0 - kAtBound));
  facts.odometry_calibration = result.odometry_calibration;
  facts.odometry_calibration_at_bound =
      result.odometry_calibration.minCoeff() < kMinOdometryScale + kAtBound ||
      result.odometry_calibration.maxCoeff() > kMaxOdometryScale - kAtBound;
  return facts;
}

// Adds the covariance of a mean that is itself an estimate (the WNOA
// solve, at the same output times) to that of the correction around it: the
// RFF weights then carry what the data leave after the mean (about nothing,
// docs/uncertainty.md), and the mean carries the rest. No-op without one.
bool AddMeanCovariance(const SlamResult& mean, SlamResult* result,
                       std::string* error) {
  if (mean.pose_covariances.empty()) return true;
  if (mean.pose_covariances.size() != result->pose_covariances.size()) {
    *error = "the WNOA mean has covariances at " +
             std::to_string(mean.pose_covariances.size()) + " times, the " +
             "estimate at " + std::to_string(result->pose_covariances.size());
    return false;
  }
  for (std::size_t i = 0; i < mean.pose_covariances.size(); ++i) {
    result->pose_covariances[i] += mean.pose_covariances[i];
  }
  std::map<LandmarkId, const Landmark*> by_id;
  for (const Landmark& l : mean.landmarks) by_id[l.id] = &l;
  for (Landmark& l : result->landmarks) {
    const auto it = by_id.find(l.id);
    if (it == by_id.end() || !it->second->has_covariance) continue;
    l.sxx += it->second->sxx;
    l.sxy += it->second->sxy;
    l.syy += it->second->syy;
  }
  return true;
}

}  // namespace

std::string SettlePriorMean(const SlamOptions& options,
                            const Dataset& dataset) {
  if (options.mean.name != "auto") return options.mean.name;
  if (dataset.odometry.empty()) return "constant";
  const bool batch = options.incremental.every == 0;
  if (!batch) return "odometry";
  const TrajectoryPrior* prior = FindPrior(options.prior);
  return prior != nullptr && prior->has_features() ? "wnoa" : "constant";
}

namespace {

// What no option can mend: data with nothing to estimate, an odometry that
// overlaps itself, more landmarks than a covariance can afford.
bool CheckData(const Dataset& dataset, const SlamOptions& options,
               std::string* error) {
  if (dataset.observations.empty() && dataset.odometry.empty()) {
    *error =
        "the dataset has no observations and no odometry: nothing to "
        "estimate";
    return false;
  }
  // The odometry is one chain whichever mean uses it: overlapping records
  // would count the motion in between twice.
  if (options.problem.use_odometry && !dataset.odometry.empty()) {
    DeadReckoningOptions chain;
    chain.hold_through_gaps = true;
    const auto first = std::min_element(
        dataset.odometry.begin(), dataset.odometry.end(),
        [](const Odometry& a, const Odometry& b) { return a.t0 < b.t0; });
    std::vector<TimedPose> nodes;
    std::vector<OdometryGap> gaps;
    if (!IntegrateOdometry({first->t0, 0.0, 0.0, 0.0}, dataset.odometry, chain,
                           &nodes, &gaps, error)) {
      return false;
    }
  }
  // A self-calibration needs records of the sensor it calibrates.
  const bool ranges =
      std::any_of(dataset.observations.begin(), dataset.observations.end(),
                  [](const Observation& o) { return o.HasRange(); });
  if (options.problem.range_calibration.estimate && !ranges) {
    *error =
        "--estimate_range_calibration: the dataset has no RANGE or "
        "RANGE_BEARING records, no range to calibrate";
    return false;
  }
  if (options.problem.odometry_calibration.estimate &&
      (dataset.odometry.empty() || !options.problem.use_odometry)) {
    *error = std::string("--estimate_odometry_calibration: ") +
             (dataset.odometry.empty() ? "the dataset has no ODOM records"
                                       : "--use_odometry=false leaves out "
                                         "the ODOM records") +
             ", no odometry to calibrate";
    return false;
  }
  // The prior's size limits over the data's times, before any solve: its
  // mean comes later, but the model's size does not depend on it.
  if (!CreateTrajectoryModel(dataset, options, UnitWindowMean(), error)) {
    return false;
  }
  if (options.output.covariance) {
    std::set<LandmarkId> ids;
    for (const LandmarkPrior& p : dataset.landmark_priors) ids.insert(p.id);
    for (const Observation& o : dataset.observations) ids.insert(o.id);
    if (ids.size() > kMaxCovarianceLandmarks) {
      *error = "the covariance of " + std::to_string(ids.size()) +
               " landmarks is more than the " +
               std::to_string(kMaxCovarianceLandmarks) +
               " supported (each costs a solve of the whole system); solve "
               "without --output_covariance";
      return false;
    }
  }
  return true;
}

// The prior's scales the learning left a variance: not at zero.
std::set<TrajectoryModel::PriorScale> ScalesWithVariance(
    const SlamResult& result) {
  std::set<TrajectoryModel::PriorScale> scales;
  for (const auto& [scale, group] :
       {std::pair(TrajectoryModel::PriorScale::kPosition,
                  VarianceGroup::kPriorPosition),
        std::pair(TrajectoryModel::PriorScale::kHeading,
                  VarianceGroup::kPriorHeading)}) {
    const std::vector<std::string>& zero = result.scales_at_boundary;
    if (std::find(zero.begin(), zero.end(), VarianceGroupName(group)) ==
        zero.end()) {
      scales.insert(scale);
    }
  }
  return scales;
}

// Fills `result` from the solved problem: the losses and models as
// settled, the quality verdict, the landmarks and, when asked, the
// covariances.
bool ReportSolution(const Dataset& dataset, const SlamOptions& options,
                    const SlamResult& wnoa_mean_solve,
                    const TrajectoryModel& model,
                    const std::map<LandmarkId, Eigen::Vector2d>& landmarks,
                    SlamOptions* settled, SlamProblem* problem,
                    SlamResult* result, std::string* error) {
  result->noise = settled->problem.noise;
  // Incremental updates read ranges as distances unless told otherwise.
  result->range_bearing_ranges =
      settled->problem.range_bearing_ranges == "depth" ? "depth" : "distance";
  result->range_calibrated = settled->problem.range_calibration.estimate;
  // Incremental updates keep an "auto" loss robust throughout.
  for (LossOptions* loss :
       {&settled->problem.loss, &settled->problem.odometry_loss}) {
    if (loss->name == "auto") loss->name = "cauchy";
  }
  result->loss = settled->problem.loss.name;
  result->odometry_loss = settled->problem.odometry_loss.name;
  // An RFF prior about a WNOA solve reports the Q_c that solve learned, not
  // its own unused WNOA options.
  result->wnoa_options = wnoa_mean_solve.trajectory.empty()
                             ? settled->wnoa
                             : wnoa_mean_solve.wnoa_options;
  result->wnoj_options = settled->wnoj;
  // And what that solve unwound on its way.
  result->heading_windings_unwound.insert(
      result->heading_windings_unwound.begin(),
      wnoa_mean_solve.heading_windings_unwound.begin(),
      wnoa_mean_solve.heading_windings_unwound.end());
  PriorOf(options).RecordModel(model, result);
  const std::vector<double>& evidence = result->scale_log_evidence;
  // Not where the learning stopped short, or outer rounds refitted the mean
  // to the estimate.
  if (!evidence.empty() && result->scales_not_learned.empty() &&
      result->prior_mean == "constant" && options.mean.outer_rounds == 0 &&
      !PriorOf(options).has_features()) {
    // After a fall the rounds went back to the scales before it.
    const bool fell = result->learning_evidence_fell && evidence.size() > 1;
    result->model_log_evidence =
        evidence[evidence.size() - (fell ? 2 : 1)] + model.PriorLogNormaliser();
  }
  if (!problem->CheckLandmarksDetermined(1e12, error)) return false;
  if (options.output.quality) {
    // Judged against the data as stated: learned sigmas would absorb a
    // misfit.
    SolveFacts facts = SolveFactsOf(*settled, *result);
    facts.mean_reasons = wnoa_mean_solve.quality.solve_reasons;
    facts.predicted_decrease =
        options.incremental.every == 0
            ? GaussNewtonDecrease(problem, &facts.predicted_decrease_exact)
            : std::numeric_limits<double>::quiet_NaN();
    result->quality = AssessQuality(
        problem->WhitenedResidualsByKind(/*stated_sigmas=*/true), facts);
  } else {
    result->quality.verdict = "not judged";  // Not the default "ok".
  }
  for (const auto& [id, position] : landmarks) {
    Landmark l;
    l.id = id;
    l.x = position.x();
    l.y = position.y();
    result->landmarks.push_back(l);
  }
  if (options.output.covariance) {
    std::vector<double> times;
    for (const TimedPose& p : result->trajectory) times.push_back(p.t);
    CovarianceOptions covariance_options;
    covariance_options.num_threads = options.solver.num_threads;
    if (!ComputePosteriorCovariance(problem, model, times, covariance_options,
                                    &result->pose_covariances,
                                    &result->landmarks, error)) {
      // Away from a minimum the Hessian need not be positive definite.
      const std::vector<std::string>& why = result->quality.solve_reasons;
      for (std::size_t i = 0; i < why.size(); ++i) {
        *error += (i == 0 ? "; the solve it is taken at is suspect: " : "; ") +
                  why[i];
      }
      return false;
    }
    if (!PriorOf(options).has_features()) {
      // Markov states truncate nothing.
    } else if (!options.output.covariance_truncation) {
      result->covariance_truncation = "none: not asked for";
    } else if (options.incremental.every > 0) {
      result->covariance_truncation = "none: an incremental solve";
    } else {
      AddTruncationCovariance(dataset, settled->problem, problem, model,
                              ScalesWithVariance(*result), times,
                              &result->pose_covariances, &result->landmarks,
                              &result->covariance_truncation);
    }
    if (!AddMeanCovariance(wnoa_mean_solve, result, error)) return false;
    for (const auto& [group, series] : problem->ObservationResidualSeries()) {
      result->residual_drift.push_back(
          MeasureResidualDrift(VarianceGroupName(group), series));
    }
  }
  return true;
}

bool RunSlamAtOrigin(const Dataset& dataset, const SlamOptions& given,
                     SlamResult* result, std::string* error) {
  const auto start = std::chrono::steady_clock::now();
  *result = SlamResult();
  ceres::Solver::Options ceres_options;
  if (!ToCeresOptions(given.solver, &ceres_options, error)) return false;
  if (!ValidateSlamOptions(given, error)) return false;
  if (!CheckData(dataset, given, error)) return false;
  // WNOA learns its Q_c and the data's noise scales (LearnScales): its
  // prior is the only motion model besides the odometry, whose sigmas, like
  // the sensors', are the recording's guess.
  const TrajectoryPrior& prior = PriorOf(given);
  const bool wnoa_learns =
      !prior.has_features() && given.learn_hyperparameters != "off";
  // Its rounds (batch solves only) start where the data put its scales.
  SlamOptions options = given;
  if (wnoa_learns && options.incremental.every == 0) {
    prior.StartLearnedScales(dataset, &options, result);
  }
  const IncrementalOptions& incremental = options.incremental;

  // The start (heading, pilot) may come from the data.
  const Dataset resolved = ResolveStartHeading(dataset, &result->start_heading);
  result->prior_mean = SettlePriorMean(options, dataset);
  // The options with the initial value a WNOA solve gives (BuildMean).
  SlamOptions warm = options;
  // The options as they settle: losses, learned scales and kernels.
  SlamOptions settled = options;
  // A "wnoa" mean is an estimate: its covariance joins the correction's.
  SlamResult wnoa_mean_solve;
  const auto mean_start = std::chrono::steady_clock::now();
  std::shared_ptr<const MeanFunction> mean =
      BuildMean(dataset, resolved, options, &warm, &settled, &wnoa_mean_solve,
                result, error);
  if (!mean) return false;
  result->mean_seconds = std::chrono::duration<double>(
                             std::chrono::steady_clock::now() - mean_start)
                             .count();
  std::unique_ptr<TrajectoryModel> model =
      CreateTrajectoryModel(dataset, options, mean, error);
  if (!model) return false;
  if (!InitializeBlocks(resolved, warm, model.get(), result, error)) {
    return false;
  }
  if (options.start.poses.empty() && !warm.start.poses.empty()) {
    result->initial_trajectory = "wnoa";
  }

  // The landmarks' initial positions and the initial trajectory: the scale
  // of the initial scene (InitialExtent).
  std::map<LandmarkId, Eigen::Vector2d> landmarks;
  if (incremental.every == 0 &&
      !InitializeLandmarks(
          resolved, [&](double t) { return model->Pose(t); }, &landmarks,
          error)) {
    return false;
  }
  for (const auto& [id, position] : warm.start.landmarks) {
    if (landmarks.count(id)) landmarks[id] = position;
  }
  std::vector<TimedPose> initial;
  for (const double t : OutputTimes(dataset)) {
    const Eigen::Vector3d pose = model->Pose(t);
    initial.push_back({t, pose.x(), pose.y(), pose.z()});
  }
  const bool search =
      options.learn_hyperparameters == "on" ||
      (options.learn_hyperparameters == "auto" && dataset.odometry.empty());
  // With a "wnoa" mean the RFF weights are a correction to a solve of the
  // same data: its variances start at what the capacity rule resolves and
  // are learned from the data (LearnScales).
  const bool correction = prior.has_features() &&
                          result->prior_mean == "wnoa" &&
                          options.learn_hyperparameters != "off";
  if (correction) {
    FeatureTrajectoryOptions& t = settled.features;
    t.position_kernel.variance = std::pow(2.0 * t.capacity_position_sigma, 2);
    t.heading_kernel.variance = std::pow(2.0 * t.capacity_heading_sigma, 2);
    model = CreateTrajectoryModel(dataset, settled, mean, error);
    if (!model) return false;
  }
  if (prior.has_features() && options.learn_hyperparameters == "auto" &&
      !search && result->initial_trajectory == "localization") {
    // Drift of dead reckoning: its size from the pilot, its time scale given.
    MatchVariancesToSpread(*mean, initial, &settled.features);
    model = CreateTrajectoryModel(dataset, settled, mean, error);
    if (!model || !FitModelToPoses(initial, model.get(), error)) return false;
  }
  if (prior.has_features() && incremental.every == 0 && search) {
    // Linearised about (and the learned model started from) the WNOA solve
    // where there is one: the fit of the features to it is only as good as
    // their starting hyperparameters.
    const std::vector<TimedPose>& about =
        warm.start.poses.empty() ? initial : warm.start.poses;
    if (!LearnHyperparameters(resolved, mean, about, landmarks, settled.problem,
                              options.learning, &settled.features,
                              &result->learning, error)) {
      *error = "learning the hyperparameters: " + *error;
      return false;
    }
    result->learned = true;
    mean = std::make_shared<ShiftedMean>(mean, result->learning.level);
    model = CreateTrajectoryModel(dataset, settled, mean, error);
    if (!model || !FitModelToPoses(about, model.get(), error)) return false;
  }
  const double initial_extent = InitialExtent(dataset, initial, landmarks);

  ProgressLogger progress;
  if (options.solver.log_progress) ceres_options.callbacks.push_back(&progress);
  AbortCheck abort_check(options.solver.should_abort);
  if (options.solver.should_abort) {
    ceres_options.callbacks.push_back(&abort_check);
  }
  std::unique_ptr<SlamProblem> problem;
  if (incremental.every > 0) {
    if (!IncrementalSolver(dataset, settled, ceres_options, model.get(),
                           &landmarks, &problem, result)
             .Solve(error) ||
        !CollectTrajectory(dataset, *model, landmarks, initial_extent, result,
                           error)) {
      return false;
    }
  } else if (!SolveBatch(dataset, settled,
                         JudgingOptions(settled.problem, ceres_options),
                         model.get(), &landmarks, initial_extent, &problem,
                         result, error)) {
    return false;
  } else {
    // Judged at a minimum only: the residuals of a solve cut short may
    // follow any regressor.
    const bool to_read =
        settled.problem.range_bearing_ranges == "auto" &&
        std::any_of(dataset.observations.begin(), dataset.observations.end(),
                    [](const Observation& o) {
                      return o.type == ObservationType::kRangeBearing;
                    });
    if (to_read && result->summary.termination_type != ceres::CONVERGENCE) {
      result->range_reading_note = "auto not judged: the first solve ended " +
                                   std::string(ceres::TerminationTypeToString(
                                       result->summary.termination_type));
    } else if (to_read) {
      result->depth_evidence = MeasureDepthEvidence(
          resolved, [&](double t) { return model->Pose(t); }, landmarks);
      result->range_reading_judged = true;
      const double distance_cost = result->summary.final_cost;
      auto judge_again = [&] {
        problem.reset();  // Another cost per range-bearing record.
        return SolveBatch(
            dataset, settled, JudgingOptions(settled.problem, ceres_options),
            model.get(), &landmarks, initial_extent, &problem, result, error);
      };
      if (SettleRangeReading(result->depth_evidence, &settled.problem)) {
        if (!judge_again()) return false;
        if (!(result->summary.final_cost < distance_cost)) {
          // Depths that fit no better than distances: distances after all.
          settled.problem.range_bearing_ranges = "distance";
          settled.problem.range_calibration.estimate =
              options.problem.range_calibration.estimate;
          if (!settled.problem.range_calibration.estimate) {
            result->range_calibration = Eigen::Vector2d(1.0, 0.0);
          }
          result->depth_rejected = true;
          if (!judge_again()) return false;
        }
      }
    }
    // Finishes the judging solve: a learning round's solves come first.
    const bool judged = SettleAutoLosses(problem.get(), &settled.problem);
    if (wnoa_learns || correction) {
      if (!LearnScales(dataset, mean, ceres_options, initial_extent,
                       /*noise=*/wnoa_learns, /*loose=*/judged, &settled,
                       &model, &landmarks, &problem, result, error)) {
        return false;
      }
    } else if (judged) {
      // The judged losses weight the same residuals: the problem follows.
      const bool reuse = problem->CanFollowScales(settled.problem);
      if (reuse) problem->FollowScales(settled.problem);
      if (!SolveBatch(dataset, settled, ceres_options, model.get(), &landmarks,
                      initial_extent, &problem, result, error, reuse)) {
        return false;
      }
    }
    // A heading that wound whole turns against the odometry is a local
    // minimum the robust loss holds: started again from it unwound.
    UnwindAndSolveAgain(dataset, settled, ceres_options, model.get(),
                        &landmarks, initial_extent, &problem, result);
  }
  if (settled.problem.use_odometry) {
    for (const HeadingWinding& w : FindHeadingWindings(
             dataset, *model, result->odometry_calibration[1])) {
      result->heading_windings.push_back(DescribeWinding(w));
    }
  }
  if (!ReportSolution(dataset, options, wnoa_mean_solve, *model, landmarks,
                      &settled, problem.get(), result, error)) {
    return false;
  }
  result->solve_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
          .count();
  return true;
}

}  // namespace

// Solved about the start: Ceres's parameter tolerance is relative to the
// parameters' size, so a scene 1e9 m from the origin would stop short.
bool RunSlam(const Dataset& dataset, const SlamOptions& options,
             SlamResult* result, std::string* error) {
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();
  if (!dataset.pose_priors.empty()) {
    const TimedPose& start = EarliestPosePrior(dataset).pose;
    origin = Eigen::Vector2d(start.x, start.y);
  }
  if (origin.isZero() || !origin.allFinite()) {
    return RunSlamAtOrigin(dataset, options, result, error);
  }
  SlamOptions centred = options;
  for (TimedPose& p : centred.start.poses) {
    p.x -= origin.x();
    p.y -= origin.y();
  }
  for (auto& [id, position] : centred.start.landmarks) position -= origin;
  if (!RunSlamAtOrigin(Translated(dataset, -origin.x(), -origin.y()), centred,
                       result, error)) {
    return false;
  }
  for (TimedPose& p : result->trajectory) {
    p.x += origin.x();
    p.y += origin.y();
  }
  for (Landmark& l : result->landmarks) {
    l.x += origin.x();
    l.y += origin.y();
  }
  return true;
}

}  // namespace rff
