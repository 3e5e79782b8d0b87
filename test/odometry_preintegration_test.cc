#include "rff_ceres/odometry_preintegration.h"

#include <cmath>
#include <random>

#include "Eigen/Dense"
#include "gtest/gtest.h"

namespace rff {
namespace {

Odometry Step(double t0, double t1, double dx, double dtheta) {
  return {t0, t1, dx, 0.0, dtheta, 0.01, 0.02, 0.003};
}

TEST(OdometryPreintegrationTest, ComposesChainsAndStopsAtKeptTimesAndGaps) {
  // A quarter turn in two steps: forward 1 m, turn 90 deg, forward 1 m.
  const std::vector<Odometry> odometry = {
      Step(0, 1, 1.0, M_PI / 2), Step(1, 2, 1.0, 0.0),
      Step(2, 3, 1.0, 0.0),   // Kept time 2 splits.
      Step(4, 5, 1.0, 0.0)};  // Gap 3..4 splits.
  const auto chains = PreintegrateOdometry(odometry, {2.0}, 100.0);
  ASSERT_EQ(chains.size(), 3u);
  EXPECT_EQ(chains[0].t0, 0.0);
  EXPECT_EQ(chains[0].t1, 2.0);
  EXPECT_EQ(chains[0].num_records, 2);
  EXPECT_NEAR(chains[0].motion.x(), 1.0, 1e-12);
  EXPECT_NEAR(chains[0].motion.y(), 1.0, 1e-12);
  EXPECT_NEAR(chains[0].motion.z(), M_PI / 2, 1e-12);
  EXPECT_EQ(chains[1].t0, 2.0);
  EXPECT_EQ(chains[1].t1, 3.0);
  EXPECT_EQ(chains[2].t0, 4.0);
}

TEST(OdometryPreintegrationTest, MaxDurationSplitsLongChains) {
  std::vector<Odometry> odometry;
  for (int k = 0; k < 10; ++k) odometry.push_back(Step(k, k + 1, 1.0, 0.0));
  EXPECT_EQ(PreintegrateOdometry(odometry, {}, 3.0).size(), 4u);  // 3+3+3+1
  EXPECT_EQ(PreintegrateOdometry(odometry, {}, 100.0).size(), 1u);
}

TEST(OdometryPreintegrationTest, CovarianceMatchesMonteCarlo) {
  const std::vector<Odometry> odometry = {
      Step(0, 1, 2.0, 0.4), Step(1, 2, 1.5, -0.3), Step(2, 3, 1.0, 0.2)};
  const auto chains = PreintegrateOdometry(odometry, {}, 100.0);
  ASSERT_EQ(chains.size(), 1u);
  // Sample noisy steps, compose exactly, and compare the sample covariance.
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  const int n = 200000;
  Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
  for (int i = 0; i < n; ++i) {
    double x = 0, y = 0, th = 0;
    for (const Odometry& o : odometry) {
      const double dx = o.dx + o.sigma_x * normal(rng);
      const double dy = o.dy + o.sigma_y * normal(rng);
      const double dth = o.dtheta + o.sigma_theta * normal(rng);
      x += std::cos(th) * dx - std::sin(th) * dy;
      y += std::sin(th) * dx + std::cos(th) * dy;
      th += dth;
    }
    const Eigen::Vector3d e = Eigen::Vector3d(x, y, th) - chains[0].motion;
    sum += e * e.transpose();
  }
  const Eigen::Matrix3d sample = sum / n;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(sample(r, c), chains[0].covariance(r, c),
                  0.03 * std::sqrt(sample(r, r) * sample(c, c)))
          << r << "," << c;
    }
  }
  const Eigen::Matrix3d l = SqrtInformation(chains[0].covariance);
  EXPECT_TRUE((l.transpose() * l * chains[0].covariance)
                  .isApprox(Eigen::Matrix3d::Identity(), 1e-9));
}

}  // namespace
}  // namespace rff
