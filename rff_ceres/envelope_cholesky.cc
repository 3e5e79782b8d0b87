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

const EnvelopeMatrix::Eliminate EnvelopeMatrix::kEliminateRowsAlike[7] = {
    nullptr,
    &EnvelopeMatrix::EliminateRowsAlike<1>,
    &EnvelopeMatrix::EliminateRowsAlike<2>,
    &EnvelopeMatrix::EliminateRowsAlike<3>,
    &EnvelopeMatrix::EliminateRowsAlike<4>,
    &EnvelopeMatrix::EliminateRowsAlike<5>,
    &EnvelopeMatrix::EliminateRowsAlike<6>};

// The same for `kCount` rows anywhere below, at the columns j in [from,
// to): each sum over the columns both rows store, in k order (a row's
// own leading terms first, where it starts before the others). With
// `lower`, also its rows' sums y_i - sum_j L_ij y_j over these columns.
template <int kCount>
void EnvelopeMatrix::EliminateLongRows(const int* rows, int from, int to,
                                       double* lower) {
  double* l[kCount];
  int f[kCount];
  double y[kCount];
  int latest_first = 0;
  for (int r = 0; r < kCount; ++r) {
    l[r] = row(rows[r]);
    f[r] = first_[rows[r]];
    y[r] = lower != nullptr ? lower[rows[r]] : 0.0;
    latest_first = std::max(latest_first, f[r]);
  }
  for (int j = from; j < to; ++j) {
    const double* lj = row(j);
    const int fj = first_[j];
    const int common = std::max(fj, latest_first);
    double sum[kCount] = {};
    if (fj < latest_first) {
      for (int r = 0; r < kCount; ++r) {
        for (int k = std::max(f[r], fj); k < common; ++k) {
          sum[r] += l[r][k - f[r]] * lj[k - fj];
        }
      }
    }
    const double* a[kCount];
    for (int r = 0; r < kCount; ++r) a[r] = l[r] + (common - f[r]);
    const double* b = lj + (common - fj);
    for (int k = 0; k < j - common; ++k) {
      for (int r = 0; r < kCount; ++r) sum[r] += a[r][k] * b[k];
    }
    const double inverse = inverse_diagonal_[j];
    for (int r = 0; r < kCount; ++r) {
      l[r][j - f[r]] = (l[r][j - f[r]] - sum[r]) * inverse;
    }
    if (lower != nullptr) {
      for (int r = 0; r < kCount; ++r) y[r] -= l[r][j - f[r]] * lower[j];
    }
  }
  if (lower != nullptr) {
    for (int r = 0; r < kCount; ++r) lower[rows[r]] = y[r];
  }
}

// A long group's columns left of it, with those of long groups after it
// (up to kMaxLongRows rows, whole groups): every row left of `group` is
// final, so theirs there can be formed now, in one pass over each row j
// for all of them. Landmarks seen over long stretches are long rows
// apart; a pair at a time, each sum is a chain that waits on its last add.
void EnvelopeMatrix::EliminateAhead(const std::vector<Group>& groups,
                                    const std::vector<std::size_t>& long_groups,
                                    std::size_t lead, std::vector<int>* from,
                                    double* lower) {
  constexpr int kMaxLongRows = 8;
  constexpr std::size_t kMaxLookAhead = 64;  // Long groups considered.
  using EliminateLong = void (EnvelopeMatrix::*)(const int*, int, int, double*);
  static constexpr EliminateLong kEliminateLong[kMaxLongRows + 1] = {
      nullptr,
      &EnvelopeMatrix::EliminateLongRows<1>,
      &EnvelopeMatrix::EliminateLongRows<2>,
      &EnvelopeMatrix::EliminateLongRows<3>,
      &EnvelopeMatrix::EliminateLongRows<4>,
      &EnvelopeMatrix::EliminateLongRows<5>,
      &EnvelopeMatrix::EliminateLongRows<6>,
      &EnvelopeMatrix::EliminateLongRows<7>,
      &EnvelopeMatrix::EliminateLongRows<8>};
  const std::size_t at = long_groups[lead];
  const int group = groups[at].begin;
  // Followers: the next long groups with entries left of `group` still to
  // form, those that start forming earliest first.
  std::vector<std::pair<int, std::size_t>> candidates;  // (from, group)
  const std::size_t last = std::min(long_groups.size(), lead + kMaxLookAhead);
  for (std::size_t next = lead + 1; next < last; ++next) {
    const std::size_t g = long_groups[next];
    if ((*from)[groups[g].begin] < group) {
      candidates.emplace_back((*from)[groups[g].begin], g);
    }
  }
  std::stable_sort(candidates.begin(), candidates.end());
  std::vector<std::pair<int, std::size_t>> chosen = {{(*from)[group], at}};
  int count = groups[at].end - group;
  for (const auto& [next_from, g] : candidates) {
    const int size = groups[g].end - groups[g].begin;
    if (count + size > kMaxLongRows) continue;
    chosen.emplace_back(next_from, g);
    count += size;
  }
  std::stable_sort(chosen.begin(), chosen.end());
  // Staggered: from where each group starts forming, it joins those that
  // started before it, up to where the next one starts.
  std::vector<int> rows;
  for (std::size_t c = 0; c < chosen.size(); ++c) {
    const auto [start, g] = chosen[c];
    for (int i = groups[g].begin; i < groups[g].end; ++i) rows.push_back(i);
    const int end = c + 1 < chosen.size() ? chosen[c + 1].first : group;
    (this->*kEliminateLong[rows.size()])(rows.data(), start, end, lower);
  }
  for (const int i : rows) (*from)[i] = group;
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
  std::vector<Group> groups;
  for (int group = 0, end = 0; group < size(); group = end) {
    end = group + 1;
    while (end < size() && end - group < kMaxRowsAtOnce &&
           first_[end] == first_[group]) {
      ++end;
    }
    groups.push_back({group, end, group - first_[group] >= kLongRow});
  }
  std::vector<std::size_t> long_groups;  // Their places in `groups`.
  for (std::size_t at = 0; at < groups.size(); ++at) {
    if (groups[at].is_long) long_groups.push_back(at);
  }
  // Row i's columns left of from[i] are final, and with `lower` its sum
  // over them taken from y_i.
  std::vector<int> from = first_;
  for (std::size_t at = 0, lead = 0; at < groups.size(); ++at) {
    const int group = groups[at].begin, end = groups[at].end;
    const int first = first_[group];
    if (groups[at].is_long) {
      if (group - from[group] >= kLongRow) {
        EliminateAhead(groups, long_groups, lead, &from,
                       lower != nullptr ? lower->data() : nullptr);
      }
      ++lead;
    }
    (this->*kEliminateRowsAlike[end - group])(group, first, from[group], group);
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
        // Columns left of from[i] were taken ahead (EliminateAhead).
        for (int k = from[i]; k < i; ++k) sum -= li[k - first] * (*lower)[k];
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

double EnvelopeMatrix::LogDeterminant() const {
  double sum = 0.0;
  for (int i = 0; i < size(); ++i) sum += std::log((*this)(i, i));
  return 2.0 * sum;
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
