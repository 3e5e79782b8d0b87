#include "rff_ceres/slam_solver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <set>
#include <utility>

#include "ceres/types.h"
#include "glog/logging.h"
#include "rff_ceres/data_stretches.h"
#include "rff_ceres/dead_reckoning.h"
#include "rff_ceres/initialization.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/landmark_init.h"
#include "rff_ceres/linear_system_size.h"
#include "rff_ceres/mean/prior_mean.h"
#include "rff_ceres/mean/spline_mean.h"
#include "rff_ceres/mean_rotation.h"
#include "rff_ceres/option_error.h"
#include "rff_ceres/posterior_covariance.h"
#include "rff_ceres/variance_components.h"

namespace rff {
namespace {

// Every time the dataset mentions: the WNOA states reach both ends.
void TimeSpan(const Dataset& dataset, double* begin, double* end) {
  std::vector<double> times = OutputTimes(dataset);
  for (const Odometry& o : dataset.odometry) {
    times.push_back(o.t0);
    times.push_back(o.t1);
  }
  for (const PosePrior& p : dataset.pose_priors) times.push_back(p.pose.t);
  const auto [lo, hi] = std::minmax_element(times.begin(), times.end());
  *begin = *lo;
  *end = *hi;
}

// Logs one line per Levenberg-Marquardt iteration through glog.
class ProgressLogger : public ceres::IterationCallback {
 public:
  ceres::CallbackReturnType operator()(
      const ceres::IterationSummary& s) override {
    LOG(INFO) << "iteration " << s.iteration << ": cost " << s.cost
              << ", cost change " << s.cost_change << ", |gradient| "
              << s.gradient_max_norm << ", |step| " << s.step_norm
              << ", trust radius " << s.trust_region_radius << ", "
              << (s.step_is_successful ? "accepted" : "rejected") << ", "
              << s.cumulative_time_in_seconds << " s";
    return ceres::SOLVER_CONTINUE;
  }
};

// The preconditioners a flag can choose (SUBSET cannot be set up from one).
constexpr char kPreconditioners[] =
    "auto, IDENTITY, JACOBI, SCHUR_JACOBI, CLUSTER_JACOBI or "
    "CLUSTER_TRIDIAGONAL";

// Stops the solve when the caller's SolverOptions::should_abort says so.
class AbortCheck : public ceres::IterationCallback {
 public:
  explicit AbortCheck(std::function<bool()> should_abort)
      : should_abort_(std::move(should_abort)) {}
  ceres::CallbackReturnType operator()(
      const ceres::IterationSummary&) override {
    return should_abort_() ? ceres::SOLVER_ABORT : ceres::SOLVER_CONTINUE;
  }

