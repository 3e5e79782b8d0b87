#include "rff_ceres/variance_components.h"

#include <algorithm>
#include <numeric>
#include <random>
#include <vector>

#include "ceres/crs_matrix.h"
#include "glog/logging.h"
#include "rff_ceres/banded_problem.h"
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

namespace {

using RowMajorDense =
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Probes per pass: a pass holds `rows` times its probes twice, at most
// 2^22 doubles each, and at most `most` probes.
int ProbesPerPass(Eigen::Index rows, int most) {
  constexpr Eigen::Index kMaxBatchEntries = Eigen::Index{1} << 22;
  return static_cast<int>(std::clamp<Eigen::Index>(
      kMaxBatchEntries / std::max<Eigen::Index>(rows, 1), 1, most));
}

// The Rademacher probes' signs over `n` columns, probe after probe, one bit
// per draw of mt19937(seed) (without a branch: the bit is a coin flip the
// branch predictor would miss half the time). They depend on nothing else,
// so the cache keeps them for the next call.
const std::vector<signed char>& ProbeSigns(
    Eigen::Index n, const VarianceComponentOptions& options,
    VarianceComponentCache* cache) {
  if (cache->columns != n || cache->probes != options.probes ||
      cache->seed != options.seed) {
    std::mt19937 engine(options.seed);
    cache->signs.resize(static_cast<std::size_t>(n) *
                        std::max(options.probes, 0));
    for (signed char& sign : cache->signs) {
      sign = static_cast<signed char>(2 * static_cast<int>(engine() & 1u) - 1);
    }
    cache->columns = n;
    cache->probes = options.probes;
    cache->seed = options.seed;
  }
  return cache->signs;
}

// Probes `first` to `first + count` as the columns of a row-major matrix
// whose row row_of[c] is column c's: placed row by row, so that no store
// strides across the whole matrix.
RowMajorDense PlaceProbes(const std::vector<signed char>& signs, int first,
                          int count, const std::vector<int>& row_of) {
  const std::size_t n = row_of.size();
  RowMajorDense z(static_cast<Eigen::Index>(n), count);
  for (std::size_t c = 0; c < n; ++c) {
    double* row = z.row(row_of[c]).data();
    for (int probe = 0; probe < count; ++probe) {
      row[probe] = signs[(first + probe) * n + c];
    }
  }
  return z;
}

// The rows' residuals and the groups' traces tr(H^-1 J_g^T J_g) summed
// over the probes, through the time-ordered envelope BANDED_CHOLESKY
// factorises: H from the residual blocks themselves, J z and J H^-1 z term
// by term, nothing stored per row of J. Probes are drawn over the columns
// `ll_columns` (LandmarksLast) as the sparse path draws them, so both see
// the same probes. False, before drawing any, for models FactorizeBanded
// refuses and problems with constant blocks: the sparse path decides then;
// false after drawing only where an evaluation fails, which the sparse
// path's evaluation then reports. `traces` is written only on success.
bool BandedTraces(SlamProblem* problem, const std::vector<double*>& ll_columns,
                  const std::vector<VarianceGroup>& groups,
                  const VarianceComponentOptions& options,
                  VarianceComponentCache* cache, Eigen::VectorXd* residuals,
                  std::array<double, kNumVarianceGroups>* traces,
                  double* log_det) {
  BandedSystem system;
  if (!FactorizeBanded(problem, &system)) return false;
  BandedProblem& banded = *system.banded;
  const EnvelopeMatrix& hessian = *system.factor;
  const Eigen::VectorXd& x = system.x;
  const int n = banded.num_columns();
  // Each column's place in the envelope's time order.
  std::vector<int> position;
  position.reserve(n);
  for (double* block : ll_columns) {
    const int first = banded.ColumnOf(block);
    if (first < 0) return false;  // A constant block.
    const int size = problem->problem()->ParameterBlockSize(block);
    for (int i = 0; i < size; ++i) position.push_back(first + i);
  }
  if (static_cast<int>(position.size()) != n ||
      banded.num_rows() != static_cast<int>(groups.size())) {
    return false;
  }
  const int per_pass = ProbesPerPass(n, options.probes);
  const std::vector<signed char>& signs = ProbeSigns(n, options, cache);
  Eigen::VectorXd products;
  std::array<double, kNumVarianceGroups> sums{};
  for (int first = 0; first < options.probes; first += per_pass) {
    const int count = std::min(per_pass, options.probes - first);
    const EnvelopeMatrix::RowMajorMatrix z =
        PlaceProbes(signs, first, count, position);
    EnvelopeMatrix::RowMajorMatrix u = z;
    hessian.SolveInPlace(&u);
    if (!banded.RowProducts(x, z, u, residuals, &products)) return false;
    for (Eigen::Index r = 0; r < products.size(); ++r) {
      sums[static_cast<int>(groups[r])] += products[r];
    }
  }
  *traces = sums;
  *log_det = hessian.LogDeterminant();
  return true;
}

// The same through the problem's sparse Jacobian and a GaussNewtonSystem
// (any model; the cache's analysis kept between calls).
bool SparseTraces(SlamProblem* problem, const std::vector<double*>& columns,
                  int num_leading,
                  const std::vector<ceres::ResidualBlockId>& ids,
                  const std::vector<VarianceGroup>& groups,
                  const VarianceComponentOptions& options,
                  VarianceComponentCache* cache, Eigen::VectorXd* residuals,
                  std::array<double, kNumVarianceGroups>* traces,
                  double* log_det, std::string* error) {
  double cost = 0.0;
  Eigen::SparseMatrix<double, Eigen::RowMajor> jacobian;
  if (!Linearize(problem->problem(), ids, &cost, residuals, &jacobian, error,
                 columns)) {
    return false;
  }
  CHECK_EQ(static_cast<Eigen::Index>(groups.size()), residuals->size());
  // Only traces and solves are needed: banded states skip the dense Schur
  // complement their solver does without too (AutoLinearSolverType).
  const bool banded = !problem->model().HasDenseReducedSystem();
  const GaussNewtonSystem hessian(
      jacobian, num_leading,
      banded ? Factorization::kEnvelopeOrSparse : Factorization::kSchurOrSparse,
      &cache->analysis,
      banded ? TimeOrderPositions(problem, columns) : std::vector<int>());
  if (!hessian.positive_definite()) {
    *error = "the Gauss-Newton Hessian is not positive definite";
    return false;
  }
  *log_det = hessian.LogDeterminant();
  // Probes in batches: one pass over J and the factor per batch.
  const int per_pass = ProbesPerPass(jacobian.rows(), 8);
  const std::vector<signed char>& signs =
      ProbeSigns(jacobian.cols(), options, cache);
  std::vector<int> in_order(jacobian.cols());
  std::iota(in_order.begin(), in_order.end(), 0);
  for (int first = 0; first < options.probes; first += per_pass) {
    const int count = std::min(per_pass, options.probes - first);
    const RowMajorDense z = PlaceProbes(signs, first, count, in_order);
    const RowMajorDense jz = jacobian * z;
    const RowMajorDense ju = jacobian * RowMajorDense(hessian.Solve(z));
    for (int probe = 0; probe < count; ++probe) {
      for (Eigen::Index r = 0; r < jz.rows(); ++r) {
        (*traces)[static_cast<int>(groups[r])] += jz(r, probe) * ju(r, probe);
      }
    }
  }
  return true;
}

}  // namespace

