#include "rff_ceres/envelope_cholesky.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "Eigen/Cholesky"
#include "Eigen/LU"
#include "gtest/gtest.h"

namespace rff {
namespace {

// A banded SPD matrix with `border` full rows and columns last, the shape
// of a time-ordered SLAM system with landmarks.
Eigen::MatrixXd BandedWithBorder(int band_size, int bandwidth, int border,
                                 std::vector<int>* first) {
  const int n = band_size + border;
  std::mt19937 random(7);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd j = Eigen::MatrixXd::Zero(3 * n, n);
  for (int r = 0; r < 3 * n; ++r) {
    const int c = r % band_size;
    for (int k = c; k < std::min(band_size, c + bandwidth + 1); ++k) {
      j(r, k) = normal(random);
    }
    if (border > 0) j(r, band_size + r % border) = normal(random);
  }
  const Eigen::MatrixXd a = j.transpose() * j;
  first->assign(n, 0);
  for (int i = 0; i < n; ++i) {
    int f = 0;
    while (a(i, f) == 0.0) ++f;  // The diagonal is positive.
    (*first)[i] = f;
  }
  return a;
}

EnvelopeMatrix FromDense(const Eigen::MatrixXd& a,
                         const std::vector<int>& first) {
  EnvelopeMatrix e(first);
  for (int i = 0; i < e.size(); ++i) {
    for (int j = first[i]; j <= i; ++j) e(i, j) = a(i, j);
  }
  return e;
}

TEST(EnvelopeCholeskyTest, SolvesAsDenseCholeskyWithABorder) {
  std::vector<int> first;
  const Eigen::MatrixXd a = BandedWithBorder(60, 4, 3, &first);
  EnvelopeMatrix e = FromDense(a, first);
  EXPECT_LT(e.num_entries(), a.size() / 2);  // The envelope, not the square.
  const Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(a.rows(), -1.0, 2.0);
  const Eigen::VectorXd b = a * x;
  ASSERT_TRUE(e.Factorize());
  const Eigen::VectorXd expected = a.llt().solve(b);
  EXPECT_LT((e.Solve(b) - expected).norm(), 1e-10 * expected.norm());
  EXPECT_LT((e.Solve(b) - x).norm(), 1e-9 * x.norm());
}

TEST(EnvelopeCholeskyTest, FactorMatchesEigensLowerFactor) {
  std::vector<int> first;
  const Eigen::MatrixXd a = BandedWithBorder(30, 2, 0, &first);
  EnvelopeMatrix e = FromDense(a, first);
  ASSERT_TRUE(e.Factorize());
  const Eigen::MatrixXd l = a.llt().matrixL();
  for (int i = 0; i < e.size(); ++i) {
    for (int j = 0; j <= i; ++j) {
      // No fill outside the envelope.
      const double entry = j >= first[i] ? e(i, j) : 0.0;
      EXPECT_NEAR(entry, l(i, j), 1e-12 * l.norm()) << i << ", " << j;
    }
  }
}

// Blocks of 1 to 9 variables, each coupled to the next, as states are: the
// rows of a block start alike (at the block before), in runs longer and
// shorter than those Factorize takes together.
TEST(EnvelopeCholeskyTest, FactorMatchesEigensWithBlocksOfEverySize) {
  std::vector<int> begin = {0};
  for (int size = 1; size <= 9; ++size) begin.push_back(begin.back() + size);
  for (int size = 9; size >= 1; size -= 2) begin.push_back(begin.back() + size);
  const int n = begin.back();
  std::mt19937 random(3);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd j = Eigen::MatrixXd::Zero(4 * n, n);
  int r = 0;
  for (std::size_t b = 0; b + 2 < begin.size(); ++b) {
    for (int row = 0; row < begin[b + 2] - begin[b] + 2; ++row, ++r) {
      for (int c = begin[b]; c < begin[b + 2]; ++c) j(r, c) = normal(random);
    }
  }
  const Eigen::MatrixXd a = j.topRows(r).transpose() * j.topRows(r);
  std::vector<int> first(n);
  for (std::size_t b = 0; b + 1 < begin.size(); ++b) {
    for (int i = begin[b]; i < begin[b + 1]; ++i) {
      first[i] = begin[b == 0 ? 0 : b - 1];
    }
  }
  EnvelopeMatrix e = FromDense(a, first);
  ASSERT_TRUE(e.Factorize());
  const Eigen::MatrixXd l = a.llt().matrixL();
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k <= i; ++k) {
      const double entry = k >= first[i] ? e(i, k) : 0.0;
      EXPECT_NEAR(entry, l(i, k), 1e-12 * l.norm()) << i << ", " << k;
    }
  }
}

