#include "rff_ceres/variance_components.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <random>
#include <tuple>
#include <utility>
#include <vector>

#include "ceres/crs_matrix.h"
#include "ceres/loss_function.h"
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

// Below this share of their variance the fitted rows of a group are all
// inliers (kappa over 0.98 for Cauchy's loss at 2 sigma on 3 rows), and
// the probes' noise could take the redundancy to or below 0.
constexpr double kMinRedundancyShare = 0.01;

// Whether `loss` down-weights large residuals: rho'(s) < 1 far out. The
// problem's "none" is a wrapper around no loss, rho(s) = s.
bool IsRobust(const ceres::LossFunction* loss) {
  if (loss == nullptr) return false;
  double rho[3];
  loss->Evaluate(1e8, rho);
  return rho[1] < 1.0;
}

// Where the loss-corrected squares of rows under a robust loss were, each
// row's rho'-weighted square over its Gaussian expectation at its group's
// redundancy share (header). The rows are `ids`' in order. One share per
// group: rows of unequal leverage, and a block whose rows belong to two
// groups, are weighed as if all had it.
bool WeighRobustSquares(SlamProblem* problem,
                        const std::vector<ceres::ResidualBlockId>& ids,
                        const std::vector<VarianceGroup>& groups,
                        const std::array<double, kNumVarianceGroups>& share,
                        Eigen::VectorXd* squares, std::string* error) {
  ceres::Problem& ceres_problem = *problem->problem();
  std::map<std::tuple<const ceres::LossFunction*, int, VarianceGroup>, double>
      consistency;
  std::vector<double> residuals;
  Eigen::Index row = 0;
  for (const ceres::ResidualBlockId id : ids) {
    const int k =
        ceres_problem.GetCostFunctionForResidualBlock(id)->num_residuals();
    const ceres::LossFunction* loss =
        ceres_problem.GetLossFunctionForResidualBlock(id);
    if (!IsRobust(loss)) {
      row += k;
      continue;
    }
    if (!problem->EvaluateWithoutLoss(id, &residuals)) {
      *error = "the problem could not be evaluated";
      return false;
    }
    double squared_norm = 0.0;
    for (const double r : residuals) squared_norm += r * r;
    double rho[3];
    loss->Evaluate(squared_norm, rho);
    for (const double r : residuals) {
      const VarianceGroup group = groups[row];
      auto [it, added] = consistency.try_emplace({loss, k, group}, 0.0);
      if (added) {
        it->second =
            RobustConsistency(*loss, k, share[static_cast<int>(group)]);
      }
      (*squares)[row++] = rho[1] * r * r / it->second;
    }
  }
  CHECK_EQ(row, squares->size());
  return true;
}

}  // namespace

double RobustConsistency(const ceres::LossFunction& loss, int k,
                         double variance) {
  // E[g(|z|^2)] over the chi density of |z|, z^(k-1) e^(-z^2/2) /
  // (2^(k/2-1) Gamma(k/2)), by Simpson's rule out to where it is below 1e-30.
  constexpr int kIntervals = 4000;
  const double upper = std::sqrt(static_cast<double>(k)) + 12.0;
  const double h = upper / kIntervals;
  const double log_norm =
      (0.5 * k - 1.0) * std::log(2.0) + std::lgamma(0.5 * k);
  double sum = 0.0;
  for (int i = 1; i <= kIntervals; ++i) {  // The integrand is 0 at z = 0.
    const double z = i * h;
    const double s = variance * z * z;
    double rho[3];
    loss.Evaluate(s, rho);
    const double density =
        std::exp((k - 1) * std::log(z) - 0.5 * z * z - log_norm);
    const double weight = i == kIntervals ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0);
    sum += weight * rho[1] * s * density;
  }
  return sum * h / 3.0 / (k * variance);
}

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
  for (const VarianceGroup group : groups) {
    ++(*components)[static_cast<int>(group)].rows;
  }
  std::array<double, kNumVarianceGroups> share{};
  for (int g = 0; g < kNumVarianceGroups; ++g) {
    VarianceComponent& c = (*components)[g];
    c.redundancy = c.rows - traces[g] / options.probes;
    share[g] = c.rows > 0
                   ? std::clamp(c.redundancy / c.rows, kMinRedundancyShare, 1.0)
                   : 1.0;
  }
  Eigen::VectorXd squares = residuals.cwiseAbs2();
  if (!WeighRobustSquares(problem, ids, groups, share, &squares, error)) {
    return false;
  }
  for (Eigen::Index r = 0; r < squares.size(); ++r) {
    (*components)[static_cast<int>(groups[r])].sum_squares += squares[r];
  }
  for (int g = 0; g < kNumVarianceGroups; ++g) {
    VarianceComponent& c = (*components)[g];
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
