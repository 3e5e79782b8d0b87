#include "rff_ceres/ceres_solve.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <memory>

#include "ceres/types.h"
#include "glog/logging.h"
#include "rff_ceres/banded_minimizer.h"
#include "rff_ceres/envelope_cholesky.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/linear_system_size.h"
#include "rff_ceres/option_error.h"
#include "rff_ceres/slam_solver.h"

namespace rff {
namespace {

// Linear solver names are read as Ceres reads its own: in any case.
bool IsBandedCholesky(std::string name) {
  for (char& c : name) c = static_cast<char>(std::toupper(c));
  return name == kBandedCholesky;
}

// The preconditioners a flag can choose (SUBSET cannot be set up from one).
constexpr char kPreconditioners[] =
    "auto, IDENTITY, JACOBI, SCHUR_JACOBI, CLUSTER_JACOBI or "
    "CLUSTER_TRIDIAGONAL";

}  // namespace

bool ToCeresOptions(const SolverOptions& options,
                    ceres::Solver::Options* ceres_options, std::string* error) {
  // "auto" is settled per problem by ChooseLinearSolver; until then the
  // sparse Cholesky, whose options are always valid.
  // BANDED_CHOLESKY is not Ceres's: its Ceres options are the sparse
  // Cholesky's, for the problems it does not take.
  const bool banded = IsBandedCholesky(options.linear_solver);
  std::string name = options.linear_solver == "auto" || banded
                         ? "SPARSE_NORMAL_CHOLESKY"
                         : options.linear_solver;
  if (!ceres::StringToLinearSolverType(name,
                                       &ceres_options->linear_solver_type)) {
    *error = OptionError("linear_solver", options.linear_solver,
                         "unknown linear solver",
                         "auto, BANDED_CHOLESKY, DENSE_SCHUR, SPARSE_SCHUR, "
                         "ITERATIVE_SCHUR, DENSE_QR, DENSE_NORMAL_CHOLESKY, "
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
  if (banded &&
      ceres_options->trust_region_strategy_type != ceres::LEVENBERG_MARQUARDT) {
    *error = OptionError("trust_region_strategy", options.trust_region_strategy,
                         "--linear_solver=BANDED_CHOLESKY runs "
                         "Levenberg-Marquardt only",
                         "LEVENBERG_MARQUARDT with BANDED_CHOLESKY");
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
        std::pair("parameter_tolerance", options.parameter_tolerance),
        std::pair("decrement_tolerance", options.decrement_tolerance)}) {
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

double DenseReducedWork(SlamProblem* problem) {
  const TrajectoryModel& model = problem->model();
  const ceres::Problem& ceres_problem = *problem->problem();
  double parameters = 0.0;
  for (int b = 0; b < model.num_blocks(); ++b) {
    const double* block = model.block(b);
    // As the envelope counts them: the blocks a solve can move.
    if (ceres_problem.HasParameterBlock(block) &&
        !ceres_problem.IsParameterBlockConstant(block)) {
      parameters += model.block_size(b);
    }
  }
  return parameters * parameters * parameters / 6.0;
}

StepWork EnvelopeAndDenseStepWork(SlamProblem* problem,
                                  const BandedProblem& banded) {
  StepWork work;
  work.envelope =
      banded.ProductWork(/*compressed=*/true) + banded.Size().multiply_adds;
  work.dense_reduced =
      banded.ProductWork(/*compressed=*/false) + DenseReducedWork(problem);
  return work;
}

bool RunSolve(const SolverOptions& solver, ceres::Solver::Options ceres_options,
              SlamProblem* problem, SlamResult* result, std::string* error,
              bool keep_linearization) {
  problem->DropLinearization();
  const bool asked = IsBandedCholesky(solver.linear_solver);
  // Auto's dense reduced system (feature weights after the landmarks'
  // elimination) against the envelope: the envelope where its step costs
  // no more than that system's (EnvelopeAndDenseStepWork).
  const bool dense_schur =
      ceres_options.linear_solver_type == ceres::DENSE_SCHUR;
  if (asked ||
      (solver.linear_solver == "auto" &&
       (dense_schur ||
        ceres_options.linear_solver_type == ceres::SPARSE_NORMAL_CHOLESKY) &&
       ceres_options.trust_region_strategy_type ==
           ceres::LEVENBERG_MARQUARDT)) {
    const BandedColumns columns = problem->BandColumns();
    std::string why;
    std::shared_ptr<BandedProblem> banded;
    if (BandedSolvable(*problem->problem(), columns, &why)) {
      banded = problem->BandedLayout(columns);
      const BandedSize size = banded->Size();
      // The envelope three times: H, the candidate step's H and the
      // factor of the damped system.
      const double bytes = 24.0 * static_cast<double>(size.entries);
      const double limit = MemoryLimitBytes(solver.max_memory_gb);
      const double work = size.multiply_adds / std::max(size.num_columns, 1);
      const StepWork step = !asked && dense_schur
                                ? EnvelopeAndDenseStepWork(problem, *banded)
                                : StepWork();
      char text[160];
      if (bytes > limit) {
        std::snprintf(text, sizeof(text),
                      "needs about %.3g GB for its envelope, more than the "
                      "%.3g GB allowed by --max_memory_gb",
                      bytes / 1e9, limit / 1e9);
        why = text;
      } else if (!asked && dense_schur && step.envelope > step.dense_reduced) {
        std::snprintf(text, sizeof(text),
                      "%.3g multiply-adds a step, more than the %.3g of the "
                      "dense reduced system",
                      step.envelope, step.dense_reduced);
        why = text;
      } else if (!asked && !dense_schur && !banded->BeatsSparseCholesky()) {
        // Landmarks seen over long stretches fill their rows of the factor;
        // a fill-reducing sparse Cholesky then does better on narrow
        // states. Feature windows' J^T J costs Ceres more than the fill
        // (envelope_cholesky.h).
        std::snprintf(text, sizeof(text),
                      "%.0f multiply-adds per variable in its factorisation, "
                      "more than %.0f, and %.3g in all, more than %.3g",
                      work, kMaxEnvelopeWorkPerVariable, size.multiply_adds,
                      kMaxSmallEnvelopeWork);
        why = text;
      }
    }
    if (why.empty()) {
      if (!asked) {
        result->linear_solver = kBandedCholesky;
        result->linear_solver_reason =
            std::string(dense_schur
                            ? "feature weights whose envelope takes no more "
                              "multiply-adds a step than the dense reduced "
                              "system"
                            : "banded states") +
            ": Levenberg-Marquardt on a Cholesky of the whole system in time "
            "order";
      }
      BandedLinearization last;
      MinimizeBanded(ceres_options, banded.get(), problem->problem(),
                     &result->summary, solver.decrement_tolerance,
                     keep_linearization ? &last : nullptr);
      if (last.hessian) {
        last.banded = std::move(banded);
        problem->KeepLinearization(std::move(last));
      }
      return CheckSolve(result->summary, problem, error);
    }
    if (asked) {
      *error = OptionError("linear_solver", solver.linear_solver, why,
                           "auto or a Ceres linear solver");
      return false;
    }
    result->linear_solver_reason +=
        " (not " + std::string(kBandedCholesky) + ": " + why + ")";
  }
  // Ceres's preprocessor edits the ordering it is given: a fresh one per solve.
  SetOrdering(problem, &ceres_options);
  if (!CheckLinearSystemFits(problem, ceres_options, solver.max_memory_gb,
                             error)) {
    return false;
  }
  ceres::Solve(ceres_options, problem->problem(), &result->summary);
  return CheckSolve(result->summary, problem, error);
}

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

ceres::CallbackReturnType ProgressLogger::operator()(
    const ceres::IterationSummary& s) {
  LOG(INFO) << "iteration " << s.iteration << ": cost " << s.cost
            << ", cost change " << s.cost_change << ", |gradient| "
            << s.gradient_max_norm << ", |step| " << s.step_norm
            << ", trust radius " << s.trust_region_radius << ", "
            << (s.step_is_successful ? "accepted" : "rejected") << ", "
            << s.cumulative_time_in_seconds << " s";
  return ceres::SOLVER_CONTINUE;
}

}  // namespace rff