// A time-ordered system as BANDED_CHOLESKY builds it: states of 3
// variables, each coupled to the next, and landmarks of 2 seen from
// overlapping stretches of states, each placed after the last state that
// sees it: long landmark rows that cross other landmarks' columns.
Eigen::MatrixXd LandmarksSeenFrom(
    int num_states, const std::vector<std::pair<int, int>>& sightings,
    std::vector<int>* first) {
  // Landmark k's columns come after state sightings[k].second's.
  std::vector<int> state_column(num_states), landmark_column(sightings.size());
  int next = 0;
  for (int s = 0; s < num_states; ++s) {
    state_column[s] = next;
    next += 3;
    for (std::size_t k = 0; k < sightings.size(); ++k) {
      if (sightings[k].second == s) {
        landmark_column[k] = next;
        next += 2;
      }
    }
  }
  const int n = next;
  std::mt19937 random(11);
  std::normal_distribution<double> normal;
  std::vector<Eigen::VectorXd> rows;
  auto add_row = [&](const std::vector<int>& columns) {
    Eigen::VectorXd row = Eigen::VectorXd::Zero(n);
    for (const int c : columns) row[c] = normal(random);
    rows.push_back(row);
  };
  for (int s = 0; s + 1 < num_states; ++s) {
    for (int r = 0; r < 4; ++r) {
      std::vector<int> columns;
      for (int c = 0; c < 3; ++c) {
        columns.push_back(state_column[s] + c);
        columns.push_back(state_column[s + 1] + c);
      }
      add_row(columns);
    }
  }
  for (std::size_t k = 0; k < sightings.size(); ++k) {
    for (int s = sightings[k].first; s <= sightings[k].second; s += 3) {
      for (int r = 0; r < 2; ++r) {
        add_row({state_column[s], state_column[s] + 1, state_column[s] + 2,
                 landmark_column[k], landmark_column[k] + 1});
      }
    }
  }
  Eigen::MatrixXd j(rows.size(), n);
  for (std::size_t r = 0; r < rows.size(); ++r) j.row(r) = rows[r];
  const Eigen::MatrixXd a = j.transpose() * j;
  first->assign(n, 0);
  int long_rows = 0;
  for (int i = 0; i < n; ++i) {
    int f = 0;
    while (a(i, f) == 0.0) ++f;
    (*first)[i] = f;
    if (i - f >= 64) ++long_rows;
  }
  EXPECT_GE(long_rows, 12);
  return a;
}

Eigen::MatrixXd LandmarksSeenOverStretches(std::vector<int>* first) {
  return LandmarksSeenFrom(200,
                           {{0, 150},
                            {5, 40},
                            {10, 120},
                            {30, 60},
                            {45, 199},
                            {50, 130},
                            {90, 100},
                            {100, 180},
                            {110, 199},
                            {160, 190}},
                           first);
}

// Its factor is Eigen's, entry for entry.
TEST(EnvelopeCholeskyTest, FactorMatchesEigensWithLandmarksSeenOverStretches) {
  std::vector<int> first;
  const Eigen::MatrixXd a = LandmarksSeenOverStretches(&first);
  const int n = static_cast<int>(a.rows());
  EnvelopeMatrix e = FromDense(a, first);
  ASSERT_TRUE(e.Factorize());
  const Eigen::MatrixXd l = a.llt().matrixL();
  const double tolerance = 1e-11 * l.norm();
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k <= i; ++k) {
      const double entry = k >= first[i] ? e(i, k) : 0.0;
      ASSERT_NEAR(entry, l(i, k), tolerance) << i << ", " << k;
    }
  }
}

