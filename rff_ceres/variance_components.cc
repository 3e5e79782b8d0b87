#include "rff_ceres/variance_components.h"

#include <algorithm>
#include <random>
#include <vector>

#include "Eigen/Cholesky"
#include "Eigen/LU"
#include "Eigen/SparseCholesky"
#include "ceres/crs_matrix.h"
#include "glog/logging.h"

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

namespace {

// Solves with H = J^T J for a Jacobian whose columns are [t columns of the
// trajectory and the other blocks | landmarks, two each], every row touching
// at most one landmark: H = [A B; B^T C] with C block diagonal, and H^-1
// follows from the Schur complement S = A - B C^-1 B^T (t x t). Forming it
// costs rows t^2 / 2 in dense products, where the sparse J^T J costs the sum
// over rows of nnz(row)^2 scattered updates: RFF rows are dense over the
// trajectory's weights. Larger or other structures take the sparse LDLT.
class GaussNewtonSolver {
 public:
  GaussNewtonSolver(const Eigen::SparseMatrix<double, Eigen::RowMajor>& j,
                    int t) {
    const Eigen::Index m = j.cols() - t;
    if (t <= kMaxDenseReducedSystem && m % 2 == 0 &&
        double(t) * (t + m) <= kMaxDenseEntries && DenseRows(j, t) &&
        FormSchur(j, t)) {
      positive_definite_ =
          schur_.info() == Eigen::Success && schur_.vectorD().minCoeff() > 0.0;
      structured_ = true;
      return;
    }
    sparse_.compute(Eigen::SparseMatrix<double>(j.transpose()) * j);
    positive_definite_ =
        sparse_.info() == Eigen::Success && sparse_.vectorD().minCoeff() > 0.0;
  }
  bool positive_definite() const { return positive_definite_; }

  Eigen::VectorXd Solve(const Eigen::VectorXd& z) const {
    if (!structured_) return sparse_.solve(z);
    const Eigen::Index t = b_.rows();
    const Eigen::VectorXd ut =
        schur_.solve(z.head(t) - b_ * ApplyCInverse(z.tail(b_.cols())));
    Eigen::VectorXd u(z.size());
    u.head(t) = ut;
    u.tail(b_.cols()) = ApplyCInverse(z.tail(b_.cols()) - b_.transpose() * ut);
    return u;
  }

 private:
  // Rows dense enough that dense products beat scattered updates: their
  // nonzeros, squared and summed, above 1/64 of rows t^2 (a dense flop is
  // ~30-60x cheaper than a scattered update).
  static bool DenseRows(const Eigen::SparseMatrix<double, Eigen::RowMajor>& j,
                        int t) {
    double sparse_updates = 0.0;
    for (Eigen::Index r = 0; r < j.rows(); ++r) {
      const double nnz = j.outerIndexPtr()[r + 1] - j.outerIndexPtr()[r];
      sparse_updates += nnz * nnz;
    }
    return 64.0 * sparse_updates > double(j.rows()) * t * t;
  }

  // 2^25 doubles (256 MB) for A and B together.
  static constexpr double kMaxDenseEntries = 33554432.0;
  static constexpr int kChunkRows = 256;

