#include "rff_ceres/linear_system_size.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <set>
#include <vector>

#include "ceres/problem.h"
#include "ceres/types.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/option_error.h"

namespace rff {

LinearSystemSize EstimateLinearSystemSize(SlamProblem* problem,
                                          ceres::LinearSolverType type) {
  ceres::Problem* ceres_problem = problem->problem();
  std::set<const double*> landmark_blocks;
  for (const auto& [id, position] : problem->landmarks()) {
    landmark_blocks.insert(problem->landmark_block(id));
  }
  const long long n = ceres_problem->NumParameters();
  const long long t = n - 2 * static_cast<long long>(landmark_blocks.size());
  const long long m = ceres_problem->NumResiduals();
  LinearSystemSize size;
  switch (type) {
    // Doubles, and a second copy where the dense factorisation takes one.
    case ceres::DENSE_QR:
      size = {8.0 * m * n, m, n, "Jacobian"};
      break;
    case ceres::DENSE_NORMAL_CHOLESKY:
      size = {2.0 * 8.0 * n * n, n, n, "normal equations"};
      break;
    case ceres::DENSE_SCHUR:
      size = {2.0 * 8.0 * t * t, t, t, "reduced system"};
      break;
    case ceres::SPARSE_SCHUR: {
      // The trajectory blocks each landmark sees become one dense clique of
      // the reduced system.
      std::map<const double*, std::set<double*>> seen;
      std::vector<ceres::ResidualBlockId> residuals;
      ceres_problem->GetResidualBlocks(&residuals);
      std::vector<double*> blocks;
      for (const ceres::ResidualBlockId id : residuals) {
        ceres_problem->GetParameterBlocksForResidualBlock(id, &blocks);
        const auto landmark = std::find_if(
            blocks.begin(), blocks.end(),
            [&](double* b) { return landmark_blocks.count(b) > 0; });
        if (landmark == blocks.end()) continue;
        for (double* b : blocks) {
          if (b != *landmark) seen[*landmark].insert(b);
        }
      }
      double entries = 0.0;
      for (const auto& [landmark, trajectory] : seen) {
        double clique = 0.0;
        for (double* b : trajectory) {
          clique += ceres_problem->ParameterBlockSize(b);
        }
        entries += clique * clique;
      }
      entries = std::min(entries, static_cast<double>(t) * t);
      size = {8.0 * entries, t, t, "reduced system"};
      break;
    }
    case ceres::SPARSE_NORMAL_CHOLESKY: {
      // J^T J has a dense block for every pair of parameter blocks that
      // share a residual block; the factor about as many again.
      std::set<std::pair<const double*, const double*>> pairs;
      std::vector<ceres::ResidualBlockId> residuals;
      ceres_problem->GetResidualBlocks(&residuals);
      std::vector<double*> blocks;
      double entries = 0.0;
      for (const ceres::ResidualBlockId id : residuals) {
        ceres_problem->GetParameterBlocksForResidualBlock(id, &blocks);
        for (const double* a : blocks) {
          for (const double* b : blocks) {
            if (a <= b && pairs.emplace(a, b).second) {
              entries +=
                  static_cast<double>(ceres_problem->ParameterBlockSize(a)) *
                  ceres_problem->ParameterBlockSize(b);
            }
          }
        }
      }
      size = {2.0 * 8.0 * entries, n, n, "normal equations (sparse)"};
      break;
    }
    default:
      break;
  }
  return size;
}

double MemoryLimitBytes(double max_memory_gb) {
  if (max_memory_gb > 0.0) return max_memory_gb * 1e9;
  const long pages = sysconf(_SC_PHYS_PAGES);
  const long page_size = sysconf(_SC_PAGE_SIZE);
  double limit =
      0.5 * static_cast<double>(pages) * static_cast<double>(page_size);
  // Under an address-space limit (ulimit -v) allocation fails long before
  // physical memory runs out.
  rlimit address_space;
  if (getrlimit(RLIMIT_AS, &address_space) == 0 &&
      address_space.rlim_cur != RLIM_INFINITY) {
    limit = std::min(limit, 0.5 * static_cast<double>(address_space.rlim_cur));
  }
  return limit;
}

bool CheckLinearSystemFits(SlamProblem* problem,
                           const ceres::Solver::Options& options,
                           double max_memory_gb, std::string* error) {
  const double limit_bytes = MemoryLimitBytes(max_memory_gb);
  const LinearSystemSize size =
      EstimateLinearSystemSize(problem, options.linear_solver_type);
  if (size.bytes <= limit_bytes) return true;
  const ceres::LinearSolverType type = options.linear_solver_type;
  const std::string solver = ceres::LinearSolverTypeToString(type);
  const bool dense = type == ceres::DENSE_QR || type == ceres::DENSE_SCHUR ||
                     type == ceres::DENSE_NORMAL_CHOLESKY;
  char needs[256];
  std::snprintf(needs, sizeof(needs),
                "needs about %.3g GB for its %lld x %lld %s, more than the "
                "%.3g GB allowed by --max_memory_gb",
                size.bytes / 1e9, size.rows, size.cols, size.what.c_str(),
                limit_bytes / 1e9);
  // Eliminating a landmark couples every state that sees it: one landmark
  // seen from the whole run fills the reduced system.
  if (type == ceres::SPARSE_SCHUR) {
    *error = OptionError("linear_solver", solver,
                         std::string(needs) +
                             " (eliminating the landmarks couples the states "
                             "that see a common landmark)",
                         "auto or SPARSE_NORMAL_CHOLESKY, which factorise the "
                         "sparse system as it is");
  } else if (dense) {
    *error = OptionError("linear_solver", solver, needs,
                         "auto, which picks a sparse factorisation where the "
                         "system is banded");
  } else {
    // The sparse system itself is too large: a smaller model or a larger
    // limit are the ways out.
    char more[64];
    std::snprintf(more, sizeof(more), "%.3g", size.bytes / 1e9);
    *error = OptionError(
        "max_memory_gb", FormatNumber(max_memory_gb),
        solver + " " + needs + " (fewer features or longer segments need less)",
        std::string("more than ") + more + " where the machine has it");
  }
  return false;
}

}  // namespace rff
