#include "rff_ceres/hyperparameter_learning.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <set>

#include "Eigen/Cholesky"
#include "Eigen/SparseCholesky"
#include "Eigen/SparseCore"
#include "ceres/crs_matrix.h"
#include "ceres/solver.h"
#include "glog/logging.h"
#include "rff_ceres/initialization.h"
#include "rff_ceres/se2.h"

namespace rff {
namespace {

// Largest Hessian factorised densely for the evidence.
constexpr int kMaxDenseEvidence = 4000;
// Below this spread (units^2) the initial trajectory is the mean itself.
constexpr double kMinSpread = 1e-4;

// The part of `dataset` up to `end` seconds: what the evidence is computed
// on. Landmarks outside it drop out unless they have a prior.
Dataset Window(const Dataset& dataset, double end) {
  Dataset window;
  window.pose_priors = dataset.pose_priors;
  window.pose_priors.erase(
      std::remove_if(window.pose_priors.begin(), window.pose_priors.end(),
                     [&](const PosePrior& p) { return p.pose.t > end; }),
      window.pose_priors.end());
  window.landmark_priors = dataset.landmark_priors;
  for (const Odometry& o : dataset.odometry) {
    if (o.t1 <= end) window.odometry.push_back(o);
  }
  for (const Observation& o : dataset.observations) {
    if (o.t <= end) window.observations.push_back(o);
  }
  return window;
}

// Parameters of the search: log lengthscale and log variance of the position
// and of the heading kernel.
using LogParameters = std::array<double, 4>;

LogParameters ToLog(const FeatureTrajectoryOptions& t) {
  return {std::log(t.position_kernel.lengthscale),
          std::log(t.position_kernel.variance),
          std::log(t.heading_kernel.lengthscale),
          std::log(t.heading_kernel.variance)};
}

void FromLog(const LogParameters& p, FeatureTrajectoryOptions* t) {
  t->position_kernel.lengthscale = std::exp(p[0]);
  t->position_kernel.variance = std::exp(p[1]);
  t->heading_kernel.lengthscale = std::exp(p[2]);
  t->heading_kernel.variance = std::exp(p[3]);
}

// Walks a grid of `step` from x0 (where f is f0) uphill for at most
// `max_steps` steps and, with `refine`, tries the vertex of the parabola
// through the best grid point and its neighbours. Returns the best value
// seen; f records its own best point.
double MaximizeAlongLine(const std::function<double(double)>& f, double x0,
                         double f0, double step, bool refine, int max_steps,
                         const std::function<double(double)>& clamp) {
  const double none = -std::numeric_limits<double>::infinity();
  double x = x0, fx = f0;
  double lo = clamp(x - step), hi = clamp(x + step);
  double f_hi = hi > x ? f(hi) : none;
  double f_lo = f_hi > fx ? none : (lo < x ? f(lo) : none);
  for (int k = 0; k < max_steps; ++k) {
    if (f_hi > fx && f_hi >= f_lo) {
      lo = x, f_lo = fx, x = hi, fx = f_hi;
      hi = clamp(x + step);
      f_hi = hi > x ? f(hi) : none;
    } else if (f_lo > fx) {
      hi = x, f_hi = fx, x = lo, fx = f_lo;
      lo = clamp(x - step);
      f_lo = lo < x ? f(lo) : none;
    } else {
      break;
    }
  }
  if (f_lo == none && lo < x && refine) f_lo = f(lo);
  const double curvature = f_lo + f_hi - 2.0 * fx;
  if (refine && std::isfinite(curvature) && curvature < 0.0) {
    fx = std::max(fx, f(clamp(x + 0.5 * step * (f_lo - f_hi) / curvature)));
  }
  return fx;
}

}  // namespace

void MatchVariancesToSpread(const MeanFunction& mean,
                            const std::vector<TimedPose>& initial,
                            FeatureTrajectoryOptions* trajectory) {
  if (initial.empty()) return;
  double position_spread = 0.0, heading_spread = 0.0;
  for (const TimedPose& p : initial) {
    const Eigen::Vector3d d =
        Eigen::Vector3d(p.x, p.y, p.theta) - mean.Evaluate(p.t);
    position_spread += 0.5 * d.head<2>().squaredNorm();
    heading_spread += std::pow(WrapAngle(d.z()), 2);
  }
  position_spread /= initial.size();
  heading_spread /= initial.size();
  if (position_spread > kMinSpread) {
    trajectory->position_kernel.variance = position_spread;
  }
  if (heading_spread > kMinSpread) {
    trajectory->heading_kernel.variance = heading_spread;
  }
}

bool LaplaceLogEvidence(ceres::Problem* problem, double* log_evidence,
                        std::string* error) {
  double cost = 0.0;
  ceres::CRSMatrix crs;
  if (!problem->Evaluate(ceres::Problem::EvaluateOptions(), &cost, nullptr,
                         nullptr, &crs)) {
    *error = "the problem could not be evaluated";
    return false;
  }
  const Eigen::Map<const Eigen::SparseMatrix<double, Eigen::RowMajor>> jacobian(
      crs.num_rows, crs.num_cols, static_cast<int>(crs.values.size()),
      crs.rows.data(), crs.cols.data(), crs.values.data());
  const Eigen::SparseMatrix<double> hessian =
      Eigen::SparseMatrix<double>(jacobian.transpose()) * jacobian;
  // Feature blocks are dense: a dense factorisation is faster up to a few
  // thousand unknowns.
  Eigen::VectorXd pivots;
  if (hessian.rows() <= kMaxDenseEvidence) {
    const Eigen::MatrixXd dense = hessian;
    const Eigen::LLT<Eigen::MatrixXd> llt(dense);
    if (llt.info() == Eigen::Success) {
      pivots = llt.matrixLLT().diagonal().array().square();
    }
  } else {
    const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(hessian);
    if (ldlt.info() == Eigen::Success) pivots = ldlt.vectorD();
  }
  if (pivots.size() == 0 || !(pivots.minCoeff() > 0.0)) {
    *error = "the Gauss-Newton Hessian is not positive definite";
    return false;
  }
  *log_evidence = -cost - 0.5 * pivots.array().log().sum();
  return std::isfinite(*log_evidence);
}

bool LearnHyperparameters(
    const Dataset& dataset, std::shared_ptr<const MeanFunction> mean,
    const std::vector<TimedPose>& initial,
    const std::map<LandmarkId, Eigen::Vector2d>& landmarks,
    const ProblemOptions& problem_options, const LearningOptions& options,
    FeatureTrajectoryOptions* trajectory, LearningReport* report,
    std::string* error) {
  const auto start = std::chrono::steady_clock::now();
  *report = LearningReport();
  if (initial.empty()) {
    *error = "hyperparameter learning needs an initial trajectory";
    return false;
  }
  const double begin = initial.front().t;
  const double end = std::min(initial.back().t, begin + options.window);
  report->window_end = end;
  const Dataset window = Window(dataset, end);
  std::vector<TimedPose> window_initial;
  for (const TimedPose& p : initial) {
    if (p.t <= end) window_initial.push_back(p);
  }
  std::set<LandmarkId> used;
  for (const LandmarkPrior& p : window.landmark_priors) used.insert(p.id);
  for (const Observation& o : window.observations) used.insert(o.id);
  std::map<LandmarkId, Eigen::Vector2d> window_landmarks;
  for (const auto& [id, position] : landmarks) {
    if (used.count(id)) window_landmarks[id] = position;
  }

  FeatureTrajectoryOptions start_values = *trajectory;
  MatchVariancesToSpread(*mean, window_initial, &start_values);

  ceres::Solver::Options solver;
  solver.max_num_iterations = options.max_solver_iterations;
  solver.logging_type = ceres::SILENT;
  // Each candidate starts from the MAP of the best one so far, which is
  // close to its own: a few iterations reach it.
  std::vector<TimedPose> best_trajectory = window_initial;
  std::vector<TimedPose> candidate_trajectory;
  // The evidence of one candidate; -inf when its solve or Hessian fails.
  auto evidence = [&](const LogParameters& p) {
    ++report->evaluations;
    FeatureTrajectoryOptions candidate = *trajectory;
    FromLog(p, &candidate);
    candidate.capacity_position_sigma *= options.capacity_relaxation;
    candidate.capacity_heading_sigma *= options.capacity_relaxation;
    std::string why;
    std::unique_ptr<FeatureTrajectory> model =
        FeatureTrajectory::Create(candidate, mean, begin, end, &why);
    double value = -std::numeric_limits<double>::infinity();
    if (!model || !FitModelToPoses(best_trajectory, model.get(), &why)) {
      return value;
    }
    SlamProblem problem(model.get(), problem_options);
    if (!problem.Build(window, window_landmarks, &why)) return value;
    solver.linear_solver_type = AutoLinearSolverType(*model);
    solver.linear_solver_ordering = problem.Ordering();
    if (solver.linear_solver_type != ceres::DENSE_SCHUR) {
      solver.linear_solver_ordering.reset();
    }
    ceres::Solver::Summary summary;
    ceres::Solve(solver, problem.problem(), &summary);
    if (summary.termination_type == ceres::FAILURE ||
        !LaplaceLogEvidence(problem.problem(), &value, &why)) {
      return -std::numeric_limits<double>::infinity();
    }
    candidate_trajectory.clear();
    for (const TimedPose& q : window_initial) {
      const Eigen::Vector3d pose = model->Pose(q.t);
      candidate_trajectory.push_back({q.t, pose.x(), pose.y(), pose.z()});
    }
    VLOG(1) << "evidence at lengthscale " << std::exp(p[0]) << ", variance "
            << std::exp(p[1]) << ", heading lengthscale " << std::exp(p[2])
            << ", variance " << std::exp(p[3]) << ": " << value;
    return value;
  };

  const double min_log_lengthscale = std::log(options.min_lengthscale);
  const double max_log_lengthscale = std::log(std::max(end - begin, 1.0));
  auto clamp = [&](int i, double v) {
    return i % 2 == 0 ? std::clamp(v, min_log_lengthscale, max_log_lengthscale)
                      : std::clamp(v, std::log(options.min_variance),
                                   std::log(options.max_variance));
  };
  LogParameters best = ToLog(start_values);
  for (int i = 0; i < 4; ++i) best[i] = clamp(i, best[i]);
  double best_value = evidence(best);
  if (!std::isfinite(best_value)) {
    *error = "the evidence cannot be evaluated at the initial hyperparameters";
    return false;
  }
  best_trajectory = candidate_trajectory;
  // The evidence at `p`, keeping the best point and its MAP.
  auto visit = [&](const LogParameters& p) {
    const double value = evidence(p);
    if (value > best_value) {
      best = p;
      best_value = value;
      best_trajectory = candidate_trajectory;
    }
    return value;
  };
  // Each kernel's lengthscale is searched with its variance profiled out
  // (maximised at every lengthscale): the evidence of a Matern kernel is
  // nearly flat along variance / lengthscale^(2 nu) = const, a ridge that a
  // search of one coordinate at a time cannot follow.
  for (int sweep = 0; sweep < options.sweeps; ++sweep) {
    for (const int kernel : {0, 2}) {
      auto profile = [&](double log_lengthscale) {
        LogParameters p = best;
        p[kernel] = log_lengthscale;
        const double value = visit(p);
        return MaximizeAlongLine(
            [&](double log_variance) {
              LogParameters q = p;
              q[kernel + 1] = log_variance;
              return visit(q);
            },
            p[kernel + 1], value, options.step, /*refine=*/false,
            options.max_steps, [&](double v) { return clamp(kernel + 1, v); });
      };
      MaximizeAlongLine(profile, best[kernel], best_value, options.step,
                        /*refine=*/true, options.max_steps,
                        [&](double v) { return clamp(kernel, v); });
    }
  }
  FromLog(best, trajectory);
  report->log_evidence = best_value;
  report->seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
          .count();
  return true;
}

}  // namespace rff
