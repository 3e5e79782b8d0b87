#include "rff_ceres/envelope_cholesky.h"

#include <algorithm>
#include <cmath>

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
}

void EnvelopeMatrix::SetZero() {
  std::fill(values_.begin(), values_.end(), 0.0);
}

// Row by row (the "bordering" form): L_ij = (A_ij - sum_k L_ik L_jk) / L_jj
// over the columns k both rows store, then L_ii = sqrt(A_ii - sum_k L_ik^2).
bool EnvelopeMatrix::Factorize() {
  for (int i = 0; i < size(); ++i) {
    double* li = row(i);
    const int fi = first_[i];
    for (int j = fi; j < i; ++j) {
      const double* lj = row(j);
      const int fj = first_[j];
      const int k0 = std::max(fi, fj);
      double sum = 0.0;
      const double* a = li + (k0 - fi);
      const double* b = lj + (k0 - fj);
      for (int k = 0; k < j - k0; ++k) sum += a[k] * b[k];
      li[j - fi] = (li[j - fi] - sum) / lj[j - fj];
    }
    double diagonal = li[i - fi];
    for (int k = 0; k < i - fi; ++k) diagonal -= li[k] * li[k];
    if (!(diagonal > 0.0) || !std::isfinite(diagonal)) return false;
    li[i - fi] = std::sqrt(diagonal);
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

Eigen::VectorXd EnvelopeMatrix::Solve(const Eigen::VectorXd& b) const {
  return SolveUpper(SolveLower(b));
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
