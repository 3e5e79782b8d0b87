#include "rff_ceres/selected_inverse.h"

#include <random>
#include <vector>

#include "Eigen/Dense"
#include "gtest/gtest.h"

namespace rff {
namespace {

// H = J^T J + I for a J of chained pairs (a banded run) and `dense` columns
// that every row touches (landmarks seen throughout).
Eigen::SparseMatrix<double> BandedWithDenseColumns(int n, int dense,
                                                   unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  std::vector<Eigen::Triplet<double>> entries;
  int row = 0;
  for (int i = 0; i + 1 < n - dense; ++i, ++row) {
    entries.emplace_back(row, i, normal(rng));
    entries.emplace_back(row, i + 1, normal(rng));
    entries.emplace_back(row, n - dense + row % dense, normal(rng));
  }
  Eigen::SparseMatrix<double> jacobian(row, n);
  jacobian.setFromTriplets(entries.begin(), entries.end());
  Eigen::SparseMatrix<double> identity(n, n);
  identity.setIdentity();
  return Eigen::SparseMatrix<double>(jacobian.transpose() * jacobian) +
         identity;
}

TEST(SelectedInverseTest, MatchesTheDenseInverseOnThePatternOfH) {
  const Eigen::SparseMatrix<double> h = BandedWithDenseColumns(60, 4, 1);
  SelectedInverse inverse;
  ASSERT_TRUE(inverse.Compute(h, 1 << 20));
  const Eigen::MatrixXd dense =
      Eigen::MatrixXd(h).ldlt().solve(Eigen::MatrixXd::Identity(60, 60));
  int checked = 0;
  for (int k = 0; k < h.outerSize(); ++k) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(h, k); it; ++it) {
      double value = 0.0;
      ASSERT_TRUE(inverse.Entry(it.row(), it.col(), &value))
          << it.row() << ", " << it.col();
      EXPECT_NEAR(value, dense(it.row(), it.col()),
                  1e-12 * dense.cwiseAbs().maxCoeff());
      ++checked;
    }
  }
  EXPECT_GT(checked, 60 * 3);
  // Far apart in a banded run: not on the pattern, and said so.
  double value = 0.0;
  EXPECT_FALSE(inverse.Entry(0, 40, &value));
  EXPECT_FALSE(inverse.Entry(-1, 0, &value));
  EXPECT_FALSE(inverse.Entry(0, 60, &value));
}

TEST(SelectedInverseTest, RefusesIndefiniteAndTooLargeFactors) {
  Eigen::SparseMatrix<double> h = BandedWithDenseColumns(20, 2, 2);
  SelectedInverse inverse;
  EXPECT_FALSE(inverse.Compute(h, 10));  // The factor has more entries.
  h.coeffRef(5, 5) = -1.0;
  EXPECT_FALSE(inverse.Compute(h, 1 << 20));
  double value = 0.0;
  EXPECT_FALSE(inverse.Entry(0, 0, &value));
}

}  // namespace
}  // namespace rff
