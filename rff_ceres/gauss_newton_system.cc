#include "rff_ceres/gauss_newton_system.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "Eigen/LU"
#include "rff_ceres/banded_minimizer.h"
#include "rff_ceres/banded_problem.h"
#include "rff_ceres/ceres_solve.h"
#include "rff_ceres/variance_components.h"

namespace rff {
namespace {

// P^T L^-T D^-1 L^-1 P z of a SimplicialLDLT (H = P^T L D L^T P), all columns
// of z in one pass over L: Eigen's own solve walks L once per column, which
// for many right-hand sides is bound by reading L. Row-major, a row of the
// right-hand sides is contiguous. Per column the operations and their order
// are Eigen's (sparse_solve_triangular_selector), so the values are the
// same; only a zero's sign may differ (Eigen skips subtracting a zero).
Eigen::MatrixXd SolveLdltByRows(
    const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>& ldlt,
    const Eigen::MatrixXd& z) {
  using RowMajorDense =
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  RowMajorDense x = ldlt.permutationP() * z;
  const Eigen::SparseMatrix<double>& l = ldlt.matrixL().nestedExpression();
  const Eigen::Index n = l.cols();
  for (Eigen::Index j = 0; j < n; ++j) {  // L x = b, unit diagonal.
    for (Eigen::SparseMatrix<double>::InnerIterator it(l, j); it; ++it) {
      if (it.index() > j) x.row(it.index()) -= it.value() * x.row(j);
    }
  }
  const Eigen::VectorXd d_inverse = ldlt.vectorD().cwiseInverse();
  for (Eigen::Index j = 0; j < n; ++j) x.row(j) *= d_inverse[j];
  for (Eigen::Index j = n - 1; j >= 0; --j) {  // L^T x = b.
    for (Eigen::SparseMatrix<double>::InnerIterator it(l, j); it; ++it) {
      if (it.index() > j) x.row(j) -= it.value() * x.row(it.index());
    }
  }
  return ldlt.permutationPinv() * Eigen::MatrixXd(x);
}

// 2^25 doubles (256 MB) for A and B together.
constexpr double kMaxDenseEntries = 33554432.0;
constexpr int kChunkRows = 256;
constexpr double kMaxLandmarkCondition = 1e8;

// Rows dense enough over the leading columns that one dense SYRK beats the
// rows' own blocks: their nonzeros, squared and summed, above 1/4 of rows t^2
// (a SYRK flop is a few times cheaper than a small block's; measured on the
// laser's RFF rounds, t = 324 and 27-54 nonzeros a row: 0.79 s against
// 0.063 s for the blocks).
bool DenseRows(const RowMajorSparse& j, int t) {
  double sparse_updates = 0.0;
  for (Eigen::Index r = 0; r < j.rows(); ++r) {
    const double nnz = j.outerIndexPtr()[r + 1] - j.outerIndexPtr()[r];
    sparse_updates += nnz * nnz;
  }
  return 4.0 * sparse_updates > double(j.rows()) * t * t;
}

// A = J_t^T J_t (lower triangle), J_t the first t columns: dense SYRK over
// chunks of rows, or row by row in dense blocks for sparse rows.
Eigen::MatrixXd LeadingGram(const RowMajorSparse& j, int t) {
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(t, t);
  if (DenseRows(j, t)) {
    Eigen::MatrixXd chunk(kChunkRows, t);
    for (Eigen::Index first = 0; first < j.rows(); first += kChunkRows) {
      const Eigen::Index rows =
          std::min<Eigen::Index>(kChunkRows, j.rows() - first);
      chunk.topRows(rows).setZero();
      for (Eigen::Index i = 0; i < rows; ++i) {
        for (RowMajorSparse::InnerIterator it(j, first + i); it; ++it) {
          if (it.col() < t) chunk(i, it.col()) = it.value();
        }
      }
      a.selfadjointView<Eigen::Lower>().rankUpdate(
          chunk.topRows(rows).transpose());
    }
  } else {
    // Each row's outer product straight into A's lower triangle, a dense
    // block per pair of its runs of consecutive columns (a weight block's
    // features): A is t x t and stays in cache, where a sparse product
    // allocates and scatters.
    struct Run {
      Eigen::Index column, offset, size;  // offset into `values`.
    };
    std::vector<Run> runs;
    std::vector<double> values;
    for (Eigen::Index r = 0; r < j.rows(); ++r) {
      runs.clear();
      values.clear();
      for (RowMajorSparse::InnerIterator it(j, r); it; ++it) {
        if (it.col() >= t) continue;
        if (runs.empty() || it.col() != runs.back().column + runs.back().size) {
          runs.push_back(
              {it.col(), static_cast<Eigen::Index>(values.size()), 0});
        }
        values.push_back(it.value());
        ++runs.back().size;
      }
      // Columns ascend within a row: run i >= k lies at or below run k.
      for (std::size_t k = 0; k < runs.size(); ++k) {
        const Eigen::Map<const Eigen::VectorXd> v(
            values.data() + runs[k].offset, runs[k].size);
        for (std::size_t i = k; i < runs.size(); ++i) {
          const Eigen::Map<const Eigen::VectorXd> u(
              values.data() + runs[i].offset, runs[i].size);
          a.block(runs[i].column, runs[k].column, u.size(), v.size())
              .noalias() += u * v.transpose();
        }
      }
    }
  }
  a.triangularView<Eigen::StrictlyUpper>() = a.transpose();
  return a;
}

}  // namespace

std::vector<double*> LandmarksLast(SlamProblem* problem, int* num_leading) {
  // The problem's own order: Ceres lists its blocks by address, which
  // follows the heap's layout, and the sums over columns with it.
  // Blocks outside BandColumns (none the problem adds today) follow the
  // model's and calibrations in Ceres's order.
  ceres::Problem* ceres_problem = problem->problem();
  const BandedColumns columns = problem->BandColumns();
  std::vector<double*> order;
  for (const std::vector<double*>* group : {&columns.timed, &columns.last}) {
    for (double* block : *group) {
      if (ceres_problem->HasParameterBlock(block)) order.push_back(block);
    }
  }
  const std::unordered_set<const double*> placed(columns.placed.begin(),
                                                 columns.placed.end());
  std::unordered_set<const double*> listed(order.begin(), order.end());
  std::vector<double*> blocks;
  ceres_problem->GetParameterBlocks(&blocks);
  for (double* block : blocks) {
    if (listed.count(block) == 0 && placed.count(block) == 0) {
      order.push_back(block);
    }
  }
  *num_leading = 0;
  for (double* block : order) {
    *num_leading += ceres_problem->ParameterBlockSize(block);
  }
  for (double* block : columns.placed) {
    if (ceres_problem->HasParameterBlock(block)) order.push_back(block);
  }
  return order;
}

std::vector<int> TimeOrderPositions(SlamProblem* problem,
                                    const std::vector<double*>& columns) {
  std::unordered_map<const double*, int> rank;
  const std::vector<double*> order =
      BandedBlockOrder(*problem->problem(), problem->BandColumns());
  for (std::size_t k = 0; k < order.size(); ++k) {
    rank[order[k]] = static_cast<int>(k);
  }
  std::vector<int> start(columns.size() + 1, 0);  // Of each block's columns.
  std::vector<int> by_rank(columns.size());
  for (std::size_t b = 0; b < columns.size(); ++b) {
    if (rank.count(columns[b]) == 0) return {};
    start[b + 1] =
        start[b] + problem->problem()->ParameterBlockSize(columns[b]);
    by_rank[b] = static_cast<int>(b);
  }
  std::sort(by_rank.begin(), by_rank.end(), [&](int a, int b) {
    return rank.at(columns[a]) < rank.at(columns[b]);
  });
  std::vector<int> position(start.back());
  int next = 0;
  for (const int b : by_rank) {
    for (int c = start[b]; c < start[b + 1]; ++c) position[c] = next++;
  }
  return position;
}

bool FactorizeBanded(SlamProblem* problem, BandedSystem* system) {
  // The solve's own H at these values, when it left one: the same sums, and
  // affordable, as the solve factorised it at every step.
  BandedLinearization kept;
  if (problem->TakeLinearization(&kept)) {
    system->banded = std::move(kept.banded);
    system->x = std::move(kept.x);
    system->gradient = std::move(kept.gradient);
    system->factor = std::move(kept.hessian);
    return system->factor->Factorize();
  }
  const BandedColumns columns = problem->BandColumns();
  std::string why;
  if (!BandedSolvable(*problem->problem(), columns, &why)) return false;
  system->banded = problem->BandedLayout(columns);
  BandedProblem& banded = *system->banded;
  // As auto chooses for the solve (RunSolve): feature weights where the
  // envelope's step costs no more than their dense reduced system's, other
  // models where it beats a sparse Cholesky.
  if (static_cast<double>(banded.Size().entries) > kMaxDenseEntries) {
    return false;
  }
  if (problem->model().HasDenseReducedSystem()) {
    const StepWork work = EnvelopeAndDenseStepWork(problem, banded);
    if (work.envelope > work.dense_reduced) return false;
  } else if (!banded.BeatsSparseCholesky()) {
    return false;
  }
  system->x = banded.Gather();
  system->factor = std::make_unique<EnvelopeMatrix>(banded.envelope_first());
  double cost;
  return banded.Linearize(system->x, &cost, &system->gradient,
                          system->factor.get()) &&
         system->factor->Factorize();
}

namespace {

// Conjugate-gradient steps of GaussNewtonDecrease where H has no envelope.
constexpr int kMaxDecreaseIterations = 100;

// Whether H's Schur form (t leading columns of `j`, then landmarks) costs
// no more multiply-adds than the conjugate gradients' bound: the leading
// Gram row by row, S's landmark part and its factorisation, against two
// products with J per step.
bool SchurNoDearerThanIterations(const RowMajorSparse& j, int t) {
  if (!SchurFormFits(t, j.cols() - t)) return false;
  double schur = double(t) * t * (j.cols() - t) + double(t) * t * t / 3.0;
  for (Eigen::Index r = 0; r < j.rows(); ++r) {
    double leading = 0.0;
    for (RowMajorSparse::InnerIterator it(j, r); it; ++it) {
      if (it.col() < t) ++leading;
    }
    schur += leading * leading;
  }
  return schur <= 2.0 * kMaxDecreaseIterations * j.nonZeros();
}

}  // namespace

double GaussNewtonDecrease(SlamProblem* problem, bool* exact) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  if (exact != nullptr) *exact = false;
  BandedSystem banded;
  if (FactorizeBanded(problem, &banded)) {
    const double decrease =
        0.5 * banded.gradient.dot(banded.factor->Solve(banded.gradient));
    if (exact != nullptr) *exact = std::isfinite(decrease);
    return decrease;
  }
  std::vector<ceres::ResidualBlockId> ids;
  problem->problem()->GetResidualBlocks(&ids);
  int t = 0;
  const std::vector<double*> columns = LandmarksLast(problem, &t);
  double cost = 0.0;
  Eigen::VectorXd residuals;
  RowMajorSparse jacobian;
  std::string why;
  if (!Linearize(problem->problem(), ids, &cost, &residuals, &jacobian, &why,
                 columns)) {
    return kNaN;
  }
  const Eigen::VectorXd gradient = jacobian.transpose() * residuals;
  if (SchurNoDearerThanIterations(jacobian, t)) {
    const GaussNewtonSystem system(jacobian, t, Factorization::kSchurOnly);
    if (system.positive_definite()) {
      const double decrease = 0.5 * gradient.dot(system.Solve(gradient).col(0));
      if (exact != nullptr) *exact = std::isfinite(decrease);
      return decrease;
    }
  }
  // Jacobi preconditioner; an empty column (a block no residual moves) has
  // no gradient and keeps x at 0 whatever its entry.
  Eigen::VectorXd diagonal = Eigen::VectorXd::Zero(jacobian.cols());
  for (Eigen::Index r = 0; r < jacobian.outerSize(); ++r) {
    for (RowMajorSparse::InnerIterator it(jacobian, r); it; ++it) {
      diagonal[it.col()] += it.value() * it.value();
    }
  }
  for (double& d : diagonal) {
    if (d == 0.0) d = 1.0;
  }
  // Preconditioned CG on H x = g from x = 0: g^T x after k steps is the
  // lower bound.
  Eigen::VectorXd x = Eigen::VectorXd::Zero(gradient.size());
  Eigen::VectorXd r = gradient, z = r.cwiseQuotient(diagonal), p = z;
  double rz = r.dot(z);
  const double stop = 1e-12 * rz;  // The residual down by 1e6.
  for (int k = 0; k < kMaxDecreaseIterations && rz > stop; ++k) {
    const Eigen::VectorXd hp = jacobian.transpose() * (jacobian * p);
    const double curvature = p.dot(hp);
    if (!(curvature > 0.0)) return kNaN;
    const double alpha = rz / curvature;
    x += alpha * p;
    r -= alpha * hp;
    z = r.cwiseQuotient(diagonal);
    const double next = r.dot(z);
    p = z + (next / rz) * p;
    rz = next;
  }
  return 0.5 * gradient.dot(x);
}

