#include "rff_ceres/envelope_cholesky.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "glog/logging.h"

namespace rff {

EnvelopeMatrix::EnvelopeMatrix(std::vector<int> first)
    : first_(std::move(first)) {
  start_.resize(first_.size() + 1, 0);
  for (std::size_t i = 0; i < first_.size(); ++i) {
    CHECK(first_[i] >= 0 && first_[i] <= static_cast<int>(i));
    start_[i + 1] = start_[i] + (static_cast<std::int64_t>(i) - first_[i] + 1);
  }
  values_.assign(start_.back(), 0.0);
  inverse_diagonal_.assign(first_.size(), 0.0);
}

void EnvelopeMatrix::SetZero() {
  std::fill(values_.begin(), values_.end(), 0.0);
}

// L_ij for the `count` rows from `group` on, all stored from column `first`,
// at the columns j in [from, to): one pass over row j for all of them,
// their sums independent chains.
template <int kCount>
void EnvelopeMatrix::EliminateRowsAlike(int group, int first, int from,
                                        int to) {
  double* l[kCount];
  for (int r = 0; r < kCount; ++r) l[r] = row(group + r);
  for (int j = from; j < to; ++j) {
    const double* lj = row(j);
    const int fj = first_[j];
    const int k0 = std::max(first, fj);
    const double* b = lj + (k0 - fj);
    const int o = k0 - first;
    double sum[kCount] = {};
    for (int k = 0; k < j - k0; ++k) {
      for (int r = 0; r < kCount; ++r) sum[r] += l[r][o + k] * b[k];
    }
    const double inverse = inverse_diagonal_[j];
    for (int r = 0; r < kCount; ++r) {
      l[r][j - first] = (l[r][j - first] - sum[r]) * inverse;
    }
  }
}

// The same for `kCount` rows anywhere below, at columns j in [from, to)
// whose rows start at or after every one of theirs: each sum runs over
// row j's stored columns, as EliminateRowsAlike's would.
template <int kCount>
void EnvelopeMatrix::EliminateLongRows(const int* rows, int from, int to) {
  double* l[kCount];
  int f[kCount];
  for (int r = 0; r < kCount; ++r) {
    l[r] = row(rows[r]);
    f[r] = first_[rows[r]];
  }
  for (int j = from; j < to; ++j) {
    const double* lj = row(j);
    const int fj = first_[j];
    const double* a[kCount];
    for (int r = 0; r < kCount; ++r) a[r] = l[r] + (fj - f[r]);
    double sum[kCount] = {};
    for (int k = 0; k < j - fj; ++k) {
      for (int r = 0; r < kCount; ++r) sum[r] += a[r][k] * lj[k];
    }
    const double inverse = inverse_diagonal_[j];
    for (int r = 0; r < kCount; ++r) {
      l[r][j - f[r]] = (l[r][j - f[r]] - sum[r]) * inverse;
    }
  }
}

// A long group's columns left of it, with the long rows of the groups
// after it (up to kMaxLongRows rows, whole groups): every row left of
// `group` is final, so theirs there can be formed now, in one pass over
// each row j for all of them. Landmarks seen over the whole run end the
// envelope as a few long rows apart; one at a time, each sum is a chain
// that waits on its last add.
void EnvelopeMatrix::EliminateAhead(const std::vector<Group>& groups,
                                    std::size_t at, std::vector<int>* from) {
  constexpr int kMaxLongRows = 8;
  const int group = groups[at].begin;
  std::vector<int> rows;
  for (std::size_t g = at; g < groups.size(); ++g) {
    const Group& next = groups[g];
    const int count = next.end - next.begin;
    if (!next.is_long || (*from)[next.begin] >= group) continue;
    if (static_cast<int>(rows.size()) + count > kMaxLongRows) break;
    for (int i = next.begin; i < next.end; ++i) rows.push_back(i);
  }
  // Where every row j up to `group` starts at or after all of theirs.
  int latest_first = 0, latest_from = 0;
  for (const int i : rows) {
    latest_first = std::max(latest_first, first_[i]);
    latest_from = std::max(latest_from, (*from)[i]);
  }
  int uniform = group;
  while (uniform > latest_from && first_[uniform - 1] >= latest_first) {
    --uniform;
  }
  for (const int i : rows) {
    EliminateRowsAlike<1>(i, first_[i], (*from)[i], uniform);
    (*from)[i] = group;
  }
  switch (rows.size()) {
    case 8:
      return EliminateLongRows<8>(rows.data(), uniform, group);
    case 7:
      return EliminateLongRows<7>(rows.data(), uniform, group);
    case 6:
      return EliminateLongRows<6>(rows.data(), uniform, group);
    case 5:
      return EliminateLongRows<5>(rows.data(), uniform, group);
    case 4:
      return EliminateLongRows<4>(rows.data(), uniform, group);
    case 3:
      return EliminateLongRows<3>(rows.data(), uniform, group);
    case 2:
      return EliminateLongRows<2>(rows.data(), uniform, group);
    default:
      return EliminateLongRows<1>(rows.data(), uniform, group);
  }
}

// Row by row (the "bordering" form): L_ij = (A_ij - sum_k L_ik L_jk) / L_jj
// over the columns k both rows store, then L_ii = sqrt(A_ii - sum_k L_ik^2).
// Each L_ij needs L_i,j-1, so a row is one chain of dependent operations:
// rows that start at the same column (a state's) are taken together, their
// entries left of the group in one pass, then the group's own triangle.
bool EnvelopeMatrix::Factorize(Eigen::VectorXd* lower) {
  CHECK(lower == nullptr || lower->size() == size());
  constexpr int kMaxRowsAtOnce = 6;
  // Rows this far right of their first column are long (landmarks).
  constexpr int kLongRow = 256;
  using Eliminate = void (EnvelopeMatrix::*)(int, int, int, int);
  static constexpr Eliminate kEliminate[kMaxRowsAtOnce + 1] = {
      nullptr,
      &EnvelopeMatrix::EliminateRowsAlike<1>,
      &EnvelopeMatrix::EliminateRowsAlike<2>,
      &EnvelopeMatrix::EliminateRowsAlike<3>,
      &EnvelopeMatrix::EliminateRowsAlike<4>,
      &EnvelopeMatrix::EliminateRowsAlike<5>,
      &EnvelopeMatrix::EliminateRowsAlike<6>};
  std::vector<Group> groups;
  for (int group = 0, end = 0; group < size(); group = end) {
    end = group + 1;
    while (end < size() && end - group < kMaxRowsAtOnce &&
           first_[end] == first_[group]) {
      ++end;
    }
    groups.push_back({group, end, group - first_[group] >= kLongRow});
  }
  // Row i's columns left of from[i] are final.
  std::vector<int> from = first_;
  for (std::size_t at = 0; at < groups.size(); ++at) {
    const int group = groups[at].begin, end = groups[at].end;
    const int first = first_[group];
    if (groups[at].is_long && group - from[group] >= kLongRow) {
      EliminateAhead(groups, at, &from);
    }
    (this->*kEliminate[end - group])(group, first, from[group], group);
    for (int i = group; i < end; ++i) {
      double* li = row(i);
      // The group's own triangle: row j of it stores from `first` too.
      for (int j = group; j < i; ++j) {
        const double* lj = row(j);
        double sum = 0.0;
        for (int k = 0; k < j - first; ++k) sum += li[k] * lj[k];
        li[j - first] = (li[j - first] - sum) * inverse_diagonal_[j];
      }
      double diagonal = li[i - first];
      for (int k = 0; k < i - first; ++k) diagonal -= li[k] * li[k];
      if (!(diagonal > 0.0) || !std::isfinite(diagonal)) return false;
      li[i - first] = std::sqrt(diagonal);
      inverse_diagonal_[i] = 1.0 / li[i - first];
      if (lower != nullptr) {
        double& y = (*lower)[i];
        double sum = y;
        for (int k = first; k < i; ++k) sum -= li[k - first] * (*lower)[k];
        y = sum / li[i - first];
      }
    }
  }
  return true;
}

double EnvelopeMatrix::FactorizationWork(const std::vector<int>& first) {
  double work = 0.0;
  for (int i = 0; i < static_cast<int>(first.size()); ++i) {
    // Factorize's inner products of row i.
    for (int j = first[i]; j <= i; ++j)
      work += j - std::max(first[i], first[j]);
  }
  return work;
}

std::vector<int> EnvelopeMatrix::ColumnCounts(const std::vector<int>& first) {
  const int n = static_cast<int>(first.size());
  // Row i lies below the diagonal in columns first(i)..i-1: +1 at its
  // first, -1 at i, summed.
  std::vector<int> counts(n + 1, 0);
  for (int i = 0; i < n; ++i) {
    ++counts[first[i]];
    --counts[i];
  }
  for (int j = 1; j <= n; ++j) counts[j] += counts[j - 1];
  counts.pop_back();
  return counts;
}

bool EnvelopeMatrix::InvertOnEnvelope(double* rcond, double min_rcond) {
  const int n = size();
  // A_jj = sum_k L_jk^2, from row j of the factor.
  double largest_diagonal = 0.0;
  for (int j = 0; j < n; ++j) {
    const Eigen::Map<const Eigen::VectorXd> lj(row(j), j - first_[j] + 1);
    largest_diagonal = std::max(largest_diagonal, lj.squaredNorm());
  }
  // Column j's rows below the diagonal, ascending: rows_of[at[j]..at[j+1]).
  const std::vector<int> counts = ColumnCounts(first_);
  std::vector<std::int64_t> at(n + 1, 0);
  for (int j = 0; j < n; ++j) at[j + 1] = at[j] + counts[j];
  std::vector<int> rows_of(at[n]);
  std::vector<std::int64_t> next(at.begin(), at.end() - 1);
  for (int i = 0; i < n; ++i) {
    for (int j = first_[i]; j < i; ++j) rows_of[next[j]++] = i;
  }
  std::vector<double> l, z;
  double largest_inverse_diagonal = 0.0;
  double bound = std::numeric_limits<double>::infinity();
  for (int j = n - 1; j >= 0; --j) {
    const int* rows = rows_of.data() + at[j];
    const int m = counts[j];
    l.resize(m);
    z.resize(m);
    for (int a = 0; a < m; ++a) l[a] = (*this)(rows[a], j);
    const double d = inverse_diagonal_[j];
    // Z_ik for k < i from row i, for k >= i from row k: both later columns.
    for (int a = 0; a < m; ++a) {
      const int i = rows[a];
      const double* zi = row(i);
      double sum = 0.0;
      for (int b = 0; b < a; ++b) sum += zi[rows[b] - first_[i]] * l[b];
      for (int b = a; b < m; ++b) {
        sum += row(rows[b])[i - first_[rows[b]]] * l[b];
      }
      z[a] = -d * sum;
    }
    double sum = 0.0;
    for (int a = 0; a < m; ++a) {
      sum += z[a] * l[a];
      (*this)(rows[a], j) = z[a];
    }
    const double zjj = d * d - d * sum;
    if (!std::isfinite(zjj)) return false;
    (*this)(j, j) = zjj;
    largest_inverse_diagonal = std::max(largest_inverse_diagonal, zjj);
    bound = 1.0 / (largest_diagonal * largest_inverse_diagonal);
    if (!(bound > min_rcond)) break;
  }
  if (rcond != nullptr) *rcond = bound;
  return bound > min_rcond;
}

Eigen::VectorXd EnvelopeMatrix::Solve(const Eigen::VectorXd& b) const {
  return SolveUpper(SolveLower(b));
}

void EnvelopeMatrix::SolveInPlace(RowMajorMatrix* b) const {
  CHECK_EQ(b->rows(), size());
  const int m = static_cast<int>(b->cols());
  auto b_row = [&](int i) { return b->data() + std::int64_t{i} * m; };
  for (int i = 0; i < size(); ++i) {  // L Y = B.
    const double* li = row(i);
    const int fi = first_[i];
    double* bi = b_row(i);
    for (int k = fi; k < i; ++k) {
      const double* bk = b_row(k);
      for (int c = 0; c < m; ++c) bi[c] -= li[k - fi] * bk[c];
    }
    for (int c = 0; c < m; ++c) bi[c] /= li[i - fi];
  }
  for (int i = size() - 1; i >= 0; --i) {  // L^T X = Y.
    const double* li = row(i);
    const int fi = first_[i];
    double* bi = b_row(i);
    for (int c = 0; c < m; ++c) bi[c] /= li[i - fi];
    for (int k = fi; k < i; ++k) {
      double* bk = b_row(k);
      for (int c = 0; c < m; ++c) bk[c] -= li[k - fi] * bi[c];
    }
  }
}

// L y = b, rows in order.
Eigen::VectorXd EnvelopeMatrix::SolveLower(const Eigen::VectorXd& b) const {
  Eigen::VectorXd y = b;
  for (int i = 0; i < size(); ++i) {
    const double* li = row(i);
    const int fi = first_[i];
    double sum = y[i];
    for (int k = fi; k < i; ++k) sum -= li[k - fi] * y[k];
    y[i] = sum / li[i - fi];
  }
  return y;
}

// L^T x = y, columns in reverse: row i of L scatters into the earlier x.
Eigen::VectorXd EnvelopeMatrix::SolveUpper(const Eigen::VectorXd& y) const {
  Eigen::VectorXd x = y;
  for (int i = size() - 1; i >= 0; --i) {
    const double* li = row(i);
    const int fi = first_[i];
    x[i] /= li[i - fi];
    for (int k = fi; k < i; ++k) x[k] -= li[k - fi] * x[i];
  }
  return x;
}

}  // namespace rff