// The bordering formula row by row, column by column: L_ij = (A_ij -
// sum_k L_ik L_jk) * (1 / L_jj) over k from max(first(i), first(j)) up,
// L_ii = sqrt(A_ii - L_i0^2 - L_i1^2 - ...), each sum in k order.
Eigen::MatrixXd RowByRowFactor(const Eigen::MatrixXd& a,
                               const std::vector<int>& first) {
  const int n = static_cast<int>(a.rows());
  Eigen::MatrixXd l = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd inverse(n);
  for (int i = 0; i < n; ++i) {
    for (int j = first[i]; j < i; ++j) {
      double sum = 0.0;
      for (int k = std::max(first[i], first[j]); k < j; ++k) {
        sum += l(i, k) * l(j, k);
      }
      l(i, j) = (a(i, j) - sum) * inverse[j];
    }
    double diagonal = a(i, i);
    for (int k = first[i]; k < i; ++k) diagonal -= l(i, k) * l(i, k);
    l(i, i) = std::sqrt(diagonal);
    inverse[i] = 1.0 / l(i, i);
  }
  return l;
}

// However Factorize groups rows (states alike, landmarks' long rows ahead
// of their turn, several at once), each entry is the formula's, bit for bit.
// Landmarks seen over the whole run (Plaza's beacons) end the envelope
// as long rows with states between them, more than one pass takes; others
// cross them.
TEST(EnvelopeCholeskyTest, FactorIsTheRowByRowFormulaBitForBit) {
  std::vector<int> first;
  const Eigen::MatrixXd a = LandmarksSeenFrom(
      300,
      {{0, 296}, {2, 297}, {40, 250}, {5, 298}, {9, 299}, {1, 299}, {3, 290}},
      &first);
  const int n = static_cast<int>(a.rows());
  int long_rows = 0;  // Wider than Factorize's kLongRow.
  for (int i = 0; i < n; ++i) long_rows += i - first[i] >= 256;
  EXPECT_EQ(long_rows, 14);
  EnvelopeMatrix e = FromDense(a, first);
  ASSERT_TRUE(e.Factorize());
  const Eigen::MatrixXd l = RowByRowFactor(a, first);
  for (int i = 0; i < n; ++i) {
    for (int k = first[i]; k <= i; ++k) {
      ASSERT_EQ(e(i, k), l(i, k)) << i << ", " << k;
    }
  }
  // L^-1 b formed along, as SolveLower forms it after.
  Eigen::VectorXd lower = Eigen::VectorXd::LinSpaced(n, -3.0, 5.0);
  const Eigen::VectorXd expected = e.SolveLower(lower);
  EnvelopeMatrix along = FromDense(a, first);
  ASSERT_TRUE(along.Factorize(&lower));
  for (int i = 0; i < n; ++i) ASSERT_EQ(lower[i], expected[i]) << i;
}

// The inverse on the envelope is the dense inverse there, for banded
// states with a border and for landmarks seen over stretches.
TEST(EnvelopeCholeskyTest, InverseOnTheEnvelopeIsTheDenseInverse) {
  for (const bool stretches : {false, true}) {
    std::vector<int> first;
    const Eigen::MatrixXd a = stretches ? LandmarksSeenOverStretches(&first)
                                        : BandedWithBorder(60, 4, 3, &first);
    EnvelopeMatrix e = FromDense(a, first);
    ASSERT_TRUE(e.Factorize());
    ASSERT_TRUE(e.InvertOnEnvelope());
    const Eigen::MatrixXd inverse = a.inverse();
    const double tolerance = 1e-10 * inverse.norm();
    for (int i = 0; i < e.size(); ++i) {
      for (int k = first[i]; k <= i; ++k) {
        ASSERT_NEAR(e(i, k), inverse(i, k), tolerance) << i << ", " << k;
        ASSERT_EQ(e.Symmetric(k, i), e(i, k));
      }
    }
  }
}

