#include "rff_ceres/banded_minimizer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <set>
#include <unordered_map>
#include <unordered_set>

#include "ceres/cost_function.h"
#include "ceres/loss_function.h"
#include "glog/logging.h"
#include "rff_ceres/envelope_cholesky.h"

namespace rff {
namespace {

double Now() {
  return std::chrono::duration<double>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// One residual block: its cost, loss and parameter blocks, each with its
// first column in the system (-1 for a constant block) and size; the
// arrays are BandedProblem's, shared by all terms.
struct ResidualTerm {
  const ceres::CostFunction* cost = nullptr;
  const ceres::LossFunction* loss = nullptr;
  int num_blocks = 0;
  double* const* blocks = nullptr;
  const int* column = nullptr;
  const int* size = nullptr;
};

// The problem's residuals over the variable blocks laid out as `columns`,
// each placed block after the last timed block one of its residuals
// touches.
class BandedProblem {
 public:
  BandedProblem(const ceres::Problem& problem, const BandedColumns& columns) {
    std::vector<ceres::ResidualBlockId> ids;
    problem.GetResidualBlocks(&ids);
    std::vector<int> begin;
    std::vector<double*> blocks;
    for (const ceres::ResidualBlockId id : ids) {
      problem.GetParameterBlocksForResidualBlock(id, &blocks);
      begin.push_back(static_cast<int>(blocks_.size()));
      blocks_.insert(blocks_.end(), blocks.begin(), blocks.end());
    }
    begin.push_back(static_cast<int>(blocks_.size()));
    // Per block its first column (-1: constant) and size.
    std::unordered_map<const double*, std::pair<int, int>> layout;
    layout.reserve(problem.NumParameterBlocks());
    // As Ceres's preprocessor: blocks no residual uses are no variables.
    const std::unordered_set<const double*> used(blocks_.begin(),
                                                 blocks_.end());
    for (double* block : ColumnOrder(columns, begin)) {
      const int size = problem.ParameterBlockSize(block);
      if (problem.IsParameterBlockConstant(block) || used.count(block) == 0) {
        layout[block] = {-1, size};
        continue;
      }
      layout[block] = {num_columns_, size};
      variables_.push_back(block);
      variable_sizes_.push_back(size);
      num_columns_ += size;
    }
    for (double* block : blocks_) {
      const std::pair<int, int>& place = layout.at(block);
      columns_.push_back(place.first);
      sizes_.push_back(place.second);
    }
    for (std::size_t r = 0; r < ids.size(); ++r) {
      ResidualTerm term;
      term.cost = problem.GetCostFunctionForResidualBlock(ids[r]);
      term.loss = problem.GetLossFunctionForResidualBlock(ids[r]);
      term.num_blocks = begin[r + 1] - begin[r];
      term.blocks = blocks_.data() + begin[r];
      term.column = columns_.data() + begin[r];
      term.size = sizes_.data() + begin[r];
      const bool variable =
          std::any_of(term.column, term.column + term.num_blocks,
                      [](int c) { return c >= 0; });
      // Terms of constant blocks only are Ceres's fixed cost: outside the
      // tolerance tests and the step quality.
      (variable ? terms_ : fixed_terms_).push_back(term);
    }
  }

  // The cost of the terms no variable changes; false as Cost.
  bool FixedCost(double* cost) {
    *cost = 0.0;
    for (const ResidualTerm& term : fixed_terms_) {
      double term_cost;
      if (!Evaluate(term, Eigen::VectorXd(), false, &term_cost)) return false;
      *cost += term_cost;
    }
    return true;
  }

  int num_columns() const { return num_columns_; }
  int num_variable_blocks() const {
    return static_cast<int>(variables_.size());
  }

  // Row i of H = J^T J stores from the first column any residual couples
  // to column i.
  std::vector<int> EnvelopeFirst() const {
    std::vector<int> first(num_columns_);
    for (int i = 0; i < num_columns_; ++i) first[i] = i;
    for (const ResidualTerm& term : terms_) {
      int lowest = num_columns_;
      for (int a = 0; a < term.num_blocks; ++a) {
        if (term.column[a] >= 0) lowest = std::min(lowest, term.column[a]);
      }
      for (int a = 0; a < term.num_blocks; ++a) {
        if (term.column[a] < 0) continue;
        for (int i = 0; i < term.size[a]; ++i) {
          first[term.column[a] + i] =
              std::min(first[term.column[a] + i], lowest);
        }
      }
    }
    return first;
  }

  Eigen::VectorXd Gather() const {
    Eigen::VectorXd x(num_columns_);
    int c = 0;
    for (std::size_t b = 0; b < variables_.size(); ++b) {
      for (int i = 0; i < variable_sizes_[b]; ++i) x[c++] = variables_[b][i];
    }
    return x;
  }

  void Scatter(const Eigen::VectorXd& x) const {
    int c = 0;
    for (std::size_t b = 0; b < variables_.size(); ++b) {
      for (int i = 0; i < variable_sizes_[b]; ++i) variables_[b][i] = x[c++];
    }
  }

  // The cost at x; false where a residual is not finite or a cost
  // function fails.
  bool Cost(const Eigen::VectorXd& x, double* cost) {
    *cost = 0.0;
    for (const ResidualTerm& term : terms_) {
      double term_cost;
      if (!Evaluate(term, x, /*jacobians=*/false, &term_cost)) return false;
      *cost += term_cost;
    }
    return true;
  }

  // The cost, gradient g = J^T r and H = J^T J at x, with each robust
  // loss's correction of the residual and Jacobian (Triggs et al. 2000,
  // 4.3, clamped as Ceres's Corrector clamps it where rho'' <= 0).
  bool Linearize(const Eigen::VectorXd& x, double* cost, Eigen::VectorXd* g,
                 EnvelopeMatrix* h) {
    *cost = 0.0;
    g->setZero(num_columns_);
    h->SetZero();
    for (const ResidualTerm& term : terms_) {
      double term_cost;
      if (!Evaluate(term, x, /*jacobians=*/true, &term_cost)) return false;
      *cost += term_cost;
      Accumulate(term, g, h);
    }
    return true;
  }

 private:
  // The blocks of `columns` in column order, from the residuals' blocks
  // (residual r's at blocks_[begin[r]] up to begin[r + 1]).
  std::vector<double*> ColumnOrder(const BandedColumns& columns,
                                   const std::vector<int>& begin) const {
    std::unordered_map<const double*, int> time_index, anchor;
    time_index.reserve(columns.timed.size());
    anchor.reserve(columns.placed.size());
    for (std::size_t k = 0; k < columns.timed.size(); ++k) {
      time_index[columns.timed[k]] = static_cast<int>(k);
    }
    for (const double* block : columns.placed) anchor[block] = -1;
    for (std::size_t r = 0; r + 1 < begin.size(); ++r) {
      int latest = -1;
      for (int e = begin[r]; e < begin[r + 1]; ++e) {
        const auto it = time_index.find(blocks_[e]);
        if (it != time_index.end()) latest = std::max(latest, it->second);
      }
      for (int e = begin[r]; e < begin[r + 1]; ++e) {
        const auto it = anchor.find(blocks_[e]);
        if (it != anchor.end()) it->second = std::max(it->second, latest);
      }
    }
    std::vector<std::vector<double*>> after(columns.timed.size() + 1);
    for (double* block : columns.placed) {
      after[anchor[block] + 1].push_back(block);
    }
    std::vector<double*> order = after[0];
    for (std::size_t k = 0; k < columns.timed.size(); ++k) {
      order.push_back(columns.timed[k]);
      order.insert(order.end(), after[k + 1].begin(), after[k + 1].end());
    }
    order.insert(order.end(), columns.last.begin(), columns.last.end());
    return order;
  }

  bool Evaluate(const ResidualTerm& term, const Eigen::VectorXd& x,
                bool jacobians, double* cost) {
    const int rows = term.cost->num_residuals();
    const std::size_t n = term.num_blocks;
    parameters_.resize(n);
    jacobian_rows_.resize(n);
    jacobian_pointers_.resize(n);
    for (std::size_t a = 0; a < n; ++a) {
      parameters_[a] =
          term.column[a] >= 0 ? x.data() + term.column[a] : term.blocks[a];
      jacobian_rows_[a].resize(static_cast<std::size_t>(rows) * term.size[a]);
      jacobian_pointers_[a] =
          jacobians && term.column[a] >= 0 ? jacobian_rows_[a].data() : nullptr;
    }
    // A buffer that keeps its capacity: terms of other sizes alternate.
    residual_buffer_.resize(rows);
    Eigen::Map<Eigen::VectorXd> residual(residual_buffer_.data(), rows);
    if (!term.cost->Evaluate(parameters_.data(), residual.data(),
                             jacobians ? jacobian_pointers_.data() : nullptr) ||
        !residual.allFinite()) {
      return false;
    }
    const double squared_norm = residual.squaredNorm();
    double rho[3] = {squared_norm, 1.0, 0.0};
    if (term.loss != nullptr) term.loss->Evaluate(squared_norm, rho);
    *cost = 0.5 * rho[0];
    if (!jacobians) return std::isfinite(*cost);
    const double sqrt_rho1 = std::sqrt(rho[1]);
    double residual_scaling = sqrt_rho1, alpha_over_norm = 0.0;
    if (squared_norm > 0.0 && rho[2] > 0.0) {
      const double alpha =
          1.0 - std::sqrt(1.0 + 2.0 * squared_norm * rho[2] / rho[1]);
      residual_scaling = sqrt_rho1 / (1.0 - alpha);
      alpha_over_norm = alpha / squared_norm;
    }
    for (std::size_t a = 0; a < n; ++a) {
      if (jacobian_pointers_[a] == nullptr) continue;
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic,
                               Eigen::RowMajor>>
          j(jacobian_rows_[a].data(), rows, term.size[a]);
      if (!j.allFinite()) return false;
      if (alpha_over_norm != 0.0) {
        const Eigen::RowVectorXd rj = residual.transpose() * j;
        j -= alpha_over_norm * residual * rj;
      }
      j *= sqrt_rho1;
    }
    residual *= residual_scaling;
    return std::isfinite(*cost);
  }

  // g += J^T r and the lower triangle of H += J^T J, block pair by pair.
  void Accumulate(const ResidualTerm& term, Eigen::VectorXd* g,
                  EnvelopeMatrix* h) const {
    const int rows = static_cast<int>(residual_buffer_.size());
    const double* residual = residual_buffer_.data();
    for (int a = 0; a < term.num_blocks; ++a) {
      if (term.column[a] < 0) continue;
      const double* ja = jacobian_rows_[a].data();
      const int sa = term.size[a], ca = term.column[a];
      for (int k = 0; k < rows; ++k) {
        for (int i = 0; i < sa; ++i)
          (*g)[ca + i] += ja[k * sa + i] * residual[k];
      }
      for (int b = 0; b < term.num_blocks; ++b) {
        const int cb = term.column[b];
        if (cb < 0 || cb > ca) continue;
        const double* jb = jacobian_rows_[b].data();
        const int sb = term.size[b];
        for (int i = 0; i < sa; ++i) {
          double* hi = &(*h)(ca + i, cb);
          const int width = a == b ? i + 1 : sb;
          for (int k = 0; k < rows; ++k) {
            const double v = ja[k * sa + i];
            const double* jbk = jb + k * sb;
            for (int j = 0; j < width; ++j) hi[j] += v * jbk[j];
          }
        }
      }
    }
  }

  std::vector<double*> variables_;  // In column order, with their sizes.
  std::vector<int> variable_sizes_;
  std::vector<double*> blocks_;  // Every term's blocks, columns and sizes.
  std::vector<int> columns_, sizes_;
  std::vector<ResidualTerm> terms_, fixed_terms_;
  int num_columns_ = 0;
  std::vector<const double*> parameters_;
  std::vector<std::vector<double>> jacobian_rows_;
  std::vector<double*> jacobian_pointers_;
  std::vector<double> residual_buffer_;  // The last term's residual.
};

std::string Format(const char* format, double a, double b) {
  char text[160];
  std::snprintf(text, sizeof(text), format, a, b);
  return text;
}

}  // namespace

bool BandedSolvable(const ceres::Problem& problem, const BandedColumns& columns,
                    BandedSize* size, std::string* why) {
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
    for (int i = 0; i < problem.ParameterBlockSize(block); ++i) {
      if (problem.GetParameterLowerBound(block, i) >
              -std::numeric_limits<double>::max() ||
          problem.GetParameterUpperBound(block, i) <
              std::numeric_limits<double>::max()) {
        *why =
            "a parameter has bounds (the self-calibrations of "
            "--estimate_range_calibration and --estimate_odometry_calibration "
            "have)";
        return false;
      }
    }
  }
  const BandedProblem banded(problem, columns);
  const std::vector<int> first = banded.EnvelopeFirst();
  *size = BandedSize();
  size->num_columns = banded.num_columns();
  for (int i = 0; i < static_cast<int>(first.size()); ++i) {
    size->entries += i - first[i] + 1;
    // EnvelopeMatrix::Factorize's inner products of row i.
    for (int j = first[i]; j <= i; ++j) {
      size->multiply_adds += j - std::max(first[i], first[j]);
    }
  }
  return true;
}

void MinimizeBanded(const ceres::Solver::Options& options,
                    const BandedColumns& columns, ceres::Problem* problem,
                    ceres::Solver::Summary* summary) {
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

  BandedProblem banded(*problem, columns);
  const int n = banded.num_columns();
  summary->num_parameters_reduced = n;
  summary->num_parameter_blocks_reduced = banded.num_variable_blocks();
  const Eigen::VectorXd start_values = banded.Gather();
  Eigen::VectorXd x = start_values, best = x, gradient(n);
  // Costs without the fixed cost, which the reported ones include.
  double cost = 0.0, fixed_cost = 0.0;
  auto finish = [&](ceres::TerminationType type, const std::string& message) {
    summary->termination_type = type;
    summary->message = message;
    // As Ceres: a failed solve leaves the starting values.
    banded.Scatter(summary->IsSolutionUsable() ? best : start_values);
    summary->final_cost = summary->initial_cost;
    for (const ceres::IterationSummary& i : summary->iterations) {
      summary->final_cost = std::min(summary->final_cost, i.cost);
    }
    summary->minimizer_time_in_seconds = Now() - start;
    summary->total_time_in_seconds = summary->minimizer_time_in_seconds;
  };
  if (!banded.FixedCost(&fixed_cost)) {
    return finish(ceres::FAILURE, "Unable to evaluate the fixed cost.");
  }
  summary->fixed_cost = fixed_cost;
  if (n == 0) {
    summary->initial_cost = fixed_cost;
    return finish(ceres::CONVERGENCE,
                  "Function tolerance reached. No non-constant parameter "
                  "blocks found.");
  }
  EnvelopeMatrix hessian(banded.EnvelopeFirst());
  EnvelopeMatrix system(banded.EnvelopeFirst());
  if (!banded.Linearize(x, &cost, &gradient, &hessian)) {
    return finish(ceres::FAILURE, "Residual and Jacobian evaluation failed.");
  }
  // Jacobi scaling from the first Jacobian, kept for the whole solve.
  Eigen::VectorXd scale(n);
  for (int i = 0; i < n; ++i) scale[i] = 1.0 / (1.0 + std::sqrt(hessian(i, i)));
  summary->initial_cost = cost + fixed_cost;
  double minimum_cost = std::numeric_limits<double>::infinity();
  // As Ceres: no parameter tolerance test before the first accepted step
  // (its x_norm_ starts at -1).
  double x_norm = -1.0;
  double radius = options.initial_trust_region_radius;
  double decrease_factor = 2.0;
  int invalid_steps = 0;
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
    if (options.update_state_every_iteration) banded.Scatter(x);
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
      return finish(ceres::NO_CONVERGENCE,
                    Format("Maximum solver time reached. Total solver time: "
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
      return finish(ceres::CONVERGENCE,
                    Format("Gradient tolerance reached. Gradient max norm: "
                           "%e <= %e",
                           it.gradient_max_norm, options.gradient_tolerance));
    }
    if (radius <= options.min_trust_region_radius) {
      return finish(ceres::CONVERGENCE,
                    Format("Minimum trust region radius reached. Trust region "
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
      const double* h = hessian.row(i);
      double* a = system.row(i);
      const int f = hessian.first(i);
      for (int j = f; j <= i; ++j) a[j - f] = h[j - f] * scale[i] * scale[j];
      damping[i] = std::clamp(a[i - f], options.min_lm_diagonal,
                              options.max_lm_diagonal) /
                   radius;
      a[i - f] += damping[i];
    }
    const double solve_start = Now();
    Eigen::VectorXd step;
    double model_cost_change = 0.0;
    bool valid = system.Factorize();
    if (valid) {
      const Eigen::VectorXd z = system.Solve(-scale.cwiseProduct(gradient));
      step = scale.cwiseProduct(z);
      // The Gauss-Newton model's decrease -(g^T dx + dx^T H dx / 2), with
      // z^T S H S z = -g^T dx - z^T D z from the solve: no product with H.
      model_cost_change =
          -0.5 * gradient.dot(step) + 0.5 * z.dot(damping.cwiseProduct(z));
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
      radius /= decrease_factor;
      decrease_factor *= 2.0;
      next.cost = cost + fixed_cost;
      next.gradient_max_norm = it.gradient_max_norm;
      next.gradient_norm = it.gradient_norm;
      it = next;
      continue;
    }
    invalid_steps = 0;
    next.step_is_valid = true;
    const Eigen::VectorXd candidate = x + step;
    double candidate_cost;
    if (!banded.Cost(candidate, &candidate_cost)) {
      candidate_cost = std::numeric_limits<double>::max();
    }
    next.step_norm = step.norm();
    if (next.step_norm <=
        options.parameter_tolerance * (x_norm + options.parameter_tolerance)) {
      return finish(
          ceres::CONVERGENCE,
          Format("Parameter tolerance reached. Relative step_norm: "
                 "%e <= %e.",
                 next.step_norm / (x_norm + options.parameter_tolerance),
                 options.parameter_tolerance));
    }
    next.cost_change = cost - candidate_cost;
    if (std::abs(next.cost_change) <= options.function_tolerance * cost) {
      return finish(ceres::CONVERGENCE,
                    Format("Function tolerance reached. |cost_change|/cost: "
                           "%e <= %e",
                           std::abs(next.cost_change) / cost,
                           options.function_tolerance));
    }
    next.relative_decrease = next.cost_change / model_cost_change;
    if (next.relative_decrease > options.min_relative_decrease) {
      x = candidate;
      x_norm = x.norm();
      if (!banded.Linearize(x, &cost, &gradient, &hessian)) {
        return finish(ceres::FAILURE,
                      "Residual and Jacobian evaluation failed.");
      }
      next.step_is_successful = true;
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
      radius /= decrease_factor;
      decrease_factor *= 2.0;
    }
    it = next;
  }
}

}  // namespace rff