  // False when a row touches two landmarks or a landmark block of C is not
  // positive definite (then H is not either, or the structure is not ours).
  bool FormSchur(const Eigen::SparseMatrix<double, Eigen::RowMajor>& j, int t) {
    const Eigen::Index m = j.cols() - t;
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(t, t);
    b_ = Eigen::MatrixXd::Zero(t, m);
    c_inverse_.assign(m / 2, Eigen::Matrix2d::Zero());
    Eigen::MatrixXd chunk(kChunkRows, t);
    for (Eigen::Index first = 0; first < j.rows(); first += kChunkRows) {
      const Eigen::Index rows =
          std::min<Eigen::Index>(kChunkRows, j.rows() - first);
      chunk.topRows(rows).setZero();
      for (Eigen::Index i = 0; i < rows; ++i) {
        Eigen::Index landmark = -1;
        Eigen::Vector2d landmark_row = Eigen::Vector2d::Zero();
        for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(
                 j, first + i);
             it; ++it) {
          if (it.col() < t) {
            chunk(i, it.col()) = it.value();
            continue;
          }
          const Eigen::Index k = (it.col() - t) / 2;
          if (landmark >= 0 && landmark != k) return false;
          landmark = k;
          landmark_row[(it.col() - t) % 2] = it.value();
        }
        if (landmark < 0) continue;
        b_.middleCols<2>(2 * landmark).noalias() +=
            chunk.row(i).transpose() * landmark_row.transpose();
        c_inverse_[landmark].noalias() +=
            landmark_row * landmark_row.transpose();
      }
      a.selfadjointView<Eigen::Lower>().rankUpdate(
          chunk.topRows(rows).transpose());
    }
    for (Eigen::Matrix2d& c : c_inverse_) {
      if (!(c(0, 0) > 0.0 && c.determinant() > 0.0)) return false;
      c = c.inverse().eval();
    }
    // S = A - B C^-1 B^T, one product.
    Eigen::MatrixXd b_c_inverse(t, m);
    for (std::size_t k = 0; k < c_inverse_.size(); ++k) {
      b_c_inverse.middleCols<2>(2 * k).noalias() =
          b_.middleCols<2>(2 * k) * c_inverse_[k];
    }
    a.triangularView<Eigen::StrictlyUpper>() = a.transpose();
    a.noalias() -= b_c_inverse * b_.transpose();
    schur_.compute(a);
    return true;
  }

  Eigen::VectorXd ApplyCInverse(const Eigen::VectorXd& v) const {
    Eigen::VectorXd out(v.size());
    for (std::size_t k = 0; k < c_inverse_.size(); ++k) {
      out.segment<2>(2 * k) = c_inverse_[k] * v.segment<2>(2 * k);
    }
    return out;
  }

  bool structured_ = false;
  bool positive_definite_ = false;
  Eigen::MatrixXd b_;
  std::vector<Eigen::Matrix2d> c_inverse_;
  Eigen::LDLT<Eigen::MatrixXd> schur_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> sparse_;
};

// The problem's parameter blocks with its landmarks (the ordering's group 0)
// last; `*num_leading` gets the parameters of the others.
std::vector<double*> LandmarksLast(SlamProblem* problem, int* num_leading) {
  std::vector<double*> blocks, landmarks;
  problem->problem()->GetParameterBlocks(&blocks);
  const auto ordering = problem->Ordering();
  std::vector<double*> order;
  *num_leading = 0;
  for (double* block : blocks) {
    if (ordering != nullptr && ordering->IsMember(block) &&
        ordering->GroupId(block) == 0) {
      landmarks.push_back(block);
    } else {
      order.push_back(block);
      *num_leading += problem->problem()->ParameterBlockSize(block);
    }
  }
  order.insert(order.end(), landmarks.begin(), landmarks.end());
  return order;
}

}  // namespace

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
                                std::string* error) {
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
  const GaussNewtonSolver hessian(jacobian, num_leading);
  if (!hessian.positive_definite()) {
    *error = "the Gauss-Newton Hessian is not positive definite";
    return false;
  }

  std::array<double, kNumVarianceGroups> traces{};
  std::mt19937 engine(options.seed);
  Eigen::VectorXd z(jacobian.cols());
  for (int probe = 0; probe < options.probes; ++probe) {
    for (Eigen::Index i = 0; i < z.size(); ++i) {
      z[i] = (engine() & 1u) ? 1.0 : -1.0;
    }
    const Eigen::VectorXd jz = jacobian * z;
    const Eigen::VectorXd ju = jacobian * hessian.Solve(z);
    for (Eigen::Index r = 0; r < jz.size(); ++r) {
      traces[static_cast<int>(groups[r])] += jz[r] * ju[r];
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
    }
  }
  return true;
}

}  // namespace rff