// The reciprocal condition bound 1 / (max A_jj max (A^-1)_jj): 1 for the
// identity; for [1 1; 1 1 + e] (eigenvalues about 2 and e / 2) A^-1 has
// (1 + e) / e and 1 / e on its diagonal: the bound is e / (1 + e)^2.
TEST(EnvelopeCholeskyTest, InversionBoundsTheReciprocalCondition) {
  EnvelopeMatrix identity({0, 1});
  identity(0, 0) = identity(1, 1) = 1.0;
  double rcond = 0.0;
  ASSERT_TRUE(identity.Factorize());
  ASSERT_TRUE(identity.InvertOnEnvelope(&rcond));
  EXPECT_EQ(rcond, 1.0);
  const double e = 1e-12;
  EnvelopeMatrix nearly_singular({0, 0});
  nearly_singular(0, 0) = nearly_singular(1, 0) = 1.0;
  nearly_singular(1, 1) = 1.0 + e;
  ASSERT_TRUE(nearly_singular.Factorize());
  ASSERT_TRUE(nearly_singular.InvertOnEnvelope(&rcond));
  EXPECT_NEAR(rcond, e / ((1.0 + e) * (1.0 + e)), 1e-3 * e);
}

// The forward solve done as the factor's rows are formed gives
// SolveLower's bits.
TEST(EnvelopeCholeskyTest, FactorizeSolvesLowerAsSolveLower) {
  std::vector<int> first;
  const Eigen::MatrixXd a = BandedWithBorder(50, 3, 2, &first);
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(a.rows(), -3.0, 5.0);
  EnvelopeMatrix alone = FromDense(a, first);
  ASSERT_TRUE(alone.Factorize());
  const Eigen::VectorXd expected = alone.SolveLower(b);
  EnvelopeMatrix fused = FromDense(a, first);
  Eigen::VectorXd y = b;
  ASSERT_TRUE(fused.Factorize(&y));
  for (int i = 0; i < a.rows(); ++i) EXPECT_EQ(y[i], expected[i]) << i;
  EXPECT_GT((y - b).norm(), 1.0);
}

// Many right-hand sides at once give, column by column, Solve's bits.
TEST(EnvelopeCholeskyTest, SolveInPlaceGivesSolvesBitsPerColumn) {
  std::vector<int> first;
  const Eigen::MatrixXd a = BandedWithBorder(50, 3, 2, &first);
  EnvelopeMatrix e = FromDense(a, first);
  ASSERT_TRUE(e.Factorize());
  std::mt19937 random(9);
  std::normal_distribution<double> normal;
  EnvelopeMatrix::RowMajorMatrix b(a.rows(), 5);
  for (Eigen::Index i = 0; i < b.size(); ++i) b.data()[i] = normal(random);
  EnvelopeMatrix::RowMajorMatrix x = b;
  e.SolveInPlace(&x);
  for (Eigen::Index k = 0; k < b.cols(); ++k) {
    const Eigen::VectorXd one = e.Solve(b.col(k));
    for (Eigen::Index i = 0; i < b.rows(); ++i) {
      ASSERT_EQ(x(i, k), one[i]) << i << ", " << k;
    }
  }
}

TEST(EnvelopeCholeskyTest, RefusesAnIndefiniteOrNonFiniteMatrix) {
  EnvelopeMatrix indefinite({0, 0});
  indefinite(0, 0) = 1.0;
  indefinite(1, 0) = 2.0;
  indefinite(1, 1) = 1.0;  // Eigenvalues 3 and -1.
  EXPECT_FALSE(indefinite.Factorize());
  EnvelopeMatrix not_finite({0});
  not_finite(0, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(not_finite.Factorize());
}

}  // namespace
}  // namespace rff