bool EnvelopeAffordable(const BandedSize& size) {
  return static_cast<double>(size.entries) <= kMaxDenseEntries &&
         size.WorkWithinBound();
}

bool SchurFormFits(int t, Eigen::Index m) {
  return t >= 1 && t <= kMaxDenseReducedSystem && m % 2 == 0 &&
         double(t) * (t + m) <= kMaxDenseEntries;
}

GaussNewtonSystem::GaussNewtonSystem(const RowMajorSparse& jacobian, int t,
                                     Factorization factorization,
                                     SparseAnalysis* analysis,
                                     std::vector<int> time_order)
    : time_order_(std::move(time_order)) {
  if (factorization == Factorization::kEnvelopeOrSparse &&
      FormEnvelope(jacobian)) {
    return;
  }
  // A Schur complement singular to rounding is retried as the sparse LDLT
  // (solves only), as is a system without the form.
  const bool sparse_fallback = factorization != Factorization::kSchurOnly;
  if (factorization != Factorization::kSparse &&
      factorization != Factorization::kEnvelopeOrSparse &&
      SchurFormFits(t, jacobian.cols() - t) && FormSchur(jacobian, t) &&
      (positive_definite_ || !sparse_fallback)) {
    structured_ = true;
    return;
  }
  positive_definite_ = false;
  b_ = Eigen::MatrixXd();
  c_inverse_.clear();
  if (!sparse_fallback) return;
  const Eigen::SparseMatrix<double> h =
      Eigen::SparseMatrix<double>(jacobian.transpose()) * jacobian;
  if (analysis == nullptr) {
    sparse_->compute(h);
  } else {
    sparse_ = &analysis->ldlt;
    const int* outer = h.outerIndexPtr();
    const int* inner = h.innerIndexPtr();
    const std::size_t num_outer = h.outerSize() + 1, num_inner = h.nonZeros();
    if (!std::equal(outer, outer + num_outer, analysis->outer.begin(),
                    analysis->outer.end()) ||
        !std::equal(inner, inner + num_inner, analysis->inner.begin(),
                    analysis->inner.end())) {
      sparse_->analyzePattern(h);
      analysis->outer.assign(outer, outer + num_outer);
      analysis->inner.assign(inner, inner + num_inner);
    }
    sparse_->factorize(h);
  }
  positive_definite_ =
      sparse_->info() == Eigen::Success && sparse_->vectorD().minCoeff() > 0.0;
}

