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

#include <cstdint>
#include <string>
#include <vector>

#include "ceres/problem.h"
#include "ceres/solver.h"
#include "rff_ceres/banded_problem.h"

namespace rff {

// The envelope of H in a column order: its columns (the variables), the
// doubles it stores and the multiply-adds of one factorisation.
struct BandedSize {
  int num_columns = 0;
  std::int64_t entries = 0;
  double multiply_adds = 0.0;
};

// Whether `problem` can be solved with its parameter blocks laid out as
// `columns` (every block of the problem once): no manifolds or bounds (this
// loop does not project); then its envelope's size in `*size`. Otherwise
// false with the cause in `why`.
bool BandedSolvable(const ceres::Problem& problem, const BandedColumns& columns,
                    BandedSize* size, std::string* why);

// Minimises `problem` from its current values and writes the best values
// back (the starting ones if it fails), filling `summary` as ceres::Solve
// would: iterations, costs with the fixed cost of residuals on constant
// blocks only, termination, message, times. `columns` as for
// BandedSolvable, which must have accepted them. Honours the options'
// tolerances, trust region radii, LM diagonal bounds, iteration and time
// limits, callbacks and update_state_every_iteration; it runs on one thread
// with Ceres's defaults of Jacobi scaling, monotonic steps and no inner
// iterations, which rff_slam never changes (checked).
void MinimizeBanded(const ceres::Solver::Options& options,
                    const BandedColumns& columns, ceres::Problem* problem,
                    ceres::Solver::Summary* summary);

}  // namespace rff

#endif  // RFF_CERES_BANDED_MINIMIZER_H_
