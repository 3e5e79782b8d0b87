#include "rff_ceres/selected_inverse.h"

#include <algorithm>
#include <cmath>

#include "Eigen/OrderingMethods"
#include "Eigen/SparseCholesky"

namespace rff {

bool SelectedInverse::Compute(const Eigen::SparseMatrix<double>& h,
                              std::int64_t max_factor_nonzeros) {
  permutation_.clear();
  column_starts_.clear();
  rows_.clear();
  inverse_.clear();
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
  for (int j = n - 1; j >= 0; --j) {
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
  }
  return true;
}

std::int64_t SelectedInverse::Find(int row, int column) const {
  const auto begin = rows_.begin() + column_starts_[column];
  const auto end = rows_.begin() + column_starts_[column + 1];
  const auto it = std::lower_bound(begin, end, row);
  return it != end && *it == row ? it - rows_.begin() : -1;
}

bool SelectedInverse::Entry(int i, int j, double* value) const {
  const int n = static_cast<int>(permutation_.size());
  if (i < 0 || j < 0 || i >= n || j >= n) return false;
  const int a = permutation_[i];
  const int b = permutation_[j];
  const std::int64_t at = Find(std::max(a, b), std::min(a, b));
  if (at < 0) return false;
  *value = inverse_[at];
  return true;
}

}  // namespace rff