bool GaussNewtonSystem::FormEnvelope(const RowMajorSparse& j) {
  const int n = static_cast<int>(j.cols());
  if (static_cast<int>(time_order_.size()) != n) return false;
  std::vector<int> first(n);
  for (int c = 0; c < n; ++c) first[c] = c;
  for (Eigen::Index r = 0; r < j.rows(); ++r) {
    int lowest = n;
    for (RowMajorSparse::InnerIterator it(j, r); it; ++it) {
      lowest = std::min(lowest, time_order_[it.col()]);
    }
    for (RowMajorSparse::InnerIterator it(j, r); it; ++it) {
      int& f = first[time_order_[it.col()]];
      f = std::min(f, lowest);
    }
  }
  BandedSize size;
  size.num_columns = n;
  for (int i = 0; i < n; ++i) size.entries += i - first[i] + 1;
  size.multiply_adds = EnvelopeMatrix::FactorizationWork(first);
  if (!EnvelopeAffordable(size)) return false;
  envelope_ = std::make_unique<EnvelopeMatrix>(std::move(first));
  for (Eigen::Index r = 0; r < j.rows(); ++r) {
    for (RowMajorSparse::InnerIterator a(j, r); a; ++a) {
      const int pa = time_order_[a.col()];
      for (RowMajorSparse::InnerIterator b(j, r); b; ++b) {
        const int pb = time_order_[b.col()];
        if (pb <= pa) (*envelope_)(pa, pb) += a.value() * b.value();
      }
    }
  }
  // Not positive definite to rounding without pivoting: the sparse LDLT,
  // in its own order, decides.
  positive_definite_ = envelope_->Factorize();
  if (!positive_definite_) envelope_.reset();
  return positive_definite_;
}

