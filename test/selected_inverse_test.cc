#include "rff_ceres/selected_inverse.h"

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "Eigen/Dense"
#include "gtest/gtest.h"

namespace rff {
namespace {

// J^T J + I for the J of `rows` x `n` with `entries`.
Eigen::SparseMatrix<double> GramPlusIdentity(
    const std::vector<Eigen::Triplet<double>>& entries, int rows, int n) {
  Eigen::SparseMatrix<double> jacobian(rows, n);
  jacobian.setFromTriplets(entries.begin(), entries.end());
  Eigen::SparseMatrix<double> identity(n, n);
  identity.setIdentity();
  return Eigen::SparseMatrix<double>(jacobian.transpose() * jacobian) +
         identity;
}

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
  return GramPlusIdentity(entries, row, n);
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

// H = J^T J + I for `blocks` parameter blocks of `width` columns, each row
// touching two neighbouring blocks (an overlapping-window run) and one of
// `dense` landmark columns: whole blocks share a pattern (supernodes).
Eigen::SparseMatrix<double> BlockBanded(int blocks, int width, int dense,
                                        unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  const int n = blocks * width + dense;
  std::vector<Eigen::Triplet<double>> entries;
  int row = 0;
  for (int b = 0; b + 1 < blocks; ++b) {
    for (int k = 0; k < 2 * width; ++k, ++row) {
      for (int c = b * width; c < (b + 2) * width; ++c) {
        entries.emplace_back(row, c, normal(rng));
      }
      entries.emplace_back(row, blocks * width + row % dense, normal(rng));
    }
  }
  return GramPlusIdentity(entries, row, n);
}

// Largest |Z_ij - (H^-1)_ij| over the pattern of H, relative to max |H^-1|.
double WorstRelativeError(const Eigen::SparseMatrix<double>& h,
                          const SelectedInverse& inverse) {
  const Eigen::MatrixXd dense = Eigen::MatrixXd(h).ldlt().solve(
      Eigen::MatrixXd::Identity(h.rows(), h.cols()));
  double worst = 0.0;
  for (int k = 0; k < h.outerSize(); ++k) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(h, k); it; ++it) {
      double value = std::numeric_limits<double>::quiet_NaN();
      if (!inverse.Entry(it.row(), it.col(), &value)) return 1.0;
      worst = std::max(worst, std::abs(value - dense(it.row(), it.col())));
    }
  }
  return worst / dense.cwiseAbs().maxCoeff();
}

TEST(SelectedInverseTest, SupernodesOfWholeBlocksMatchTheDenseInverse) {
  for (const int width : {1, 6, 40}) {
    const Eigen::SparseMatrix<double> h = BlockBanded(7, width, 4, width);
    SelectedInverse inverse;
    ASSERT_TRUE(inverse.Compute(h, 1 << 22)) << "width " << width;
    EXPECT_LT(WorstRelativeError(h, inverse), 1e-12) << "width " << width;
    // Each block of a wider run is (within) one supernode.
    EXPECT_GE(inverse.supernode_columns(), 7 * (width - 1));
  }
}

// Dense blocks capped at 3 rows and columns: supernodes are cut into
// pieces, and those with more rows below go column by column; the same
// inverse either way.
TEST(SelectedInverseTest, CappedDenseBlocksGiveTheSameInverse) {
  const Eigen::SparseMatrix<double> h = BlockBanded(6, 8, 4, 9);
  SelectedInverse capped;
  ASSERT_TRUE(capped.Compute(h, 1 << 22, 3));
  EXPECT_LT(WorstRelativeError(h, capped), 1e-12);
  SelectedInverse whole;
  ASSERT_TRUE(whole.Compute(h, 1 << 22));
  EXPECT_GT(whole.supernode_columns(), capped.supernode_columns());
  EXPECT_GT(capped.supernode_columns(), 0);
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
