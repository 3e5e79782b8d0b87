#include "costs/wnoa_prior_cost.h"

#include <cmath>

#include "Eigen/Cholesky"
#include "Eigen/LU"
#include "costs/wnoa_initial_state_cost.h"
#include "test/costs/cost_test_util.h"

namespace rff {
namespace {

// Q_i(dt) of one coordinate, straight from the SDE.
Eigen::Matrix2d ProcessCovariance(double dt, double qc) {
  Eigen::Matrix2d q;
  q << dt * dt * dt / 3.0, dt * dt / 2.0, dt * dt / 2.0, dt;
  return qc * q;
}

// The autodiff twin: the square-root information from a numerical Cholesky
// factor of Q_i (independent of the closed form under test).
struct WnoaPriorAutoDiff {
  double dt;
  Eigen::Vector3d qc;
  template <typename T>
  bool operator()(T const* const* p, T* r) const {
    for (int c = 0; c < 3; ++c) {
      const Eigen::Matrix2d lower =
          ProcessCovariance(dt, qc[c]).llt().matrixL();
      const Eigen::Matrix2d sqrt_info = lower.inverse();
      const T e_p = p[1][c] - p[0][c] - dt * p[0][c + 3];
      const T e_v = p[1][c + 3] - p[0][c + 3];
      r[c] = sqrt_info(0, 0) * e_p + sqrt_info(0, 1) * e_v;
      r[c + 3] = sqrt_info(1, 0) * e_p + sqrt_info(1, 1) * e_v;
    }
    return true;
  }
};

TEST(WnoaPriorCostTest, AnalyticJacobianMatchesAutoDiff) {
  std::mt19937 rng(7);
  for (const double dt : {1e-3, 0.1, 1.0, 50.0}) {
    for (int trial = 0; trial < 5; ++trial) {
      const Eigen::Vector3d qc(0.5, 0.5, 0.05);
      const WnoaPriorCost cost(dt, qc.x(), qc.y(), qc.z());
      auto autodiff =
          testing::MakeAutoDiff(new WnoaPriorAutoDiff{dt, qc}, cost);
      // States of the motion's own scale, so the residuals are O(1)-ish
      // whatever dt.
      auto parameters =
          testing::RandomParameters(cost.parameter_block_sizes(), &rng);
      SCOPED_TRACE(dt);
      testing::ExpectSameCost(cost, *autodiff, parameters, 1e-8);
    }
  }
}

TEST(WnoaPriorCostTest, SqrtInformationWhitensProcessCovariance) {
  for (const double dt : {1e-3, 0.02, 1.0, 50.0, 100.0}) {
    const Eigen::Vector3d qc(0.3, 0.3, 0.02);
    const WnoaPriorCost cost(dt, qc.x(), qc.y(), qc.z());
    const WnoaPriorCost::Matrix6 information =
        cost.sqrt_information().transpose() * cost.sqrt_information();
    for (int c = 0; c < 3; ++c) {
      const Eigen::Matrix2d expected = ProcessCovariance(dt, qc[c]).inverse();
      for (int a = 0; a < 2; ++a) {
        for (int b = 0; b < 2; ++b) {
          EXPECT_NEAR(information(c + 3 * a, c + 3 * b), expected(a, b),
                      1e-9 * std::abs(expected(a, b)))
              << "dt " << dt << " coordinate " << c;
        }
      }
      // Coordinates are independent.
      for (int other = 0; other < 3; ++other) {
        if (other == c) continue;
        for (int a = 0; a < 2; ++a) {
          for (int b = 0; b < 2; ++b) {
            EXPECT_EQ(information(c + 3 * a, other + 3 * b), 0.0);
          }
        }
      }
    }
  }
}

TEST(WnoaPriorCostTest, HandComputedResidual) {
  // dt = 2, qc = 0.5: e_x = (3 - 1 - 2 * 0.5, 1 - 0.5) = (1, 0.5), and
  // S = sqrt(2) [sqrt(3) / 2^1.5, 0; -3 / 2^1.5, 2 / sqrt(2)], so
  // r_x = (sqrt(3) / 2, -1.5 + 1); the squared norm e^T Q^-1 e is 1.
  const WnoaPriorCost cost(2.0, 0.5, 0.5, 0.1);
  const double previous[6] = {1.0, 0.0, 0.0, 0.5, 0.0, 0.0};
  const double next[6] = {3.0, 0.0, 0.0, 1.0, 0.0, 0.0};
  const double* parameters[2] = {previous, next};
  double r[6];
  ASSERT_TRUE(cost.Evaluate(parameters, r, nullptr));
  EXPECT_NEAR(r[0], std::sqrt(3.0) / 2.0, 1e-15);
  EXPECT_NEAR(r[3], -0.5, 1e-15);
  for (const int k : {1, 2, 4, 5}) EXPECT_EQ(r[k], 0.0);
  EXPECT_NEAR(r[0] * r[0] + r[3] * r[3], 1.0, 1e-15);
}

TEST(WnoaPriorCostTest, ConstantVelocityMotionHasZeroResidual) {
  const double dt = 0.37;
  const WnoaPriorCost cost(dt, 1.0, 1.0, 0.1);
  const double previous[6] = {1.0, -2.0, 0.3, 0.5, 1.5, -0.2};
  double next[6];
  for (int c = 0; c < 3; ++c) {
    next[c] = previous[c] + dt * previous[c + 3];
    next[c + 3] = previous[c + 3];
  }
  const double* parameters[2] = {previous, next};
  double r[6];
  ASSERT_TRUE(cost.Evaluate(parameters, r, nullptr));
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(r[k], 0.0, 1e-14);
}

TEST(WnoaPriorCostTest, OnlyRequestedJacobiansAreWritten) {
  const WnoaPriorCost cost(1.0, 1.0, 1.0, 1.0);
  const double previous[6] = {0, 0, 0, 0, 0, 0};
  const double next[6] = {1, 1, 1, 1, 1, 1};
  const double* parameters[2] = {previous, next};
  double r[6], j1[36];
  double* jacobians[2] = {nullptr, j1};
  ASSERT_TRUE(cost.Evaluate(parameters, r, jacobians));
  // d r / d gamma_{i+1} = S: for qc = dt = 1, S_x = [sqrt(3) 0; -3 2].
  EXPECT_NEAR(j1[0 * 6 + 0], std::sqrt(3.0), 1e-15);
  EXPECT_EQ(j1[0 * 6 + 3], 0.0);
  EXPECT_EQ(j1[3 * 6 + 0], -3.0);
  EXPECT_EQ(j1[3 * 6 + 3], 2.0);
}

struct InitialStateAutoDiff {
  Eigen::Matrix<double, 6, 1> sigma;
  template <typename T>
  bool operator()(T const* const* p, T* r) const {
    for (int k = 0; k < 6; ++k) r[k] = p[0][k] / sigma[k];
    return true;
  }
};

TEST(WnoaInitialStateCostTest, AnalyticJacobianMatchesAutoDiff) {
  std::mt19937 rng(3);
  WnoaInitialStateCost::Vector6 sigma;
  sigma << 10.0, 10.0, 1.0, 0.5, 0.5, 0.1;
  const WnoaInitialStateCost cost(sigma);
  auto autodiff = testing::MakeAutoDiff(new InitialStateAutoDiff{sigma}, cost);
  for (int trial = 0; trial < 5; ++trial) {
    testing::ExpectSameCost(
        cost, *autodiff,
        testing::RandomParameters(cost.parameter_block_sizes(), &rng, 3.0));
  }
}

TEST(WnoaInitialStateCostTest, ResidualIsStateOverSigma) {
  WnoaInitialStateCost::Vector6 sigma;
  sigma << 10.0, 10.0, 1.0, 0.5, 0.5, 0.1;
  const WnoaInitialStateCost cost(sigma);
  const double state[6] = {5.0, -20.0, 0.5, 1.0, 0.0, 0.2};
  const double* parameters[1] = {state};
  double r[6], j[36];
  double* jacobians[1] = {j};
  ASSERT_TRUE(cost.Evaluate(parameters, r, jacobians));
  const double expected[6] = {0.5, -2.0, 0.5, 2.0, 0.0, 2.0};
  for (int k = 0; k < 6; ++k) {
    EXPECT_DOUBLE_EQ(r[k], expected[k]);
    for (int m = 0; m < 6; ++m) {
      EXPECT_DOUBLE_EQ(j[6 * k + m], k == m ? 1.0 / sigma[k] : 0.0);
    }
  }
}

}  // namespace
}  // namespace rff