// False when a row touches two landmarks (not this structure) or a
// landmark's block is ill-conditioned.
bool GaussNewtonSystem::FormSchur(const RowMajorSparse& j, int t) {
  const Eigen::Index m = j.cols() - t;
  b_ = Eigen::MatrixXd::Zero(t, m);
  std::vector<Eigen::Matrix2d> c(m / 2, Eigen::Matrix2d::Zero());
  for (Eigen::Index r = 0; r < j.rows(); ++r) {
    Eigen::Index landmark = -1;
    Eigen::Vector2d landmark_row = Eigen::Vector2d::Zero();
    for (RowMajorSparse::InnerIterator it(j, r); it; ++it) {
      if (it.col() < t) continue;
      const Eigen::Index k = (it.col() - t) / 2;
      if (landmark >= 0 && landmark != k) return false;
      landmark = k;
      landmark_row[(it.col() - t) % 2] = it.value();
    }
    if (landmark < 0) continue;
    c[landmark].noalias() += landmark_row * landmark_row.transpose();
    for (RowMajorSparse::InnerIterator it(j, r); it; ++it) {
      if (it.col() >= t) continue;
      b_.block<1, 2>(it.col(), 2 * landmark) +=
          it.value() * landmark_row.transpose();
    }
  }
  // J^T J squares the condition number of J: a landmark block left with
  // fewer than 8 digits (a bearing taken next to its landmark), or not
  // positive definite, goes to the sparse LDLT with its pivoting.
  c_inverse_.resize(c.size());
  for (std::size_t k = 0; k < c.size(); ++k) {
    const double determinant = c[k].determinant();
    // |C|_F^2 / det(C) ~ lambda_max / lambda_min.
    if (!(c[k](0, 0) > 0.0 && determinant > 0.0 &&
          c[k].squaredNorm() <= kMaxLandmarkCondition * determinant)) {
      return false;
    }
    c_inverse_[k] = c[k].inverse();
  }
  // S = A - B C^-1 B^T, one product.
  Eigen::MatrixXd b_c_inverse(t, m);
  for (std::size_t k = 0; k < c_inverse_.size(); ++k) {
    b_c_inverse.middleCols<2>(2 * k).noalias() =
        b_.middleCols<2>(2 * k) * c_inverse_[k];
  }
  Eigen::MatrixXd s = LeadingGram(j, t);
  s.noalias() -= b_c_inverse * b_.transpose();
  schur_.compute(s);
  // A zero pivot is not enough: S may be singular to rounding (rcond 1e-16),
  // where its inverse is noise; a rank-revealing QR of J decides then.
  positive_definite_ = schur_.info() == Eigen::Success &&
                       schur_.vectorD().minCoeff() > 0.0 &&
                       schur_.rcond() > kMinReciprocalCondition;
  return true;
}

