// A symmetric positive definite matrix stored by its lower envelope: row i
// keeps columns first(i)..i. The Cholesky factor L (A = L L^T) has no entry
// outside the envelope (George & Liu 1981, ch. 4), so a system whose columns
// are ordered in time (trajectory states, each landmark after its
// sightings, the calibrations last) factorises in O(n b^2 + m w b) for a
// band b and m longer rows of width w, with no symbolic analysis.
#ifndef RFF_CERES_ENVELOPE_CHOLESKY_H_
#define RFF_CERES_ENVELOPE_CHOLESKY_H_

#include <cstdint>
#include <vector>

#include "Eigen/Core"

namespace rff {

// Up to this many multiply-adds per variable in Factorize, an envelope
// beats a fill-reducing sparse Cholesky on our systems of narrow states;
// beyond it, landmarks seen again after long stretches fill the envelope
// (whole WNOA solves against CHOLMOD, 2026-11-28: 0.81x the time at 3313,
// 0.64x at 4670 (the laser preset's 17 landmarks seen throughout); 1.10x at
// 6361, 1.29x at 9623, 1.68x at 13635 (landmarks revisited);
// bench/README.md, "BANDED_CHOLESKY"). Feature windows, whose J^T J the
// envelope forms a panel at a time, beat CHOLMOD at any fill measured
// (0.25-0.7x at 9k-351k; bench/README.md).
constexpr double kMaxEnvelopeWorkPerVariable = 5000.0;
// Up to this many multiply-adds in all, the envelope beats it whatever the
// work per variable: CHOLMOD's analysis and per-step overhead outweigh the
// fill it saves (paper presets of 300-2000 poses whose 50 landmarks are seen
// throughout, 5000-5800 a variable, 1e7-7e7 in all: 0.33-0.5x the time).
// Kept below the first measured loss (1.2e8, landmarks revisited) with a
// margin, so the 5.2e7 and 7e7 wins fall outside it.
constexpr double kMaxSmallEnvelopeWork = 5e7;

class EnvelopeMatrix {
 public:
  // `first[i]` <= i is the first stored column of row i.
  explicit EnvelopeMatrix(std::vector<int> first);

  int size() const { return static_cast<int>(first_.size()); }
  int first(int i) const { return first_[i]; }
  // Stored entries: the doubles the factorisation needs.
  std::int64_t num_entries() const { return start_.back(); }
  void SetZero();
  // Entry (i, j), j in first(i)..i.
  double& operator()(int i, int j) {
    return values_[start_[i] + j - first_[i]];
  }
  double operator()(int i, int j) const {
    return values_[start_[i] + j - first_[i]];
  }
  double* row(int i) { return values_.data() + start_[i]; }
  const double* row(int i) const { return values_.data() + start_[i]; }

  // Replaces the matrix by its Cholesky factor L; false (matrix left
  // partly overwritten) when a pivot is not positive and finite. With
  // `lower`, also replaces it by L^-1 lower, each row of L used as it is
  // formed (SolveLower's arithmetic, without a pass of its own over L).
  bool Factorize(Eigen::VectorXd* lower = nullptr);
  // log det A with the factor of Factorize: 2 sum_i log L_ii.
  double LogDeterminant() const;
  // A^-1 b with the factor of Factorize: L^-T (L^-1 b), each half apart.
  Eigen::VectorXd Solve(const Eigen::VectorXd& b) const;
  Eigen::VectorXd SolveLower(const Eigen::VectorXd& b) const;
  Eigen::VectorXd SolveUpper(const Eigen::VectorXd& y) const;
  // A^-1 B in place for every column of B at once (a row of B contiguous,
  // L read once); per column the arithmetic of Solve.
  using RowMajorMatrix =
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  void SolveInPlace(RowMajorMatrix* b) const;
  // The multiply-adds of Factorize on an envelope that starts at `first`.
  static double FactorizationWork(const std::vector<int>& first);

  // Replaces the factor of Factorize by the entries of A^-1 on the
  // envelope, which holds every Z_ik the recurrence needs (Takahashi,
  // Fagan and Chin 1973): for the rows i > j of column j of L, last
  // column first,
  //   Z_ij = -(1 / L_jj) sum_k Z_ik L_kj,
  //   Z_jj = 1 / L_jj^2 - (1 / L_jj) sum_k Z_kj L_kj.
  // False (values left partly overwritten) where an entry is not finite.
  // The solves are meaningless after it. With `rcond`, also a bound of
  // A's reciprocal condition number from above, 1 / (max_j A_jj max_j
  // (A^-1)_jj): each norm is at least its largest diagonal entry. The
  // bound only falls as columns are done: false as soon as it is at most
  // `min_rcond` (`rcond` then the bound so far).
  bool InvertOnEnvelope(double* rcond = nullptr, double min_rcond = 0.0);
  // Entry (i, j) of the symmetric matrix from either triangle's position:
  // (i, j) or (j, i) must lie on the envelope.
  double Symmetric(int i, int j) const {
    return i >= j ? (*this)(i, j) : (*this)(j, i);
  }

 private:
  // Factorize's rows taken together: consecutive ones that start alike,
  // up to kMaxRowsAtOnce; long ones are those of landmarks.
  struct Group {
    int begin, end;
    bool is_long;
  };
  // Factorize's entries left of a group of rows that start alike, at the
  // columns [from, to); kEliminateRowsAlike[count] for `count` rows.
  template <int kCount>
  void EliminateRowsAlike(int group, int first, int from, int to);
  using Eliminate = void (EnvelopeMatrix::*)(int, int, int, int);
  static const Eliminate kEliminateRowsAlike[7];
  template <int kCount>
  void EliminateLongRows(const int* rows, int from, int to, double* lower);
  // The long group long_groups[lead] of `groups`, with followers.
  void EliminateAhead(const std::vector<Group>& groups,
                      const std::vector<std::size_t>& long_groups,
                      std::size_t lead, std::vector<int>* from,
                      double* lower);
  // Rows below the diagonal per column: how many, from `first`.
  static std::vector<int> ColumnCounts(const std::vector<int>& first);

  std::vector<int> first_;
  std::vector<std::int64_t> start_;  // Row i's entries at start_[i].
  std::vector<double> values_;
  // 1 / L_jj: a multiply, not a divide, on the chain each row's entries
  // form (L_ij needs L_i,j-1).
  std::vector<double> inverse_diagonal_;
};

}  // namespace rff

#endif  // RFF_CERES_ENVELOPE_CHOLESKY_H_
