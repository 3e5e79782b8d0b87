#include "costs/wnoj_prior_cost.h"

#include <cmath>

#include "Eigen/Cholesky"
#include "Eigen/LU"
#include "test/costs/cost_test_util.h"

namespace rff {
namespace {

// Q_i(dt) of one coordinate, straight from the SDE (d^3 p / dt^3 white).
Eigen::Matrix3d ProcessCovariance(double dt, double qc) {
  const double dt2 = dt * dt, dt3 = dt2 * dt;
  Eigen::Matrix3d q;
  q << dt3 * dt2 / 20.0, dt2 * dt2 / 8.0, dt3 / 6.0,  //
      dt2 * dt2 / 8.0, dt3 / 3.0, dt2 / 2.0,          //
      dt3 / 6.0, dt2 / 2.0, dt;
  return qc * q;
}

// The autodiff twin: the square-root information from a numerical Cholesky
// factor of Q_i (independent of the closed form under test).
struct WnojPriorAutoDiff {
  double dt;
  Eigen::Vector3d qc;
  template <typename T>
  bool operator()(T const* const* p, T* r) const {
    for (int c = 0; c < 3; ++c) {
      const Eigen::Matrix3d lower =
          ProcessCovariance(dt, qc[c]).llt().matrixL();
      const Eigen::Matrix3d sqrt_info = lower.inverse();
      const T e[3] = {
          p[1][c] - p[0][c] - dt * p[0][c + 3] - 0.5 * dt * dt * p[0][c + 6],
          p[1][c + 3] - p[0][c + 3] - dt * p[0][c + 6],
          p[1][c + 6] - p[0][c + 6]};
      for (int row = 0; row < 3; ++row) {
        r[c + 3 * row] = sqrt_info(row, 0) * e[0] + sqrt_info(row, 1) * e[1] +
                         sqrt_info(row, 2) * e[2];
      }
    }
    return true;
  }
};

TEST(WnojPriorCostTest, AnalyticJacobianMatchesAutoDiff) {
  std::mt19937 rng(11);
  // A numerical Cholesky of Q(dt) loses digits as dt leaves 1 (its entries
  // span dt^5 to dt), so the twin is checked where it is accurate.
  for (const double dt : {0.05, 0.3, 1.0, 4.0}) {
    for (int trial = 0; trial < 5; ++trial) {
      const Eigen::Vector3d qc(0.5, 0.5, 0.05);
      const WnojPriorCost cost(dt, qc.x(), qc.y(), qc.z());
      auto autodiff =
          testing::MakeAutoDiff(new WnojPriorAutoDiff{dt, qc}, cost);
      auto parameters =
          testing::RandomParameters(cost.parameter_block_sizes(), &rng);
      SCOPED_TRACE(dt);
      testing::ExpectSameCost(cost, *autodiff, parameters, 1e-7);
    }
  }
}

TEST(WnojPriorCostTest, SqrtInformationWhitensProcessCovariance) {
  for (const double dt : {1e-3, 0.02, 1.0, 50.0, 100.0}) {
    const Eigen::Vector3d qc(0.3, 0.3, 0.02);
    const WnojPriorCost cost(dt, qc.x(), qc.y(), qc.z());
    for (int c = 0; c < 3; ++c) {
      Eigen::Matrix3d s;
      for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) {
          s(a, b) = cost.sqrt_information()(c + 3 * a, c + 3 * b);
        }
      }
      // S Q S^T = I: the residuals of a draw of the process are white.
      const Eigen::Matrix3d whitened =
          s * ProcessCovariance(dt, qc[c]) * s.transpose();
      EXPECT_TRUE(whitened.isApprox(Eigen::Matrix3d::Identity(), 1e-12))
          << "dt " << dt << " coordinate " << c << "\n"
          << whitened;
      // Coordinates are independent.
      for (int other = 0; other < 3; ++other) {
        if (other == c) continue;
        for (int a = 0; a < 3; ++a) {
          for (int b = 0; b < 3; ++b) {
            EXPECT_EQ(cost.sqrt_information()(c + 3 * a, other + 3 * b), 0.0);
          }
        }
      }
    }
  }
}

TEST(WnojPriorCostTest, HandComputedResidual) {
  // dt = 1, qc = 1, from rest to p' = 1: e_x = (1, 0, 0), so r_x is the
  // first column of M: (2 sqrt(5), -10 sqrt(3), 20), |r|^2 = 720 = Q^-1_00.
  const WnojPriorCost cost(1.0, 1.0, 1.0, 1.0);
  const double previous[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  const double next[9] = {1, 0, 0, 0, 0, 0, 0, 0, 0};
  const double* parameters[2] = {previous, next};
  double r[9];
  ASSERT_TRUE(cost.Evaluate(parameters, r, nullptr));
  EXPECT_NEAR(r[0], 2.0 * std::sqrt(5.0), 1e-14);
  EXPECT_NEAR(r[3], -10.0 * std::sqrt(3.0), 1e-13);
  EXPECT_NEAR(r[6], 20.0, 1e-13);
  for (const int k : {1, 2, 4, 5, 7, 8}) EXPECT_EQ(r[k], 0.0);
}

TEST(WnojPriorCostTest, ConstantAccelerationMotionHasZeroResidual) {
  const double dt = 0.37;
  const WnojPriorCost cost(dt, 1.0, 1.0, 0.1);
  const double previous[9] = {1.0, -2.0, 0.3, 0.5, 1.5, -0.2, 0.4, -1.0, 0.03};
  double next[9];
  for (int c = 0; c < 3; ++c) {
    const double a = previous[c + 6];
    next[c] = previous[c] + dt * previous[c + 3] + 0.5 * dt * dt * a;
    next[c + 3] = previous[c + 3] + dt * a;
    next[c + 6] = a;
  }
  const double* parameters[2] = {previous, next};
  double r[9];
  ASSERT_TRUE(cost.Evaluate(parameters, r, nullptr));
  for (int k = 0; k < 9; ++k) EXPECT_NEAR(r[k], 0.0, 1e-12);
}

TEST(WnojPriorCostTest, SetQcGivesTheFreshCost) {
  WnojPriorCost cost(0.7, 1.0, 1.0, 0.1);
  cost.SetQc(0.02, 0.02, 3e-4);
  const WnojPriorCost fresh(0.7, 0.02, 0.02, 3e-4);
  std::mt19937 rng(5);
  testing::ExpectSameCost(
      cost, fresh,
      testing::RandomParameters(cost.parameter_block_sizes(), &rng), 0.0);
}

}  // namespace
}  // namespace rff