Eigen::VectorXd GaussNewtonSystem::ApplyCInverse(
    const Eigen::VectorXd& v) const {
  Eigen::VectorXd out(v.size());
  for (std::size_t k = 0; k < c_inverse_.size(); ++k) {
    out.segment<2>(2 * k) = c_inverse_[k] * v.segment<2>(2 * k);
  }
  return out;
}

double GaussNewtonSystem::LogDeterminant() const {
  CHECK(positive_definite_);
  if (envelope_ != nullptr) return envelope_->LogDeterminant();
  if (!structured_) return sparse_->vectorD().array().log().sum();
  double sum = schur_.vectorD().array().log().sum();
  for (const Eigen::Matrix2d& c_inverse : c_inverse_) {
    sum -= std::log(c_inverse.determinant());
  }
  return sum;
}

Eigen::MatrixXd GaussNewtonSystem::Solve(const Eigen::MatrixXd& z) const {
  if (envelope_ != nullptr) {
    EnvelopeMatrix::RowMajorMatrix x(z.rows(), z.cols());
    for (Eigen::Index c = 0; c < z.rows(); ++c)
      x.row(time_order_[c]) = z.row(c);
    envelope_->SolveInPlace(&x);
    Eigen::MatrixXd u(z.rows(), z.cols());
    for (Eigen::Index c = 0; c < z.rows(); ++c)
      u.row(c) = x.row(time_order_[c]);
    return u;
  }
  if (!structured_) return SolveLdltByRows(*sparse_, z);
  const Eigen::Index t = b_.rows(), m = b_.cols();
  Eigen::MatrixXd u(z.rows(), z.cols());
  for (Eigen::Index k = 0; k < z.cols(); ++k) {
    const Eigen::VectorXd leading =
        schur_.solve(z.col(k).head(t) - b_ * ApplyCInverse(z.col(k).tail(m)));
    u.col(k).head(t) = leading;
    u.col(k).tail(m) =
        ApplyCInverse(z.col(k).tail(m) - b_.transpose() * leading);
  }
  return u;
}

Eigen::MatrixXd GaussNewtonSystem::LeadingCovariance() const {
  return schur_.solve(Eigen::MatrixXd::Identity(b_.rows(), b_.rows()));
}

std::vector<Eigen::Matrix2d> GaussNewtonSystem::LandmarkCovariances() const {
  const Eigen::MatrixXd s_inverse_b = schur_.solve(b_);
  std::vector<Eigen::Matrix2d> covariances(c_inverse_.size());
  for (std::size_t k = 0; k < c_inverse_.size(); ++k) {
    const Eigen::Matrix2d coupling =
        b_.middleCols<2>(2 * k).transpose() * s_inverse_b.middleCols<2>(2 * k);
    covariances[k] = c_inverse_[k] + c_inverse_[k] * coupling * c_inverse_[k];
  }
  return covariances;
}

}  // namespace rff