bool EstimateVarianceComponents(SlamProblem* problem,
                                const VarianceComponentOptions& options,
                                VarianceComponents* components,
                                std::string* error,
                                VarianceComponentCache* cache) {
  *components = VarianceComponents();
  VarianceComponentCache local;
  if (cache == nullptr) cache = &local;
  std::vector<ceres::ResidualBlockId> ids;
  problem->problem()->GetResidualBlocks(&ids);
  const std::vector<VarianceGroup> groups = problem->RowGroups(ids);
  int num_leading = 0;
  const std::vector<double*> columns = LandmarksLast(problem, &num_leading);
  std::array<double, kNumVarianceGroups> traces{};
  Eigen::VectorXd residuals;
  double* log_det = &components->log_det_hessian;
  const bool banded = BandedTraces(problem, columns, groups, options, cache,
                                   &residuals, &traces, log_det);
  if (!banded && !SparseTraces(problem, columns, num_leading, ids, groups,
                               options, cache, &residuals, &traces, log_det,
                               error)) {
    return false;
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

double LaplaceLogEvidence(
    const VarianceComponents& components,
    const std::array<double, kNumVarianceGroups>& log_row_scales) {
  double sum = components.log_det_hessian;
  for (int g = 0; g < kNumVarianceGroups; ++g) {
    sum += components[g].sum_squares + components[g].rows * log_row_scales[g];
  }
  return -0.5 * sum;
}

}  // namespace rff
