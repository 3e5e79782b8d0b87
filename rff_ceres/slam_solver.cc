#include "rff_ceres/slam_solver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>

#include "ceres/types.h"
#include "glog/logging.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/landmark_init.h"
#include "rff_ceres/mean/prior_mean.h"
#include "rff_ceres/mean/spline_mean.h"

namespace rff {
namespace {

// Every time the dataset mentions, for the extent of the feature window.
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

}  // namespace

bool ToCeresOptions(const SolverOptions& options,
                    ceres::Solver::Options* ceres_options, std::string* error) {
  std::string name = options.linear_solver;
  if (!ceres::StringToLinearSolverType(name,
                                       &ceres_options->linear_solver_type)) {
    *error = "unknown linear solver '" + options.linear_solver +
             "' (DENSE_SCHUR, SPARSE_SCHUR, ITERATIVE_SCHUR, DENSE_QR, "
             "DENSE_NORMAL_CHOLESKY, SPARSE_NORMAL_CHOLESKY, CGNR)";
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
    *error = "unknown preconditioner '" + options.preconditioner +
             "' (IDENTITY, JACOBI, SCHUR_JACOBI, CLUSTER_JACOBI, "
             "CLUSTER_TRIDIAGONAL)";
    return false;
  }
  // Ceres 2.1's CGNR aborts on any other preconditioner.
  if (ceres_options->linear_solver_type == ceres::CGNR &&
      ceres_options->preconditioner_type != ceres::IDENTITY &&
      ceres_options->preconditioner_type != ceres::JACOBI) {
    *error =
        "linear solver CGNR supports the preconditioners IDENTITY and "
        "JACOBI only, got '" +
        options.preconditioner + "'";
    return false;
  }
  name = options.trust_region_strategy;
  if (!ceres::StringToTrustRegionStrategyType(
          name, &ceres_options->trust_region_strategy_type)) {
    *error = "unknown trust region strategy '" + options.trust_region_strategy +
             "' (LEVENBERG_MARQUARDT, DOGLEG)";
    return false;
  }
  if (options.num_threads < 1) {
    *error = "num_threads must be >= 1";
    return false;
  }
  if (options.max_iterations < 1) {
    *error = "max_iterations must be >= 1";
    return false;
  }
  for (const double tolerance :
       {options.function_tolerance, options.gradient_tolerance,
        options.parameter_tolerance}) {
    if (!(tolerance >= 0.0) || !std::isfinite(tolerance)) {
      *error = "solver tolerances must be finite and >= 0";
      return false;
    }
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

bool RunSlam(const Dataset& dataset, const SlamOptions& options,
             SlamResult* result, std::string* error) {
  const auto start = std::chrono::steady_clock::now();
  *result = SlamResult();
  ceres::Solver::Options ceres_options;
  if (!ToCeresOptions(options.solver, &ceres_options, error)) return false;
  if (options.outer_rounds < 0) {
    *error = "outer_rounds must be >= 0, got " +
             std::to_string(options.outer_rounds);
    return false;
  }
  if (!(options.spline_smoothing >= 0.0 && options.spline_smoothing <= 1.0)) {
    *error = "spline_smoothing must be in [0, 1], got " +
             FormatNumber(options.spline_smoothing);
    return false;
  }

  std::shared_ptr<const MeanFunction> mean =
      BuildPriorMean(options.prior_mean, dataset, error);
  if (!mean) return false;
  double t_begin, t_end;
  TimeSpan(dataset, &t_begin, &t_end);
  std::unique_ptr<FeatureTrajectory> model = FeatureTrajectory::Create(
      options.trajectory, mean, t_begin, t_end, error);
  if (!model) return false;

  std::map<LandmarkId, Eigen::Vector2d> landmarks;
  if (!InitializeLandmarks(
          dataset, [&](double t) { return mean->Evaluate(t); }, &landmarks,
          error)) {
    return false;
  }
  ProgressLogger progress;
  if (options.solver.log_progress) ceres_options.callbacks.push_back(&progress);
  // Paper III-B.2: after each solve the prior mean becomes a smoothing spline
  // of the estimate and the weights restart from zero.
  for (int round = 0;; ++round) {
    SlamProblem problem(model.get(), options.problem);
    if (!problem.Build(dataset, landmarks, error)) return false;
    ceres_options.linear_solver_ordering = problem.Ordering();
    ceres::Solve(ceres_options, problem.problem(), &result->summary);
    VLOG(1) << result->summary.FullReport();
    const ceres::Solver::Summary& summary = result->summary;
    if (summary.termination_type == ceres::FAILURE ||
        summary.termination_type == ceres::USER_FAILURE ||
        !std::isfinite(summary.final_cost)) {
      *error = "the solve failed: " + summary.message;
      return false;
    }
    result->converged = summary.termination_type == ceres::CONVERGENCE;
    result->total_iterations += static_cast<int>(summary.iterations.size());
    landmarks = problem.landmarks();

    result->trajectory.clear();
    for (const double t : OutputTimes(dataset)) {
      const Eigen::Vector3d pose = model->Pose(t);
      if (!pose.allFinite()) {
        *error =
            "the solve diverged: non-finite pose at t = " + FormatNumber(t);
        return false;
      }
      result->trajectory.push_back(
          {t, pose.x(), pose.y(), WrapAngle(pose.z())});
    }
    for (const auto& [id, position] : landmarks) {
      if (!position.allFinite()) {
        *error =
            "the solve diverged: non-finite landmark " + std::to_string(id);
        return false;
      }
    }
    if (round >= options.outer_rounds) break;
    mean =
        RefitSplineMean(result->trajectory,
                        DataFitWeights(dataset, result->trajectory, landmarks),
                        options.spline_smoothing, error);
    if (!mean) return false;
    model->set_mean(mean);
    for (int b = 0; b < model->num_blocks(); ++b) {
      Eigen::Map<Eigen::VectorXd>(model->mutable_block(b), model->block_size(b))
          .setZero();
    }
  }
  for (const auto& [id, position] : landmarks) {
    Landmark l;
    l.id = id;
    l.x = position.x();
    l.y = position.y();
    result->landmarks.push_back(l);
  }
  result->solve_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
          .count();
  return true;
}

bool WriteSummaryJson(const SlamOptions& options, const SlamResult& result,
                      const std::string& path, std::string* error) {
  std::ofstream out;
  if (!OpenForWriting(path, &out, error)) return false;
  const ceres::Solver::Summary& s = result.summary;
  const FeatureTrajectoryOptions& t = options.trajectory;
  out << "{\n"
      << "  \"prior_mean\": " << JsonString(options.prior_mean) << ",\n"
      << "  \"kernel\": " << JsonString(t.position_kernel.name) << ",\n"
      << "  \"heading_kernel\": " << JsonString(t.heading_kernel.name) << ",\n"
      << "  \"lengthscale\": " << FormatNumber(t.position_kernel.lengthscale)
      << ",\n"
      << "  \"kernel_variance\": " << FormatNumber(t.position_kernel.variance)
      << ",\n"
      << "  \"features\": " << JsonString(t.family) << ",\n"
      << "  \"num_features\": " << t.num_position_features << ",\n"
      << "  \"num_heading_features\": " << t.num_heading_features << ",\n"
      << "  \"seed\": " << t.seed << ",\n"
      << "  \"loss\": " << JsonString(options.problem.loss.name) << ",\n"
      << "  \"linear_solver\": " << JsonString(options.solver.linear_solver)
      << ",\n"
      << "  \"termination\": "
      << JsonString(ceres::TerminationTypeToString(s.termination_type)) << ",\n"
      << "  \"converged\": " << (result.converged ? "true" : "false") << ",\n"
      << "  \"iterations\": " << result.total_iterations << ",\n"
      << "  \"outer_rounds\": " << options.outer_rounds << ",\n"
      << "  \"initial_cost\": " << FormatNumber(s.initial_cost) << ",\n"
      << "  \"final_cost\": " << FormatNumber(s.final_cost) << ",\n"
      << "  \"num_residual_blocks\": " << s.num_residual_blocks << ",\n"
      << "  \"num_parameters\": " << s.num_parameters << ",\n"
      << "  \"ceres_seconds\": " << FormatNumber(s.total_time_in_seconds)
      << ",\n"
      << "  \"total_seconds\": " << FormatNumber(result.solve_seconds) << ",\n"
      << "  \"num_poses\": " << result.trajectory.size() << ",\n"
      << "  \"num_landmarks\": " << result.landmarks.size() << "\n"
      << "}\n";
  return FinishWriting(path, &out, error);
}

}  // namespace rff
