#include "rff_ceres/banded_minimizer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <set>

#include "glog/logging.h"
#include "rff_ceres/banded_problem.h"
#include "rff_ceres/envelope_cholesky.h"

namespace rff {
namespace {

double Now() {
  return std::chrono::duration<double>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// A step counts as undamped for the decrement rule from this trust radius
// (LM damping = scaled diagonal / radius) and while the damping's share
// z^T D z of the model decrease's y^T y is below kMaxDampingShare.
constexpr double kUndampedRadius = 1e8;
constexpr double kMaxDampingShare = 1e-2;
// A step the function tolerance ends (|cost change| <= tol * cost) has a
// model decrease of at most tol * cost over its gain ratio: within this
// factor of tol * cost for any ratio above its inverse. Such a step's cost
// is taken without the Jacobians, which a last step does not use.
constexpr double kLastStepModelRatio = 2.0;

std::string MessageWith(const char* format, double a, double b) {
  char text[160];
  std::snprintf(text, sizeof(text), format, a, b);
  return text;
}

}  // namespace

bool BandedSolvable(const ceres::Problem& problem, const BandedColumns& columns,
                    std::string* why) {
  std::set<const double*> blocks;
  for (const auto* set : {&columns.timed, &columns.placed, &columns.last}) {
    blocks.insert(set->begin(), set->end());
  }
  if (static_cast<int>(blocks.size()) != problem.NumParameterBlocks() ||
      blocks.size() !=
          columns.timed.size() + columns.placed.size() + columns.last.size()) {
    *why = "the columns do not hold every parameter block once";
    return false;
  }
  for (const double* block : blocks) {
    if (!problem.HasParameterBlock(block)) {
      *why = "the columns hold a block the problem does not";
      return false;
    }
    if (problem.HasManifold(block)) {
      *why = "a parameter block has a manifold";
      return false;
    }
  }
  return true;
}

void MinimizeBanded(const ceres::Solver::Options& options,
                    BandedProblem* banded, ceres::Problem* problem,
                    ceres::Solver::Summary* summary, double decrement_tolerance,
                    BandedLinearization* last) {
  CHECK(options.jacobi_scaling && !options.use_nonmonotonic_steps &&
        !options.use_inner_iterations)
      << "MinimizeBanded implements Ceres's default trust-region loop only";
  const double start = Now();
  *summary = ceres::Solver::Summary();
  summary->minimizer_type = ceres::TRUST_REGION;
  summary->trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  summary->num_parameter_blocks = problem->NumParameterBlocks();
  summary->num_parameters = problem->NumParameters();
  summary->num_residual_blocks = problem->NumResidualBlocks();
  summary->num_residuals = problem->NumResiduals();
  summary->num_threads_given = options.num_threads;
  summary->num_threads_used = 1;
  summary->num_successful_steps = summary->num_unsuccessful_steps = 0;

  const int n = banded->num_columns();
  summary->num_parameters_reduced = n;
  summary->num_parameter_blocks_reduced = banded->num_variable_blocks();
  const Eigen::VectorXd start_values = banded->Gather();
  // As Ceres's preprocessor: the start projected onto the bounds.
  Eigen::VectorXd x = start_values;
  banded->Project(&x);
  Eigen::VectorXd best = x, gradient(n);
  std::unique_ptr<EnvelopeMatrix> hessian;  // H = J^T J at x.
  // Costs without the fixed cost, which the reported ones include.
  double cost = 0.0, fixed_cost = 0.0;
  auto finish = [&](ceres::TerminationType type, const std::string& message) {
    summary->termination_type = type;
    summary->message = message;
    // As Ceres: a failed solve leaves the starting values.
    banded->Scatter(summary->IsSolutionUsable() ? best : start_values);
    // H and g are those of x, the last point linearised.
    if (last != nullptr && summary->IsSolutionUsable() && hessian &&
        (x.array() == best.array()).all()) {
      last->x = best;
      last->gradient = gradient;
      last->hessian = std::move(hessian);
    }
    summary->final_cost = summary->initial_cost;
    for (const ceres::IterationSummary& i : summary->iterations) {
      summary->final_cost = std::min(summary->final_cost, i.cost);
    }
    summary->minimizer_time_in_seconds = Now() - start;
    summary->total_time_in_seconds = summary->minimizer_time_in_seconds;
  };
  if (!banded->FixedCost(&fixed_cost)) {
    return finish(ceres::FAILURE, "Unable to evaluate the fixed cost.");
  }
  summary->fixed_cost = fixed_cost;
  if (n == 0) {
    summary->initial_cost = fixed_cost;
    return finish(ceres::CONVERGENCE,
                  "Function tolerance reached. No non-constant parameter "
                  "blocks found.");
  }
  hessian = std::make_unique<EnvelopeMatrix>(banded->envelope_first());
  EnvelopeMatrix system(banded->envelope_first());
  // The candidate is linearised as its cost is taken (one evaluation of
  // the residuals per step, not two); a rejected one's H is dropped.
  // Ceres's order of the tests is kept: the step's length before its cost.
  auto candidate_hessian =
      std::make_unique<EnvelopeMatrix>(banded->envelope_first());
  Eigen::VectorXd candidate_gradient(n);
  if (!banded->Linearize(x, &cost, &gradient, hessian.get())) {
    return finish(ceres::FAILURE, "Residual and Jacobian evaluation failed.");
  }
  // Jacobi scaling from the first Jacobian, kept for the whole solve.
  Eigen::VectorXd scale(n);
  for (int i = 0; i < n; ++i) {
    scale[i] = 1.0 / (1.0 + std::sqrt((*hessian)(i, i)));
  }
  summary->initial_cost = cost + fixed_cost;
  double minimum_cost = std::numeric_limits<double>::infinity();
  // As Ceres: no parameter tolerance test before the first accepted step
  // (its x_norm_ starts at -1).
  double x_norm = -1.0;
  double radius = options.initial_trust_region_radius;
  double decrease_factor = 2.0;
  // A rejected or invalid step: LevenbergMarquardtStrategy::StepRejected.
  auto Reject = [&] {
    radius /= decrease_factor;
    decrease_factor *= 2.0;
  };
  int invalid_steps = 0;
  // What the last accepted step leaves, by its predicted decrease m and its
  // actual one rho m: along the step the cost's curvature is (2 - rho) times
  // the model's, so a step of the right length would have gained
  // m / (2 - rho), which bounds what is left after it. Infinite for a
  // damped step or where the model's curvature is not the cost's (rho >= 2).
  double accepted_remaining = std::numeric_limits<double>::infinity();
  bool undamped = false;  // The step being solved.
  ceres::IterationSummary it;
  it.step_is_valid = it.step_is_successful = true;
  it.eta = options.eta;
  it.cost = cost + fixed_cost;
  it.gradient_max_norm = gradient.lpNorm<Eigen::Infinity>();
  it.gradient_norm = gradient.norm();
  double iteration_start = start;
  for (;;) {
    // Ceres's FinalizeIterationAndCheckIfMinimizerCanContinue.
    if (it.step_is_successful) {
      ++summary->num_successful_steps;
      it.step_is_nonmonotonic = !(cost < minimum_cost);
      if (cost < minimum_cost) {
        minimum_cost = cost;
        best = x;
      }
    } else {
      ++summary->num_unsuccessful_steps;
    }
    it.trust_region_radius = radius;
    it.iteration_time_in_seconds = Now() - iteration_start;
    it.cumulative_time_in_seconds = Now() - start;
    summary->iterations.push_back(it);
    if (options.update_state_every_iteration) banded->Scatter(x);
    for (ceres::IterationCallback* callback : options.callbacks) {
      const ceres::CallbackReturnType answer = (*callback)(it);
      if (answer == ceres::SOLVER_ABORT) {
        return finish(ceres::USER_FAILURE,
                      "User callback returned SOLVER_ABORT.");
      }
      if (answer == ceres::SOLVER_TERMINATE_SUCCESSFULLY) {
        return finish(ceres::USER_SUCCESS,
                      "User callback returned SOLVER_TERMINATE_SUCCESSFULLY.");
      }
    }
    if (Now() - start >= options.max_solver_time_in_seconds) {
      return finish(
          ceres::NO_CONVERGENCE,
          MessageWith("Maximum solver time reached. Total solver time: "
                      "%e >= %e.",
                      Now() - start, options.max_solver_time_in_seconds));
    }
    if (it.iteration >= options.max_num_iterations) {
      return finish(ceres::NO_CONVERGENCE,
                    "Maximum number of iterations reached. Number of "
                    "iterations: " +
                        std::to_string(it.iteration) + ".");
    }
    if (it.step_is_successful &&
        it.gradient_max_norm <= options.gradient_tolerance) {
      return finish(
          ceres::CONVERGENCE,
          MessageWith("Gradient tolerance reached. Gradient max norm: "
                      "%e <= %e",
                      it.gradient_max_norm, options.gradient_tolerance));
    }
    // Newton's decrement as a stopping rule (Boyd and Vandenberghe 2004,
    // 9.5.1), with the model's decrease corrected by the step's quality.
    if (it.step_is_successful && accepted_remaining <= decrement_tolerance) {
      return finish(
          ceres::CONVERGENCE,
          MessageWith("Gauss-Newton decrement tolerance reached. Decrease "
                      "left after the last step: %e <= %e",
                      accepted_remaining, decrement_tolerance));
    }
    if (radius <= options.min_trust_region_radius) {
      return finish(
          ceres::CONVERGENCE,
          MessageWith("Minimum trust region radius reached. Trust region "
                      "radius: %e <= %e",
                      radius, options.min_trust_region_radius));
    }

    iteration_start = Now();
    ceres::IterationSummary next;
    next.iteration = it.iteration + 1;
    next.eta = options.eta;
    // The LM step in Jacobi-scaled columns z = x / scale (Ceres's
    // LevenbergMarquardtStrategy): (S H S + diag(clamped S H S) / radius) z
    // = -S g.
    Eigen::VectorXd damping(n);  // D, the diagonal added to S H S.
    for (int i = 0; i < n; ++i) {
      const double* h = hessian->row(i);
      double* a = system.row(i);
      const int f = hessian->first(i);
      for (int j = f; j <= i; ++j) a[j - f] = h[j - f] * scale[i] * scale[j];
      damping[i] = std::clamp(a[i - f], options.min_lm_diagonal,
                              options.max_lm_diagonal) /
                   radius;
      a[i - f] += damping[i];
    }
    const double solve_start = Now();
    Eigen::VectorXd step;
    double model_cost_change = 0.0;
    // L y = -S g solved as the rows of L are formed.
    Eigen::VectorXd y = -scale.cwiseProduct(gradient);
    bool valid = system.Factorize(&y);
    if (valid) {
      const Eigen::VectorXd z = system.SolveUpper(y);
      step = scale.cwiseProduct(z);
      // The Gauss-Newton model's decrease -(g^T dx + dx^T H dx / 2) without
      // a product with H: L L^T z = -S g gives -g^T dx = y^T y and
      // z^T S H S z = y^T y - z^T D z, so it is (y^T y + z^T D z) / 2, a sum
      // of squares (it assumes the solve's rounding, as Ceres's J dx does).
      const double damped = z.dot(damping.cwiseProduct(z));
      model_cost_change = 0.5 * (y.squaredNorm() + damped);
      undamped = radius >= kUndampedRadius &&
                 damped <= kMaxDampingShare * y.squaredNorm();
      valid = step.allFinite() && model_cost_change > 0.0;
    }
    next.step_solver_time_in_seconds = Now() - solve_start;
    if (!valid) {
      if (++invalid_steps >= options.max_num_consecutive_invalid_steps) {
        return finish(
            ceres::FAILURE,
            "Number of consecutive invalid steps more than "
            "Solver::Options::max_num_consecutive_invalid_steps: " +
                std::to_string(options.max_num_consecutive_invalid_steps));
      }
      Reject();
      next.cost = cost + fixed_cost;
      next.gradient_max_norm = it.gradient_max_norm;
      next.gradient_norm = it.gradient_norm;
      it = next;
      continue;
    }
    invalid_steps = 0;
    next.step_is_valid = true;
    Eigen::VectorXd candidate = x + step;
    banded->Project(&candidate);
    next.step_norm = (x - candidate).norm();  // As Ceres: the ambient step.
    if (next.step_norm <=
        options.parameter_tolerance * (x_norm + options.parameter_tolerance)) {
      return finish(
          ceres::CONVERGENCE,
          MessageWith("Parameter tolerance reached. Relative step_norm: "
                      "%e <= %e.",
                      next.step_norm / (x_norm + options.parameter_tolerance),
                      options.parameter_tolerance));
    }
    // A step that may be the last takes its cost alone (as Ceres does);
    // any other is linearised as its cost is taken.
    const bool maybe_last =
        model_cost_change <=
        kLastStepModelRatio * options.function_tolerance * cost;
    double candidate_cost;
    if (!(maybe_last ? banded->Cost(candidate, &candidate_cost)
                     : banded->Linearize(candidate, &candidate_cost,
                                         &candidate_gradient,
                                         candidate_hessian.get()))) {
      candidate_cost = std::numeric_limits<double>::max();
    }
    next.cost_change = cost - candidate_cost;
    if (std::abs(next.cost_change) <= options.function_tolerance * cost) {
      return finish(
          ceres::CONVERGENCE,
          MessageWith("Function tolerance reached. |cost_change|/cost: "
                      "%e <= %e",
                      std::abs(next.cost_change) / cost,
                      options.function_tolerance));
    }
    next.relative_decrease = next.cost_change / model_cost_change;
    if (next.relative_decrease > options.min_relative_decrease) {
      x = candidate;
      x_norm = x.norm();
      if (maybe_last) {
        if (!banded->Linearize(x, &cost, &gradient, hessian.get())) {
          return finish(ceres::FAILURE,
                        "Residual and Jacobian evaluation failed.");
        }
      } else {
        cost = candidate_cost;
        gradient.swap(candidate_gradient);
        hessian.swap(candidate_hessian);
      }
      next.step_is_successful = true;
      accepted_remaining =
          undamped && next.relative_decrease < 2.0
              ? model_cost_change / (2.0 - next.relative_decrease)
              : std::numeric_limits<double>::infinity();
      next.cost = cost + fixed_cost;
      next.gradient_max_norm = gradient.lpNorm<Eigen::Infinity>();
      next.gradient_norm = gradient.norm();
      radius = std::min(
          options.max_trust_region_radius,
          radius /
              std::max(1.0 / 3.0,
                       1.0 - std::pow(2.0 * next.relative_decrease - 1.0, 3)));
      decrease_factor = 2.0;
    } else {
      next.cost = candidate_cost + fixed_cost;
      next.gradient_max_norm = it.gradient_max_norm;
      next.gradient_norm = it.gradient_norm;
      Reject();
    }
    it = next;
  }
}

}  // namespace rff
