// The Ceres side of every solve: SolverOptions turned into Ceres's options,
// the linear solver and ordering settled per problem, the check of a
// solve's outcome, and the per-iteration callbacks.
#ifndef RFF_CERES_CERES_SOLVE_H_
#define RFF_CERES_CERES_SOLVE_H_

#include <functional>
#include <string>
#include <utility>

#include "ceres/iteration_callback.h"
#include "ceres/solver.h"
#include "rff_ceres/banded_problem.h"
#include "rff_ceres/slam_problem.h"
#include "rff_ceres/trajectory_model.h"

namespace rff {

struct SlamResult;  // slam_solver.h, which includes this header.

// The name --linear_solver takes for our banded Levenberg-Marquardt
// (banded_minimizer.h).
inline constexpr char kBandedCholesky[] = "BANDED_CHOLESKY";

// Ceres solver settings, named as Ceres names them.
struct SolverOptions {
  // "auto" (chosen from the problem's structure, see ChooseLinearSolver) or
  // a Ceres linear solver name.
  std::string linear_solver = "auto";
  std::string preconditioner = "auto";  // Or a Ceres preconditioner name.
  std::string trust_region_strategy = "LEVENBERG_MARQUARDT";
  // 1: reproducible to the bit; more threads sum in scheduling order.
  int num_threads = 1;
  int max_iterations = 100;
  double function_tolerance = 1e-8;
  double gradient_tolerance = 1e-10;
  double parameter_tolerance = 1e-8;
  // BANDED_CHOLESKY only: converged once an undamped step leaves less than
  // this to gain (MinimizeBanded); 0: Ceres's rules.
  // 0.01 leaves the estimate within about sqrt(2 x 0.01) = 0.14 posterior
  // standard deviations of the minimum along the step.
  double decrement_tolerance = 0.01;
  bool log_progress = false;  // Ceres's per-iteration log (glog INFO).
  // Asked before every Ceres iteration when set: true stops the solve, which
  // then fails ("the solve failed: ..."). For a caller that is interrupted
  // (a Python Ctrl-C) and cannot wait for the last iteration.
  std::function<bool()> should_abort;
  // Largest linear system a solve may form (GB; 0: half of the machine's
  // memory): a larger one is refused before it is allocated.
  double max_memory_gb = 0.0;
};

// Validates `options` and fills the Ceres options from it.
bool ToCeresOptions(const SolverOptions& options,
                    ceres::Solver::Options* ceres_options, std::string* error);

// The multiply-adds of one Cholesky of auto's dense reduced system (the
// model's weights the solve moves, after the landmarks' elimination):
// t^3 / 6.
double DenseReducedWork(SlamProblem* problem);

// The multiply-adds of a step on the envelope of `banded` (forming H from
// its rows, compressed where costs share a time, and factorising it) and
// on the dense reduced system (forming it from every row of J, as Ceres's
// DENSE_SCHUR does, and its Cholesky). Auto solves feature weights on the
// envelope where the first is at most the second.
struct StepWork {
  double envelope = 0.0, dense_reduced = 0.0;
};
StepWork EnvelopeAndDenseStepWork(SlamProblem* problem,
                                  const BandedProblem& banded);

// "auto" settles on AutoLinearSolverType; an explicit choice is obeyed.
// Records the choice and why in result->linear_solver(_reason).
void ChooseLinearSolver(const SolverOptions& solver,
                        const TrajectoryModel& model,
                        ceres::Solver::Options* options, SlamResult* result);

// Schur solvers eliminate the landmarks first; the others get no ordering.
void SetOrdering(SlamProblem* problem, ceres::Solver::Options* options);

// Solves `problem` from its current values into result->summary with the
// linear solver settled by ChooseLinearSolver: BANDED_CHOLESKY where asked,
// or where "auto" settled on the sparse Cholesky and the problem has no
// bounds and a cheap factorisation (the choice and why then recorded in
// `result`, after ChooseLinearSolver's, once per call); otherwise Ceres,
// once the system is known to fit in memory. False with the cause in
// `error` when it does not fit or the solve fails (CheckSolve). With
// `keep_linearization` a BANDED_CHOLESKY solve leaves its last
// linearisation in `problem` (SlamProblem::KeepLinearization) for the
// variance components and the convergence check; the incremental updates,
// which take none, skip the copy of the problem's state that costs.
bool RunSolve(const SolverOptions& solver, ceres::Solver::Options ceres_options,
              SlamProblem* problem, SlamResult* result, std::string* error,
              bool keep_linearization = false);

// A solve is accepted only if Ceres did not fail and the cost is finite.
// On failure the first non-finite residual is named, when there is one.
bool CheckSolve(const ceres::Solver::Summary& summary, SlamProblem* problem,
                std::string* error);

// Logs one line per Levenberg-Marquardt iteration through glog.
class ProgressLogger : public ceres::IterationCallback {
 public:
  ceres::CallbackReturnType operator()(
      const ceres::IterationSummary& s) override;
};

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

}  // namespace rff

#endif  // RFF_CERES_CERES_SOLVE_H_
