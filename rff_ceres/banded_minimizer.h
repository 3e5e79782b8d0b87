// Levenberg-Marquardt over a ceres::Problem whose normal equations are
// factorised as an EnvelopeMatrix: the BANDED_CHOLESKY linear solver.
// Ceres 2.1 takes no linear solver of one's own, so this is Ceres's
// trust-region loop restated (TrustRegionMinimizer with the
// LevenbergMarquardtStrategy and Jacobi scaling: the same steps, radius
// updates and stopping rules, read from the same ceres::Solver::Options)
// around one factorisation that exploits a time-ordered system. The
// residual blocks, cost functions and losses are the problem's own.
#ifndef RFF_CERES_BANDED_MINIMIZER_H_
#define RFF_CERES_BANDED_MINIMIZER_H_

#include <string>

#include "ceres/problem.h"
#include "ceres/solver.h"
#include "rff_ceres/banded_problem.h"

namespace rff {

// Whether `problem` can be solved with its parameter blocks laid out as
// `columns` (every block of the problem once) and no manifolds; bounds are
// kept as Ceres keeps them (BandedProblem::Project). Otherwise false with
// the cause in `why`.
bool BandedSolvable(const ceres::Problem& problem, const BandedColumns& columns,
                    std::string* why);

// Minimises `problem`, laid out as `banded` (built on columns BandedSolvable
// accepted), from its current values and writes the best values back (the
// starting ones if it fails), filling `summary` as ceres::Solve would:
// iterations, costs with the fixed cost of residuals on constant blocks
// only, termination, message, times. Honours the options' tolerances,
// trust region radii, LM diagonal bounds, iteration and time limits,
// callbacks and update_state_every_iteration; it runs on one thread with
// Ceres's defaults of Jacobi scaling, monotonic steps and no inner
// iterations, which rff_slam never changes (checked). With
// `decrement_tolerance` > 0 it also stops, converged, after an undamped
// step that leaves less than it to gain (the cost's units; its predicted
// decrease over 2 - its quality): Ceres has no such rule, so 0 keeps
// Ceres's steps exactly. With
// `last`, a usable solve leaves there its last linearisation, which is at
// the values it writes back (every accepted step lowers the cost); `last`'s
// `banded` is the caller's to set.
void MinimizeBanded(const ceres::Solver::Options& options,
                    BandedProblem* banded, ceres::Problem* problem,
                    ceres::Solver::Summary* summary,
                    double decrement_tolerance = 0.0,
                    BandedLinearization* last = nullptr);

}  // namespace rff

#endif  // RFF_CERES_BANDED_MINIMIZER_H_
