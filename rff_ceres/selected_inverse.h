// Entries of the inverse of a sparse symmetric positive definite matrix H on
// the pattern of its Cholesky factor, P H P^T = L L^T (Takahashi, Fagan and
// Chin 1973; Erisman and Tinney 1975). With Z = H^-1 in the permuted order,
// for every i >= j in the pattern of L, from the last column to the first,
//
//   Z_ij = delta_ij / L_jj^2 - (1 / L_jj) sum_{k > j, L_kj != 0} Z_ik L_kj,
//
// and every Z_ik the sum needs lies on that pattern too (the rows of a column
// of L form a clique of it). The pattern holds that of H, so each diagonal
// block and each pair of blocks that share a residual is available, at a
// cost of sum_j nnz(L_:j)^2: linear in the length of a banded run.
// Columns with one pattern below their diagonal block (a supernode J with
// rows R, such as a parameter block) are done at once, with dense products:
//
//   Z_RJ = -Z_RR L_RJ L_JJ^-1,  Z_JJ = L_JJ^-T (L_JJ^-1 - L_RJ^T Z_RJ).
#ifndef RFF_CERES_SELECTED_INVERSE_H_
#define RFF_CERES_SELECTED_INVERSE_H_

#include <cstdint>
#include <vector>

#include "Eigen/SparseCore"

namespace rff {

class SelectedInverse {
 public:
  // Factorises `h` (symmetric; its lower triangle is read) and computes the
  // inverse on the factor's pattern. False when `h` is not positive definite
  // or the factor has more than `max_factor_nonzeros` entries. Supernodes
  // are done in pieces of at most `max_dense_block` columns, and column by
  // column where more rows than that lie below them (the dense blocks Z_RR
  // and L_JJ take r^2 and s^2 doubles: 128 MiB each at the default).
  static constexpr int kMaxDenseBlock = 4096;
  bool Compute(const Eigen::SparseMatrix<double>& h,
               std::int64_t max_factor_nonzeros,
               int max_dense_block = kMaxDenseBlock);

  // (H^-1)_ij in the original order; false when (i, j) is outside the
  // computed pattern.
  bool Entry(int i, int j, double* value) const;

  // Columns the last Compute() did in supernodes of two or more.
  int supernode_columns() const { return supernode_columns_; }

 private:
  // Position of row `row` in column `column` of the factor's pattern, or -1.
  std::int64_t Find(int row, int column) const;
  // Entries in column `column` of the factor's pattern.
  std::int64_t Count(int column) const;
  // The first column of the supernode that ends at column `last`, or
  // `lowest` if that is later.
  int SupernodeStart(int last, int lowest) const;
  // Z on the pattern of column j, or of columns [first, end), from the
  // factor's values `l` and the later columns of Z; false when an entry it
  // needs is off the pattern or the result is not finite.
  bool InvertColumn(int j, const double* l);
  bool InvertSupernode(int first, int end, const double* l);

  std::vector<int> permutation_;  // Original index -> factor index.
  std::vector<std::int64_t> column_starts_;
  std::vector<int> rows_;  // Ascending within each column.
  std::vector<double> inverse_;
  int supernode_columns_ = 0;
};

}  // namespace rff

#endif  // RFF_CERES_SELECTED_INVERSE_H_
