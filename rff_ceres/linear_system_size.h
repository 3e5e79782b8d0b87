// The memory a Ceres linear solver's system needs on a SLAM problem, from the
// problem's structure alone, so that a solve that cannot fit is refused
// before anything is allocated (a dense Schur complement of 20k WNOA states
// is 3.2 GB; of 100k, 80 GB).
#ifndef RFF_CERES_LINEAR_SYSTEM_SIZE_H_
#define RFF_CERES_LINEAR_SYSTEM_SIZE_H_

#include <string>

#include "ceres/solver.h"
#include "rff_ceres/slam_problem.h"

namespace rff {

struct LinearSystemSize {
  double bytes = 0.0;  // 0 where no bound is computed (iterative solvers).
  long long rows = 0;  // Of the system whose size is `bytes`.
  long long cols = 0;
  std::string what;  // "reduced system", "normal equations", "Jacobian".
};

// Dense solvers: the matrix they form (DENSE_QR the Jacobian, m x n;
// DENSE_NORMAL_CHOLESKY the normal equations, n x n; DENSE_SCHUR the
// reduced system of the trajectory after the landmarks, t x t; the last two
// twice, matrix and factor). SPARSE_SCHUR:
// the reduced system's blocks that the landmarks couple, at most t x t
// (sum over landmarks of (trajectory parameters it sees)^2).
// SPARSE_NORMAL_CHOLESKY: the blocks of J^T J (every pair of parameter
// blocks sharing a residual block), twice, matrix and factor.
LinearSystemSize EstimateLinearSystemSize(SlamProblem* problem,
                                          ceres::LinearSolverType type);

// The memory limit of --max_memory_gb: `max_memory_gb` GB, or with 0 half of
// the machine's physical memory or of the address-space limit, the smaller.
double MemoryLimitBytes(double max_memory_gb);

// False, with the message a user needs (solver, size, limit and the way
// out), when the chosen solver's system exceeds MemoryLimitBytes of
// `max_memory_gb` (--max_memory_gb).
bool CheckLinearSystemFits(SlamProblem* problem,
                           const ceres::Solver::Options& options,
                           double max_memory_gb, std::string* error);

}  // namespace rff

#endif  // RFF_CERES_LINEAR_SYSTEM_SIZE_H_