 private:
  std::function<bool()> should_abort_;
};

}  // namespace

bool ToCeresOptions(const SolverOptions& options,
                    ceres::Solver::Options* ceres_options, std::string* error) {
  // "auto" is settled per problem by ChooseLinearSolver; until then the
  // sparse Cholesky, whose options are always valid.
  std::string name = options.linear_solver == "auto" ? "SPARSE_NORMAL_CHOLESKY"
                                                     : options.linear_solver;
  if (!ceres::StringToLinearSolverType(name,
                                       &ceres_options->linear_solver_type)) {
    *error = OptionError("linear_solver", options.linear_solver,
                         "unknown linear solver",
                         "auto, DENSE_SCHUR, SPARSE_SCHUR, ITERATIVE_SCHUR, "
                         "DENSE_QR, DENSE_NORMAL_CHOLESKY, "
                         "SPARSE_NORMAL_CHOLESKY or CGNR");
    return false;
  }
  // "auto": the preconditioner each iterative solver supports best.
  name = options.preconditioner;
  if (name == "auto") {
    name = ceres_options->linear_solver_type == ceres::CGNR ? "JACOBI"
                                                            : "SCHUR_JACOBI";
  }
  if (!ceres::StringToPreconditionerType(name,
                                         &ceres_options->preconditioner_type)) {
    *error = OptionError("preconditioner", options.preconditioner,
                         "unknown preconditioner", kPreconditioners);
    return false;
  }
  // SUBSET needs residual blocks chosen for it, which no flag can give.
  if (ceres_options->preconditioner_type == ceres::SUBSET) {
    *error = OptionError("preconditioner", options.preconditioner,
                         "needs residual blocks chosen for it, which no flag "
                         "gives",
                         kPreconditioners);
    return false;
  }
  // Ceres 2.1's CGNR aborts on any other preconditioner.
  if (ceres_options->linear_solver_type == ceres::CGNR &&
      ceres_options->preconditioner_type != ceres::IDENTITY &&
      ceres_options->preconditioner_type != ceres::JACOBI) {
    *error = OptionError("preconditioner", options.preconditioner,
                         "--linear_solver=CGNR takes IDENTITY or JACOBI only",
                         "auto, IDENTITY or JACOBI with CGNR");
    return false;
  }
  name = options.trust_region_strategy;
  if (!ceres::StringToTrustRegionStrategyType(
          name, &ceres_options->trust_region_strategy_type)) {
    *error = OptionError("trust_region_strategy", options.trust_region_strategy,
                         "unknown trust region strategy",
                         "LEVENBERG_MARQUARDT or DOGLEG");
    return false;
  }
  for (const auto& [flag, count] :
       {std::pair("num_threads", options.num_threads),
        std::pair("max_iterations", options.max_iterations)}) {
    if (count < 1) {
      *error = OptionError(flag, std::to_string(count), "", "1 or more");
      return false;
    }
  }
  for (const auto& [flag, tolerance] :
       {std::pair("function_tolerance", options.function_tolerance),
        std::pair("gradient_tolerance", options.gradient_tolerance),
        std::pair("parameter_tolerance", options.parameter_tolerance)}) {
    if (!CheckNonNegativeOption(tolerance, flag, error)) return false;
  }
  ceres_options->num_threads = options.num_threads;
  ceres_options->max_num_iterations = options.max_iterations;
  ceres_options->function_tolerance = options.function_tolerance;
  ceres_options->gradient_tolerance = options.gradient_tolerance;
  ceres_options->parameter_tolerance = options.parameter_tolerance;
  ceres_options->minimizer_progress_to_stdout = false;
  ceres_options->logging_type = ceres::SILENT;
  std::string why;
  if (!ceres_options->IsValid(&why)) {
    *error = "invalid solver options: " + why;
    return false;
  }
  return true;
}

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

std::unique_ptr<TrajectoryModel> CreateTrajectoryModel(
    const Dataset& dataset, const SlamOptions& options,
    std::shared_ptr<const MeanFunction> mean, std::string* error) {
  const std::string mean_name = SettlePriorMean(options, dataset);
  std::unique_ptr<TrajectoryModel> model;
  if (options.prior == "rff") {
    model = FeatureTrajectory::Create(options.trajectory, mean,
                                      DataTimesOf(dataset), error);
  } else if (options.prior == "wnoa") {
    // A state at every distinct observation time, and at both ends of the
    // run so that no query extrapolates. A constant mean leaves the motion
    // to the states: one at each end of every odometry residual too, or the
    // cubic between states could not follow it (a 64 s stretch without
    // observations would be one cubic).
    double t_begin, t_end;
    TimeSpan(dataset, &t_begin, &t_end);
    std::vector<double> times = {t_begin, t_end};
    for (const Observation& o : dataset.observations) times.push_back(o.t);
    std::vector<PreintegratedOdometry> chains;
    if (mean_name == "constant" &&
        !OdometryChains(dataset, options.problem, &chains, error)) {
      return nullptr;
    }
    for (const PreintegratedOdometry& chain : chains) {
      times.push_back(chain.t0);
      times.push_back(chain.t1);
    }
    model = WnoaTrajectory::Create(options.wnoa, mean, std::move(times), error);
  } else {
    *error =
        OptionError("prior", options.prior, "unknown prior", "rff or wnoa");
    return nullptr;
  }
  if (!model || mean_name != "odometry") return model;
  // Dead reckoning carries the error of its start heading: let it turn.
  const PosePrior& start = EarliestPosePrior(dataset);
  return std::make_unique<MeanRotationTrajectory>(
      std::move(model), std::move(mean), start.pose.t,
      std::min(start.sigma_theta, kLooseHeadingSigma));
}

namespace {

// "auto" settles on AutoLinearSolverType; an explicit choice is obeyed.
void ChooseLinearSolver(const SolverOptions& solver,
                        const TrajectoryModel& model,
                        ceres::Solver::Options* options, SlamResult* result) {
  if (solver.linear_solver != "auto") {
    result->linear_solver = solver.linear_solver;
    result->linear_solver_reason = "as asked";
    return;
  }
  int trajectory_parameters = 0;
  for (int b = 0; b < model.num_blocks(); ++b) {
    trajectory_parameters += model.block_size(b);
  }
  options->linear_solver_type = AutoLinearSolverType(model);
  const bool dense = options->linear_solver_type == ceres::DENSE_SCHUR;
  result->linear_solver =
      ceres::LinearSolverTypeToString(options->linear_solver_type);
  const std::string count =
      std::to_string(trajectory_parameters) + " trajectory parameters";
  result->linear_solver_reason =
      dense ? count + " <= " + std::to_string(kMaxDenseReducedSystem) +
                  ": the reduced system is small and dense"
      : model.HasDenseReducedSystem()
          ? count + " > " + std::to_string(kMaxDenseReducedSystem) +
                ": sparse factorisation of the whole system"
          : count +
                " in banded states: sparse factorisation of the whole "
                "system";
}

// Schur solvers eliminate the landmarks first. The others get no ordering:
// their fill-reducing ordering (AMD) puts landmarks seen from the whole run
// last, where eliminating them first would make the system dense (the WNOA
// states of Plaza: 3500 states, 4 landmarks).
void SetOrdering(SlamProblem* problem, ceres::Solver::Options* options) {
  const ceres::LinearSolverType type = options->linear_solver_type;
  if (type == ceres::DENSE_SCHUR || type == ceres::SPARSE_SCHUR ||
      type == ceres::ITERATIVE_SCHUR) {
    options->linear_solver_ordering = problem->Ordering();
  } else {
    options->linear_solver_ordering.reset();
  }
}

// A solve is accepted only if Ceres did not fail and the cost is finite.
// On failure the first non-finite residual is named, when there is one.
bool CheckSolve(const ceres::Solver::Summary& summary, SlamProblem* problem,
                std::string* error) {
  if (summary.termination_type != ceres::FAILURE &&
      summary.termination_type != ceres::USER_FAILURE &&
      std::isfinite(summary.final_cost)) {
    return true;
  }
  std::string culprit;
  *error = "the solve failed: " + summary.message;
  if (problem->FindNonFinite(&culprit)) *error += " (" + culprit + ")";
  return false;
}

// Largest |coordinate| of the poses and landmarks, for the runaway check.
double Extent(const std::vector<TimedPose>& poses,
              const std::map<LandmarkId, Eigen::Vector2d>& landmarks) {
  double extent = 0.0;
  for (const TimedPose& p : poses) {
    extent = std::max({extent, std::abs(p.x), std::abs(p.y)});
  }
  for (const auto& [id, l] : landmarks) extent = std::max(extent, l.norm());
  return extent;
}

// The trajectory at the output times, with the divergence guards: every
// value finite, and nothing run away to more than 1000 times the scale of
// the initial scene (which a converged solution never does).
bool CollectTrajectory(const Dataset& dataset, const TrajectoryModel& model,
                       const std::map<LandmarkId, Eigen::Vector2d>& landmarks,
                       double initial_extent, SlamResult* result,
                       std::string* error) {
  result->trajectory.clear();
  for (const double t : OutputTimes(dataset)) {
    const Eigen::Vector3d pose = model.Pose(t);
    if (!pose.allFinite()) {
      *error = "the solve diverged: non-finite pose at t = " + FormatNumber(t);
      return false;
    }
    result->trajectory.push_back({t, pose.x(), pose.y(), WrapAngle(pose.z())});
  }
  for (const auto& [id, position] : landmarks) {
    if (!position.allFinite()) {
      *error = "the solve diverged: non-finite landmark " + std::to_string(id);
      return false;
    }
  }
  const double limit = 1000.0 * (initial_extent + 1.0);
  const double extent = Extent(result->trajectory, landmarks);
  if (extent > limit) {
    *error = "the solve diverged: the estimate reaches " +
             FormatNumber(extent) + " m from the origin, the initial scene " +
             FormatNumber(initial_extent) + " m";
    return false;
  }
  return true;
}

// Where the turn of the mean's start has grown beyond its first-order form
// (kMaxRotationLinearization), applies it exactly and returns true: the
// problem is then solved again about the turned mean.
constexpr double kMaxRotationLinearization = 0.01;  // m
bool FoldMeanRotation(TrajectoryModel* model,
                      const std::vector<double>& times) {
  auto* rotation = dynamic_cast<MeanRotationTrajectory*>(model);
  if (rotation == nullptr ||
      rotation->LinearizationError(times) <= kMaxRotationLinearization) {
    return false;
  }
  VLOG(1) << "turning the mean by " << rotation->delta() << " rad";
  rotation->FoldRotation();
  return true;
}

// Paper III-B.2: after each solve the prior mean becomes a smoothing spline
// of the estimate and the weights restart from zero.
bool SolveBatch(const Dataset& dataset, const SlamOptions& options,
                ceres::Solver::Options ceres_options, TrajectoryModel* model,
                std::map<LandmarkId, Eigen::Vector2d>* landmarks,
                double initial_extent, std::unique_ptr<SlamProblem>* problem,
                SlamResult* result, std::string* error) {
  for (int round = 0;; ++round) {
    *problem = std::make_unique<SlamProblem>(model, options.problem);
    (*problem)->set_range_calibration(result->range_calibration);
    (*problem)->set_odometry_calibration(result->odometry_calibration);
    if (!(*problem)->Build(dataset, *landmarks, error)) return false;
    ChooseLinearSolver(options.solver, *model, &ceres_options, result);
    SetOrdering(problem->get(), &ceres_options);
    if (!CheckLinearSystemFits(problem->get(), ceres_options,
                               options.solver.max_memory_gb, error)) {
      return false;
    }
    ceres::Solve(ceres_options, (*problem)->problem(), &result->summary);
    VLOG(1) << result->summary.FullReport();
    if (!CheckSolve(result->summary, problem->get(), error)) return false;
    result->converged = result->summary.termination_type == ceres::CONVERGENCE;
    result->total_iterations +=
        static_cast<int>(result->summary.iterations.size());
    *landmarks = (*problem)->landmarks();
    result->range_calibration = (*problem)->range_calibration();
    result->odometry_calibration = (*problem)->odometry_calibration();
    if (!CollectTrajectory(dataset, *model, *landmarks, initial_extent, result,
                           error)) {
      return false;
    }
    if (FoldMeanRotation(model, OutputTimes(dataset))) {
      --round;  // The same round again, about the turned mean.
      continue;
    }
    if (round >= options.outer_rounds) return true;
    std::shared_ptr<const MeanFunction> mean =
        RefitSplineMean(result->trajectory,
                        DataFitWeights(dataset, result->trajectory, *landmarks),
                        options.spline_smoothing, error);
    if (!mean) return false;
    model->set_mean(mean);
    for (int b = 0; b < model->num_blocks(); ++b) {
      Eigen::Map<Eigen::VectorXd>(model->mutable_block(b), model->block_size(b))
          .setZero();
    }
  }
}

// The paper's online protocol: measurements in time order, a warm-started
// re-solve after every K of them. Trajectory blocks enter the problem (become
// variable) when a residual first touches them and are frozen once no
// residual has touched them for `lag` seconds; landmarks enter when their
// observations so far locate them.
bool SolveIncremental(const Dataset& dataset, const SlamOptions& options,
                      ceres::Solver::Options ceres_options,
                      TrajectoryModel* model,
                      std::map<LandmarkId, Eigen::Vector2d>* landmarks,
                      std::unique_ptr<SlamProblem>* problem, SlamResult* result,
                      std::string* error) {
  const IncrementalOptions& incremental = options.incremental;
  *problem = std::make_unique<SlamProblem>(model, options.problem);
  SlamProblem& slam = **problem;
  std::vector<LandmarkId> ids;
  for (const LandmarkPrior& p : dataset.landmark_priors) ids.push_back(p.id);
  for (const Observation& o : dataset.observations) ids.push_back(o.id);
  if (!slam.Begin(ids, error)) return false;
  // A landmark that the whole run cannot locate never will be: an error now,
  // not a retry at every update.
  std::map<LandmarkId, Eigen::Vector2d> locatable;
  if (!InitializeLandmarks(
          dataset, [&](double t) { return model->Pose(t); }, &locatable,
          error)) {
    return false;
  }
  ceres::Problem* ceres_problem = slam.problem();
  ChooseLinearSolver(options.solver, *model, &ceres_options, result);

  // Newest time each trajectory block has been touched at (-inf: never).
  std::vector<double> touched(model->num_blocks(),
                              -std::numeric_limits<double>::infinity());
  auto in_use = [&](int b) { return std::isfinite(touched[b]); };
  auto touch = [&](double t) {
    for (const PoseTerm& term : model->PoseAt(t).terms) {
      touched[term.block] = std::max(touched[term.block], t);
    }
  };
  for (const LandmarkPrior& p : dataset.landmark_priors) {
    slam.AddLandmark(p.id, Eigen::Vector2d(p.x, p.y));
    slam.AddLandmarkPrior(p);
  }
  std::vector<PreintegratedOdometry> odometry;
  if (!OdometryChains(dataset, options.problem, &odometry, error)) {
    return false;
  }
  std::size_t next_odometry = 0, next_prior = 0;
  int prior_end = 0;  // Trajectory prior terms added for blocks below this.
  std::vector<Observation> pending;  // Of landmarks not located yet.

  double data_end = -std::numeric_limits<double>::infinity();
  for (const Observation& o : dataset.observations) {
    data_end = std::max(data_end, o.t);
  }
  for (const PreintegratedOdometry& o : odometry) {
    data_end = std::max(data_end, o.t1);
  }
  for (const PosePrior& p : dataset.pose_priors) {
    data_end = std::max(data_end, p.pose.t);
  }
  // Adds the priors and odometry up to `now` and the landmarks that can be
  // located, then solves the blocks in use.
  auto solve_update = [&](double now, int num_measurements) {
    const auto start = std::chrono::steady_clock::now();
    for (; next_prior < dataset.pose_priors.size() &&
           dataset.pose_priors[next_prior].pose.t <= now;
         ++next_prior) {
      slam.AddPosePrior(dataset.pose_priors[next_prior]);
      touch(dataset.pose_priors[next_prior].pose.t);
    }
    for (; next_odometry < odometry.size() && odometry[next_odometry].t1 <= now;
         ++next_odometry) {
      slam.AddOdometry(odometry[next_odometry]);
      touch(odometry[next_odometry].t0);
      touch(odometry[next_odometry].t1);
    }
    if (!pending.empty()) {
      Dataset seen;
      seen.observations = pending;
      std::map<LandmarkId, Eigen::Vector2d> located;
      std::vector<LandmarkId> unlocated;
      InitializeLandmarks(
          seen, [&](double t) { return model->Pose(t); }, &located, error,
          &unlocated);
      std::vector<Observation> still_pending;
      for (const auto& [id, position] : located) slam.AddLandmark(id, position);
      for (const Observation& p : pending) {
        if (slam.has_landmark(p.id)) {
          slam.AddObservation(p);
        } else {
          still_pending.push_back(p);
        }
      }
      pending.swap(still_pending);
    }

    // Prior terms of the blocks in use; a WNOA term to a state still in the
    // future would pin the present to the prior mean.
    int used_end = prior_end;
    for (int b = prior_end; b < model->num_blocks(); ++b) {
      if (in_use(b)) {
        used_end = b + 1;
      }
    }
    model->AddPriorCosts(ceres_problem, prior_end, used_end);
    prior_end = used_end;

    IncrementalUpdate update;
    update.t = std::min(now, data_end);
    update.num_measurements = num_measurements;
    for (int b = 0; b < model->num_blocks(); ++b) {
      const bool active = in_use(b) && (incremental.lag <= 0.0 ||
                                        touched[b] >= now - incremental.lag);
      if (active) {
        ceres_problem->SetParameterBlockVariable(model->mutable_block(b));
        ++update.active_blocks;
      } else {
        ceres_problem->SetParameterBlockConstant(model->mutable_block(b));
      }
    }
    // The preprocessor edits the ordering it is given: a fresh one per solve.
    SetOrdering(&slam, &ceres_options);
    if (!CheckLinearSystemFits(&slam, ceres_options,
                               options.solver.max_memory_gb, error)) {
      return false;
    }
    ceres::Solve(ceres_options, ceres_problem, &result->summary);
    if (!CheckSolve(result->summary, &slam, error)) {
      *error = "update at t = " + FormatNumber(update.t) + ": " + *error;
      return false;
    }
    update.iterations = static_cast<int>(result->summary.iterations.size());
    result->total_iterations += update.iterations;
    update.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
            .count();
    result->updates.push_back(update);
    VLOG(1) << "update at t = " << now << ": " << update.num_measurements
            << " measurements, " << update.active_blocks << " active blocks, "
            << update.iterations << " iterations, " << update.seconds << " s";
    return true;
  };
  const std::vector<Observation>& observations = dataset.observations;
  for (std::size_t i = 0; i < observations.size(); ++i) {
    const Observation& o = observations[i];
    touch(o.t);
    if (slam.has_landmark(o.id)) {
      slam.AddObservation(o);
    } else {
      pending.push_back(o);
    }
    if ((i + 1) % incremental.every != 0) continue;
    if (!solve_update(o.t, static_cast<int>(i + 1))) return false;
  }
  // The data after the last update (the last observations, odometry and
  // priors after them), or all of it when no update ran.
  if (result->updates.empty() || next_odometry < odometry.size() ||
      next_prior < dataset.pose_priors.size() ||
      observations.size() % incremental.every != 0) {
    if (!solve_update(std::numeric_limits<double>::infinity(),
                      static_cast<int>(observations.size()))) {
      return false;
    }
  }
  if (!pending.empty()) {
    *error = "landmark " + std::to_string(pending.front().id) +
             " has no PRIOR_LANDMARK and its observations do not locate it";
    return false;
  }
  // Everything the data touched is a variable again, for the covariance.
  for (int b = 0; b < model->num_blocks(); ++b) {
    if (in_use(b)) {
      ceres_problem->SetParameterBlockVariable(model->mutable_block(b));
    }
  }
  result->converged = result->summary.termination_type == ceres::CONVERGENCE;
  *landmarks = slam.landmarks();
  result->range_calibration = slam.range_calibration();
  result->odometry_calibration = slam.odometry_calibration();
  return true;
}

// The WNOA solve the RFF prior starts from: a batch solve of its own with
// the same problem options, with its covariance when `covariance`.
bool SolveWnoa(const Dataset& dataset, const SlamOptions& options,
               bool covariance, SlamResult* solve, std::string* error) {
  SlamOptions wnoa = options;
  wnoa.prior = "wnoa";
  wnoa.prior_mean = "auto";
  wnoa.outer_rounds = 0;
  wnoa.compute_covariance = covariance;
  // The user's linear solver is for the RFF solve; banded states want their
  // own (AutoLinearSolverType).
  wnoa.solver.linear_solver = "auto";
  wnoa.solver.preconditioner = "auto";
  return RunSlam(dataset, wnoa, solve, error);
}

// What the quality report needs from the solve besides the residuals.
SolveFacts SolveFactsOf(const SlamOptions& options, const SlamResult& result) {
  SolveFacts facts;
  facts.converged = result.converged;
  facts.termination =
      ceres::TerminationTypeToString(result.summary.termination_type);
  facts.range_calibration = result.range_calibration;
  const double scale = result.range_calibration[0];
  const double offset_bound =
      kMaxOffsetSigmas * options.problem.range_calibration.offset_sigma;
  constexpr double kAtBound = 1e-6;
  facts.range_calibration_at_bound =
      scale < kMinRangeScale + kAtBound || scale > kMaxRangeScale - kAtBound ||
      std::abs(result.range_calibration[1]) > offset_bound * (1.0 - kAtBound);
  facts.odometry_calibration = result.odometry_calibration;
  facts.odometry_calibration_at_bound =
      result.odometry_calibration.minCoeff() < kMinOdometryScale + kAtBound ||
      result.odometry_calibration.maxCoeff() > kMaxOdometryScale - kAtBound;
  return facts;
}

// The blocks start (initial_trajectory "auto") at dead reckoning about a
// constant mean with odometry, else at the fit of the pilot trajectory when
// there is one, else at zero (the prior mean). A "wnoa" mean is already a
// solve of the data: it is the start.
bool InitializeBlocks(const Dataset& start, const SlamOptions& options,
                      TrajectoryModel* model, SlamResult* result,
                      std::string* error) {
  result->initial_trajectory = "mean";
  if (!options.initial_poses.empty()) {
    result->initial_trajectory = "given";
    return FitModelToPoses(options.initial_poses, model, error);
  }
  if (options.initial_trajectory == "mean" || result->prior_mean == "wnoa") {
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

// Solves whose result only places the next step (the judging of "auto"
// losses, a round of learned scales) stop at this relative cost change: the
// factors and outlier levels they feed are far coarser.
constexpr double kPlacingTolerance = 1e-4;

// Learns the scales of the trajectory prior (WNOA Q_c, RFF kernel
// variances) of x, y and theta and, where `noise`, the factors on the sigmas
// of range, bearing and odometry: after the first MAP, each round rescales
// the variances by their variance-component factors (variance_components.h,
// the fixed point of the Laplace evidence) and solves again from the current
// estimate, until every factor is within kScaleTolerance of one. The data's
// stated sigmas are often a guess: MRCLAM's bearings and odometry are
// several times tighter than stated (docs/heldout.md). `loose`: the problem
// was solved at kPlacingTolerance only.
constexpr int kMaxScaleRounds = 12;
constexpr double kScaleTolerance = 0.1;
constexpr double kMaxScaleStep = 10.0;  // Per round, either way.
constexpr int kAcceleratingFalls = 3;
// Noise sigmas stay within this factor of the stated ones: noise-free data
// would drive them to 0 and the system to no digits.
constexpr double kMaxNoiseScale = 1e3;
bool LearnScales(const Dataset& dataset,
                 std::shared_ptr<const MeanFunction> mean,
                 const ceres::Solver::Options& ceres_options,
                 double initial_extent, bool noise, bool loose,
                 SlamOptions* settled, std::unique_ptr<TrajectoryModel>* model,
                 std::map<LandmarkId, Eigen::Vector2d>* landmarks,
                 std::unique_ptr<SlamProblem>* problem, SlamResult* result,
                 std::string* error) {
  const bool wnoa = settled->prior == "wnoa";
  double* position_scale = wnoa ? &settled->wnoa.position_qc
                                : &settled->trajectory.position_kernel.variance;
  double* heading_scale = wnoa ? &settled->wnoa.heading_qc
                               : &settled->trajectory.heading_kernel.variance;
  NoiseScales& sigmas = settled->problem.noise;
  // Per noise group: its last fall (-log factor) and the rounds in a row
  // it fell by at least the round before's.
  struct Falls {
    double last = 0.0;
    int accelerating = 0;
  };
  std::map<VarianceGroup, Falls> falls;
  std::set<VarianceGroup> kept;  // Noise sigmas back at the stated ones.
  ceres::Solver::Options placing_options = ceres_options;
  placing_options.function_tolerance =
      std::max(ceres_options.function_tolerance, kPlacingTolerance);
  for (int round = 0; round < kMaxScaleRounds; ++round) {
    VarianceComponents components;
    std::string why;
    if (!EstimateVarianceComponents(problem->get(), VarianceComponentOptions(),
                                    &components, &why)) {
      // Data that leave part of the run beyond double precision (a pose
      // after a gap of days): the scales stay as they are, and say so.
      result->scales_not_learned = why;
      break;
    }
    double largest_step = 0.0;
    // `power` 1 for a variance, 0.5 for a sigma.
    auto rescale = [&](VarianceGroup group, double power, double* scale) {
      const VarianceComponent& c = components[static_cast<int>(group)];
      if (!c.estimated || kept.count(group) > 0) return;
      const double fall = -std::log(c.factor);
      Falls& f = falls[group];
      f.accelerating = fall > 0.0 && fall >= f.last ? f.accelerating + 1 : 0;
      f.last = fall;
      if (power < 1.0 && f.accelerating > kAcceleratingFalls) {
        // A noise sigma falling faster round after round runs to the
        // likelihood's degenerate edge, its rows fit exactly as it goes to
        // 0 (a misfit prior lets them): back to the stated one. A real
        // scale's falls slow down towards its fixed point.
        *scale = 1.0;
        kept.insert(group);
        result->noise_kept.push_back(VarianceGroupName(group));
        largest_step = std::numeric_limits<double>::infinity();
        return;
      }
      largest_step = std::max(largest_step, std::abs(std::log(c.factor)));
      *scale *= std::pow(
          std::clamp(c.factor, 1.0 / kMaxScaleStep, kMaxScaleStep), power);
      if (power < 1.0) {
        *scale = std::clamp(*scale, 1.0 / kMaxNoiseScale, kMaxNoiseScale);
      }
    };
    rescale(VarianceGroup::kPriorPosition, 1.0, position_scale);
    rescale(VarianceGroup::kPriorHeading, 1.0, heading_scale);
    if (noise) {
      rescale(VarianceGroup::kRange, 0.5, &sigmas.range);
      rescale(VarianceGroup::kBearing, 0.5, &sigmas.bearing);
      rescale(VarianceGroup::kOdometry, 0.5, &sigmas.odometry);
    }
    VLOG(1)
        << "scale round " << round << ": prior position factor "
        << components[static_cast<int>(VarianceGroup::kPriorPosition)].factor
        << ", heading factor "
        << components[static_cast<int>(VarianceGroup::kPriorHeading)].factor
        << "; sigma factors range " << sigmas.range << ", bearing "
        << sigmas.bearing << ", odometry " << sigmas.odometry;
    result->learning_rounds = round + 1;
    result->prior_scale_factors
        << components[static_cast<int>(VarianceGroup::kPriorPosition)].factor,
        components[static_cast<int>(VarianceGroup::kPriorHeading)].factor;
    if (largest_step < std::log1p(kScaleTolerance)) {
      result->learning_converged = true;
      break;
    }
    // Q_c scales the WNOA prior only: its states stay as they are. RFF
    // features follow the variance (capacity): refit them to the estimate.
    const std::vector<double> blocks = ModelBlocks(**model);
    const std::vector<TimedPose> estimate = result->trajectory;
    *model = CreateTrajectoryModel(dataset, *settled, mean, error);
    if (!*model) return false;
    if (wnoa) {
      SetModelBlocks(blocks, model->get());
    } else if (!FitModelToPoses(estimate, model->get(), error)) {
      return false;
    }
    if (!SolveBatch(dataset, *settled, placing_options, model->get(), landmarks,
                    initial_extent, problem, result, error)) {
      return false;
    }
    result->learned = true;
    loose = true;
  }
  // The rounds' solves only placed the next factors.
  return !loose ||
         SolveBatch(dataset, *settled, ceres_options, model->get(), landmarks,
                    initial_extent, problem, result, error);
}

bool HasAutoLoss(const ProblemOptions& options) {
  return options.loss.name == "auto" || options.odometry_loss.name == "auto";
}

// The robust solve that judges "auto" losses stops at kPlacingTolerance: the
// judgement compares residuals with an outlier level of several sigma; the
// solve after it finishes.
ceres::Solver::Options JudgingOptions(const ProblemOptions& options,
                                      ceres::Solver::Options ceres_options) {
  if (HasAutoLoss(options)) {
    ceres_options.function_tolerance =
        std::max(ceres_options.function_tolerance, kPlacingTolerance);
  }
  return ceres_options;
}

// Settles "auto" losses (slam_problem.h) after the robust solve that judges
// them (JudgingOptions): a loss whose residual kinds all stay within the
// outlier level of their count becomes "none", the rest "cauchy". Returns
// whether any was "auto", so that the judging solve is to be finished.
bool SettleAutoLosses(SlamProblem* problem, ProblemOptions* options) {
  const std::map<std::string, std::vector<double>> residuals =
      problem->WhitenedResidualsByKind();
  auto clean = [&](std::initializer_list<const char*> kinds) {
    for (const char* kind : kinds) {
      const auto it = residuals.find(kind);
      if (it == residuals.end()) continue;
      const double level = OutlierLevel(static_cast<int>(it->second.size()));
      for (const double r : it->second) {
        if (!(std::abs(r) <= level)) return false;
      }
    }
    return true;
  };
  const bool judged = HasAutoLoss(*options);
  auto settle = [&](bool is_clean, LossOptions* loss) {
    if (loss->name == "auto") loss->name = is_clean ? "none" : "cauchy";
  };
  settle(clean({"range", "bearing", "range-bearing"}), &options->loss);
  settle(clean({"odometry"}), &options->odometry_loss);
  return judged;
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
  if (options.prior_mean != "auto") return options.prior_mean;
  if (dataset.odometry.empty()) return "constant";
  const bool batch = options.incremental.every == 0;
  if (!batch) return "odometry";
  return options.prior == "rff" ? "wnoa" : "constant";
}

namespace {

bool RunSlamAtOrigin(const Dataset& dataset, const SlamOptions& options,
                     SlamResult* result, std::string* error) {
  const auto start = std::chrono::steady_clock::now();
  *result = SlamResult();
  ceres::Solver::Options ceres_options;
  if (!ToCeresOptions(options.solver, &ceres_options, error)) return false;
  if (!ValidateSlamOptions(options, error)) return false;
  const IncrementalOptions& incremental = options.incremental;
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
  if (options.compute_covariance) {
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

  // The start (heading, pilot) may come from the data.
  const Dataset resolved = ResolveStartHeading(dataset, &result->start_heading);
  result->prior_mean = SettlePriorMean(options, dataset);
  // The RFF prior starts from a WNOA solve: as its mean with a "wnoa" mean;
  // as its initial value without odometry, where the localisation pilot
  // has no motion model to bridge gaps between fixes.
  SlamOptions warm = options;
  // The options as they settle: losses, learned scales and kernels.
  SlamOptions settled = options;
  // A "wnoa" mean is an estimate: its covariance joins the correction's.
  SlamResult wnoa_mean_solve;
  const auto mean_start = std::chrono::steady_clock::now();
  std::shared_ptr<const MeanFunction> mean;
  if (options.prior == "rff" && incremental.every == 0 &&
      (result->prior_mean == "wnoa" ||
       (dataset.odometry.empty() && options.initial_trajectory == "auto" &&
        options.initial_poses.empty()))) {
    SlamResult wnoa;
    const bool wnoa_mean = result->prior_mean == "wnoa";
    if (!SolveWnoa(dataset, options, wnoa_mean && options.compute_covariance,
                   &wnoa, error)) {
      return false;
    }
    // The same data: a loss the WNOA solve found no outlier for is dropped
    // here too. Its outliers may be its own misfit: the RFF solve decides.
    if (wnoa.loss == "none") settled.problem.loss.name = "none";
    if (wnoa.odometry_loss == "none") {
      settled.problem.odometry_loss.name = "none";
    }
    settled.problem.noise = wnoa.noise;  // Learned from the same data.
    result->noise_kept = wnoa.noise_kept;
    if (wnoa_mean) {
      mean = std::make_shared<PiecewiseLinearMean>(wnoa.trajectory);
      wnoa_mean_solve = std::move(wnoa);
    } else {
      warm.initial_poses = wnoa.trajectory;
      for (const Landmark& l : wnoa.landmarks) {
        warm.initial_landmarks[l.id] = Eigen::Vector2d(l.x, l.y);
      }
    }
  }
  if (!mean) {
    mean = BuildPriorMean(result->prior_mean, resolved, options.localization,
                          options.spline_smoothing, error);
  }
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
  if (options.initial_poses.empty() && !warm.initial_poses.empty()) {
    result->initial_trajectory = "wnoa";
  }

  // The initial scene: the initial trajectory, the landmarks' initial
  // positions and the longest range, to tell a run-away solution from a
  // large scene.
  std::map<LandmarkId, Eigen::Vector2d> landmarks;
  if (incremental.every == 0 &&
      !InitializeLandmarks(
          resolved, [&](double t) { return model->Pose(t); }, &landmarks,
          error)) {
    return false;
  }
  for (const auto& [id, position] : warm.initial_landmarks) {
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
  // WNOA learns its Q_c and the data's noise scales (LearnScales): its
  // prior is the only motion model besides the odometry, whose sigmas, like
  // the sensors', are the recording's guess.
  const bool wnoa_learns =
      options.prior == "wnoa" && options.learn_hyperparameters != "off";
  // With a "wnoa" mean the RFF weights are a correction to a solve of the
  // same data: its variances start at what the capacity rule resolves and
  // are learned from the data (LearnScales).
  const bool correction = options.prior == "rff" &&
                          result->prior_mean == "wnoa" &&
                          options.learn_hyperparameters != "off";
  if (correction) {
    FeatureTrajectoryOptions& t = settled.trajectory;
    t.position_kernel.variance = std::pow(2.0 * t.capacity_position_sigma, 2);
    t.heading_kernel.variance = std::pow(2.0 * t.capacity_heading_sigma, 2);
    model = CreateTrajectoryModel(dataset, settled, mean, error);
    if (!model) return false;
  }
  if (options.prior == "rff" && options.learn_hyperparameters == "auto" &&
      !search && result->initial_trajectory == "localization") {
    // Drift of dead reckoning: its size from the pilot, its time scale given.
    MatchVariancesToSpread(*mean, initial, &settled.trajectory);
    model = CreateTrajectoryModel(dataset, settled, mean, error);
    if (!model || !FitModelToPoses(initial, model.get(), error)) return false;
  }
  if (options.prior == "rff" && incremental.every == 0 && search) {
    // Linearised about (and the learned model started from) the WNOA solve
    // where there is one: the fit of the features to it is only as good as
    // their starting hyperparameters.
    const std::vector<TimedPose>& about =
        warm.initial_poses.empty() ? initial : warm.initial_poses;
    if (!LearnHyperparameters(resolved, mean, about, landmarks, settled.problem,
                              options.learning, &settled.trajectory,
                              &result->learning, error)) {
      *error = "learning the hyperparameters: " + *error;
      return false;
    }
    result->learned = true;
    mean = std::make_shared<ShiftedMean>(mean, result->learning.level);
    model = CreateTrajectoryModel(dataset, settled, mean, error);
    if (!model || !FitModelToPoses(about, model.get(), error)) return false;
  }
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
  initial_extent += longest_range;

  ProgressLogger progress;
  if (options.solver.log_progress) ceres_options.callbacks.push_back(&progress);
  AbortCheck abort_check(options.solver.should_abort);
  if (options.solver.should_abort) {
    ceres_options.callbacks.push_back(&abort_check);
  }
  std::unique_ptr<SlamProblem> problem;
  if (incremental.every > 0) {
    if (!SolveIncremental(dataset, settled, ceres_options, model.get(),
                          &landmarks, &problem, result, error) ||
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
    // Finishes the judging solve: a learning round's solves come first.
    const bool judged = SettleAutoLosses(problem.get(), &settled.problem);
    if (wnoa_learns || correction) {
      if (!LearnScales(dataset, mean, ceres_options, initial_extent,
                       /*noise=*/wnoa_learns, /*loose=*/judged, &settled,
                       &model, &landmarks, &problem, result, error)) {
        return false;
      }
    } else if (judged &&
               !SolveBatch(dataset, settled, ceres_options, model.get(),
                           &landmarks, initial_extent, &problem, result,
                           error)) {
      return false;
    }
  }
  result->noise = settled.problem.noise;
  // Incremental updates keep an "auto" loss robust throughout.
  for (LossOptions* loss :
       {&settled.problem.loss, &settled.problem.odometry_loss}) {
    if (loss->name == "auto") loss->name = "cauchy";
  }
  result->loss = settled.problem.loss.name;
  result->odometry_loss = settled.problem.odometry_loss.name;
  result->wnoa_options = settled.wnoa;
  if (const auto* features =
          dynamic_cast<const FeatureTrajectory*>(InnerModel(model.get()))) {
    result->trajectory_options = features->options();
  }
  if (!problem->CheckLandmarksDetermined(1e12, error)) return false;
  // Judged against the data as stated: learned sigmas would absorb a misfit.
  result->quality = AssessQuality(problem->WhitenedResidualsByKind(
                                      /*stated_sigmas=*/true),
                                  SolveFactsOf(settled, *result));
  for (const auto& [id, position] : landmarks) {
    Landmark l;
    l.id = id;
    l.x = position.x();
    l.y = position.y();
    result->landmarks.push_back(l);
  }
  if (options.compute_covariance) {
    std::vector<double> times;
    for (const TimedPose& p : result->trajectory) times.push_back(p.t);
    CovarianceOptions covariance_options;
    covariance_options.num_threads = options.solver.num_threads;
    if (!ComputePosteriorCovariance(
            problem.get(), *model, times, covariance_options,
            &result->pose_covariances, &result->landmarks, error) ||
        !AddMeanCovariance(wnoa_mean_solve, result, error)) {
      return false;
    }
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
  for (TimedPose& p : centred.initial_poses) {
    p.x -= origin.x();
    p.y -= origin.y();
  }
  for (auto& [id, position] : centred.initial_landmarks) position -= origin;
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
