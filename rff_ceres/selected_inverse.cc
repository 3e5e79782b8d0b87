#include "rff_ceres/selected_inverse.h"

#include <algorithm>
#include <cmath>

#include "Eigen/Dense"
#include "Eigen/OrderingMethods"
#include "Eigen/SparseCholesky"

namespace rff {

bool SelectedInverse::Compute(const Eigen::SparseMatrix<double>& h,
                              std::int64_t max_factor_nonzeros,
                              int max_dense_block) {
  permutation_.clear();
  column_starts_.clear();
  rows_.clear();
  inverse_.clear();
  supernode_columns_ = 0;
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower,
                       Eigen::AMDOrdering<int>>
      cholesky(h);
  if (cholesky.info() != Eigen::Success) return false;
  Eigen::SparseMatrix<double> factor = cholesky.matrixL();
  factor.makeCompressed();
  if (factor.nonZeros() > max_factor_nonzeros) return false;
  const int n = static_cast<int>(factor.cols());
  const auto& indices = cholesky.permutationP().indices();
  permutation_.assign(indices.data(), indices.data() + n);
  column_starts_.assign(factor.outerIndexPtr(), factor.outerIndexPtr() + n + 1);
  rows_.assign(factor.innerIndexPtr(),
               factor.innerIndexPtr() + factor.nonZeros());
  const double* l = factor.valuePtr();
  // Find() bisects: each column must start at its diagonal and ascend.
  for (int j = 0; j < n; ++j) {
    const std::int64_t begin = column_starts_[j];
    const std::int64_t end = column_starts_[j + 1];
    if (begin == end || rows_[begin] != j || !(l[begin] > 0.0) ||
        !std::is_sorted(rows_.begin() + begin, rows_.begin() + end)) {
      return false;
    }
  }
  inverse_.assign(rows_.size(), 0.0);
  bool ok = true;
  for (int last = n - 1; ok && last >= 0;) {
    // The last columns of a supernode are a supernode themselves.
    const int first = SupernodeStart(last, last + 1 - max_dense_block);
    const int below = static_cast<int>(Count(first)) - (last + 1 - first);
    if (last > first && below <= max_dense_block) {
      ok = InvertSupernode(first, last + 1, l);
      supernode_columns_ += last + 1 - first;
    } else {
      for (int j = last; ok && j >= first; --j) ok = InvertColumn(j, l);
    }
    last = first - 1;
  }
  if (!ok) inverse_.clear();
  return ok;
}

int SelectedInverse::SupernodeStart(int last, int lowest) const {
  // Column j - 1 joins column j's supernode when its pattern is {j - 1}
  // followed by column j's.
  int first = last;
  while (first > std::max(lowest, 0) && Count(first - 1) == Count(first) + 1 &&
         std::equal(rows_.begin() + column_starts_[first],
                    rows_.begin() + column_starts_[first + 1],
                    rows_.begin() + column_starts_[first - 1] + 1)) {
    --first;
  }
  return first;
}

bool SelectedInverse::InvertColumn(int j, const double* l) {
  const std::int64_t diagonal = column_starts_[j];
  const std::int64_t end = column_starts_[j + 1];
  const double l_jj = l[diagonal];
  for (std::int64_t p = diagonal + 1; p < end; ++p) {
    const int i = rows_[p];
    double sum = 0.0;
    for (std::int64_t q = diagonal + 1; q < end; ++q) {
      const int k = rows_[q];
      const std::int64_t at = Find(std::max(i, k), std::min(i, k));
      if (at < 0) return false;
      sum += inverse_[at] * l[q];
    }
    inverse_[p] = -sum / l_jj;
  }
  double sum = 0.0;
  for (std::int64_t q = diagonal + 1; q < end; ++q) {
    sum += inverse_[q] * l[q];
  }
  inverse_[diagonal] = 1.0 / (l_jj * l_jj) - sum / l_jj;
  // As InvertSupernode: a pivot without digits (1e-310) is a failure.
  return std::all_of(inverse_.begin() + diagonal, inverse_.begin() + end,
                     [](double v) { return std::isfinite(v); });
}

bool SelectedInverse::InvertSupernode(int first, int end, const double* l) {
  const int s = end - first;
  const std::int64_t head = column_starts_[first];
  const int r = static_cast<int>(Count(first)) - s;
  // Columns first..end-1 share the rows R = rows_[head + s, head + s + r);
  // column j stores its rows j..end-1, then R.
  auto at = [&](int j, int k) {  // Position of the k-th row of column j.
    return column_starts_[j] + k;
  };
  Eigen::MatrixXd l_jj = Eigen::MatrixXd::Zero(s, s);
  Eigen::MatrixXd l_rj(r, s);
  for (int c = 0; c < s; ++c) {
    const int j = first + c;
    for (int k = 0; k < end - j; ++k) l_jj(c + k, c) = l[at(j, k)];
    for (int k = 0; k < r; ++k) l_rj(k, c) = l[at(j, end - j + k)];
  }
  // Z_RR from the columns of R, each holding the later rows of R (R is a
  // clique of the pattern): a merge of two ascending lists.
  const int* r_rows = rows_.data() + head + s;
  Eigen::MatrixXd z_rr(r, r);
  for (int b = 0; b < r; ++b) {
    const int column = r_rows[b];
    std::int64_t p = column_starts_[column];
    const std::int64_t stop = column_starts_[column + 1];
    for (int a = b; a < r; ++a) {
      while (p < stop && rows_[p] < r_rows[a]) ++p;
      if (p == stop || rows_[p] != r_rows[a]) return false;
      z_rr(a, b) = inverse_[p];
    }
  }
  // Z_RJ = -Z_RR L_RJ L_JJ^-1,  Z_JJ = L_JJ^-T (L_JJ^-1 - L_RJ^T Z_RJ).
  // (Eigen's products divide by a zero inner size: R may be empty.)
  const auto lower = l_jj.triangularView<Eigen::Lower>();
  Eigen::MatrixXd z_rj = Eigen::MatrixXd::Zero(r, s);
  Eigen::MatrixXd z_jj = lower.solve(Eigen::MatrixXd::Identity(s, s));
  if (r > 0) {
    z_rj.noalias() -= z_rr.selfadjointView<Eigen::Lower>() * l_rj;
    lower.solveInPlace<Eigen::OnTheRight>(z_rj);
    z_jj.noalias() -= l_rj.transpose() * z_rj;
  }
  l_jj.transpose().triangularView<Eigen::Upper>().solveInPlace(z_jj);
  for (int c = 0; c < s; ++c) {
    const int j = first + c;
    for (int k = 0; k < end - j; ++k) inverse_[at(j, k)] = z_jj(c + k, c);
    for (int k = 0; k < r; ++k) inverse_[at(j, end - j + k)] = z_rj(k, c);
  }
  return z_jj.allFinite() && z_rj.allFinite();
}

std::int64_t SelectedInverse::Count(int column) const {
  return column_starts_[column + 1] - column_starts_[column];
}

std::int64_t SelectedInverse::Find(int row, int column) const {
  const auto begin = rows_.begin() + column_starts_[column];
  const auto end = rows_.begin() + column_starts_[column + 1];
  const auto it = std::lower_bound(begin, end, row);
  return it != end && *it == row ? it - rows_.begin() : -1;
}

bool SelectedInverse::Entry(int i, int j, double* value) const {
  const int n = static_cast<int>(permutation_.size());
  if (i < 0 || j < 0 || i >= n || j >= n || inverse_.empty()) return false;
  const int a = permutation_[i];
  const int b = permutation_[j];
  const std::int64_t at = Find(std::max(a, b), std::min(a, b));
  if (at < 0) return false;
  *value = inverse_[at];
  return true;
}

}  // namespace rff
