#include "rff_ceres/variance_components.h"

#include <algorithm>
#include <random>
#include <vector>

#include "ceres/crs_matrix.h"
#include "glog/logging.h"
#include "rff_ceres/gauss_newton_system.h"

namespace rff {

const char* VarianceGroupName(VarianceGroup group) {
  switch (group) {
    case VarianceGroup::kFixed:
      return "fixed";
    case VarianceGroup::kRange:
      return "range";
    case VarianceGroup::kBearing:
      return "bearing";
    case VarianceGroup::kOdometry:
      return "odometry";
    case VarianceGroup::kPriorPosition:
      return "trajectory position";
    case VarianceGroup::kPriorHeading:
      return "trajectory heading";
  }
  return "unknown";
}

bool Linearize(ceres::Problem* problem,
               const std::vector<ceres::ResidualBlockId>& blocks, double* cost,
               Eigen::VectorXd* residuals,
               Eigen::SparseMatrix<double, Eigen::RowMajor>* jacobian,
               std::string* error, const std::vector<double*>& columns) {
  ceres::Problem::EvaluateOptions options;
  options.residual_blocks = blocks;
  options.parameter_blocks = columns;
  std::vector<double> values;
  ceres::CRSMatrix crs;
  if (!problem->Evaluate(options, cost, &values, nullptr, &crs)) {
    *error = "the problem could not be evaluated";
    return false;
  }
  *residuals = Eigen::Map<const Eigen::VectorXd>(
      values.data(), static_cast<Eigen::Index>(values.size()));
  *jacobian = Eigen::Map<const Eigen::SparseMatrix<double, Eigen::RowMajor>>(
      crs.num_rows, crs.num_cols, static_cast<int>(crs.values.size()),
      crs.rows.data(), crs.cols.data(), crs.values.data());
  return true;
}

bool EstimateVarianceComponents(SlamProblem* problem,
                                const VarianceComponentOptions& options,
                                VarianceComponents* components,
                                std::string* error, SparseAnalysis* analysis) {
  *components = VarianceComponents();
  std::vector<ceres::ResidualBlockId> ids;
  problem->problem()->GetResidualBlocks(&ids);
  double cost = 0.0;
  Eigen::VectorXd residuals;
  Eigen::SparseMatrix<double, Eigen::RowMajor> jacobian;
  int num_leading = 0;
  const std::vector<double*> columns = LandmarksLast(problem, &num_leading);
  if (!Linearize(problem->problem(), ids, &cost, &residuals, &jacobian, error,
                 columns)) {
    return false;
  }
  const std::vector<VarianceGroup> groups = problem->RowGroups(ids);
  CHECK_EQ(static_cast<Eigen::Index>(groups.size()), residuals.size());
  // Only traces and solves are needed: banded states skip the dense Schur
  // complement their solver does without too (AutoLinearSolverType) and
  // take the envelope BANDED_CHOLESKY factorises.
  const bool banded = !problem->model().HasDenseReducedSystem();
  const GaussNewtonSystem hessian(
      jacobian, num_leading,
      banded ? Factorization::kEnvelopeOrSparse : Factorization::kSchurOrSparse,
      analysis,
      banded ? TimeOrderPositions(problem, columns) : std::vector<int>());
  if (!hessian.positive_definite()) {
    *error = "the Gauss-Newton Hessian is not positive definite";
    return false;
  }

  std::array<double, kNumVarianceGroups> traces{};
  std::mt19937 engine(options.seed);
  // Probes in batches: one pass over J and the factor per batch. A batch
  // holds J's rows times its probes twice: at most 2^22 doubles each.
  constexpr Eigen::Index kMaxBatchEntries = Eigen::Index{1} << 22;
  const int per_pass = static_cast<int>(std::clamp<Eigen::Index>(
      kMaxBatchEntries / std::max<Eigen::Index>(jacobian.rows(), 1), 1, 8));
  using RowMajorDense =
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  for (int first = 0; first < options.probes; first += per_pass) {
    const int count = std::min(per_pass, options.probes - first);
    Eigen::MatrixXd z(jacobian.cols(), count);
    // Rademacher signs from one bit per draw, without a branch: the bit is
    // a coin flip the branch predictor would miss half the time.
    for (int probe = 0; probe < count; ++probe) {
      for (Eigen::Index i = 0; i < z.rows(); ++i) {
        z(i, probe) =
            static_cast<double>(2 * static_cast<int>(engine() & 1u) - 1);
      }
    }
    const RowMajorDense jz = jacobian * RowMajorDense(z);
    const RowMajorDense ju = jacobian * RowMajorDense(hessian.Solve(z));
    for (int probe = 0; probe < count; ++probe) {
      for (Eigen::Index r = 0; r < jz.rows(); ++r) {
        traces[static_cast<int>(groups[r])] += jz(r, probe) * ju(r, probe);
      }
    }
  }
  for (Eigen::Index r = 0; r < residuals.size(); ++r) {
    VarianceComponent& c = (*components)[static_cast<int>(groups[r])];
    ++c.rows;
    c.sum_squares += residuals[r] * residuals[r];
  }
  for (int g = 0; g < kNumVarianceGroups; ++g) {
    VarianceComponent& c = (*components)[g];
    c.redundancy = c.rows - traces[g] / options.probes;
    if (g != static_cast<int>(VarianceGroup::kFixed) &&
        c.redundancy >= options.min_redundancy) {
      c.factor = c.sum_squares / c.redundancy;
      c.estimated = true;
    }
  }
  return true;
}

}  // namespace rff
