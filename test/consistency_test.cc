#include "rff_ceres/consistency.h"

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "Eigen/Cholesky"
#include "gtest/gtest.h"

namespace rff {
namespace {

// Ground truth = estimate + errors drawn from the stated covariance, scaled
// by `error_scale`: with 1 the NEES means are the degrees of freedom and the
// coverage the nominal levels.
struct DrawnRun {
  std::vector<TimedPose> truth, estimate;
  std::vector<PoseCovariance> covariances;
};

DrawnRun Draw(int n, double error_scale, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  DrawnRun setup;
  Eigen::Matrix3d covariance;
  covariance << 0.04, 0.01, 0.002, 0.01, 0.09, -0.003, 0.002, -0.003, 0.01;
  const Eigen::Matrix3d root = covariance.llt().matrixL();
  for (int i = 0; i < n; ++i) {
    const double t = i;
    const TimedPose estimate{t, std::cos(0.1 * t), std::sin(0.1 * t), 0.05 * t};
    const Eigen::Vector3d e =
        error_scale * root *
        Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
    setup.estimate.push_back(estimate);
    setup.truth.push_back(
        {t, estimate.x + e.x(), estimate.y + e.y(), estimate.theta + e.z()});
    setup.covariances.push_back({t, covariance});
  }
  return setup;
}

// The consistency of a drawn run (which must evaluate).
ConsistencySummary Consistency(const DrawnRun& run) {
  Evaluation evaluation;
  std::string error;
  EXPECT_TRUE(EvaluateConsistency(run.truth, run.estimate, run.covariances,
                                  &evaluation, &error))
      << error;
  return evaluation.consistency;
}

TEST(CovarianceAtTest, ExactAtEntriesLinearBetweenEndsOutside) {
  const Eigen::Matrix3d a = 0.3 * Eigen::Matrix3d::Identity();
  Eigen::Matrix3d b;
  b << 0.5, 0.1, 0.0, 0.1, 0.7, 0.02, 0.0, 0.02, 0.011;
  const std::vector<PoseCovariance> covariances = {{1.0, a}, {3.0, b}};
  EXPECT_EQ(CovarianceAt(covariances, 1.0), a);
  EXPECT_EQ(CovarianceAt(covariances, 3.0), b);
  EXPECT_TRUE(CovarianceAt(covariances, 1.5).isApprox(0.75 * a + 0.25 * b));
  EXPECT_EQ(CovarianceAt(covariances, 0.0), a);
  EXPECT_EQ(CovarianceAt(covariances, 9.0), b);
}

TEST(EvaluateConsistencyTest, ErrorsDrawnFromTheCovarianceAreConsistent) {
  const ConsistencySummary c = Consistency(Draw(20000, 1.0, 7));
  EXPECT_TRUE(c.evaluated);
  EXPECT_EQ(c.count, 20000);
  // Standard errors: sqrt(4 / n) = 0.014 and sqrt(2 / n) = 0.01.
  EXPECT_NEAR(c.mean_position_nees, 2.0, 0.05);
  EXPECT_NEAR(c.mean_heading_nees, 1.0, 0.04);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(c.position_coverage[k], kCoverageLevels[k], 0.01) << k;
    EXPECT_NEAR(c.heading_coverage[k], kCoverageLevels[k], 0.01) << k;
  }
}

TEST(EvaluateConsistencyTest, ErrorsTwiceTheClaimGiveFourTimesTheNees) {
  const ConsistencySummary c = Consistency(Draw(20000, 2.0, 8));
  EXPECT_NEAR(c.mean_position_nees, 8.0, 0.25);
  EXPECT_LT(c.position_coverage[1], 0.6);
}

TEST(EvaluateConsistencyTest, CovariancesAtOtherTimesAreAnError) {
  DrawnRun setup = Draw(5, 1.0, 9);
  Evaluation evaluation;
  std::string error;
  setup.covariances.pop_back();
  EXPECT_FALSE(EvaluateConsistency(setup.truth, setup.estimate,
                                   setup.covariances, &evaluation, &error));
  EXPECT_EQ(error,
            "the covariances have 4 entries, the trajectory 5 poses: they "
            "must be at the same times");
  setup = Draw(5, 1.0, 9);
  setup.covariances[2].t = 2.5;
  EXPECT_FALSE(EvaluateConsistency(setup.truth, setup.estimate,
                                   setup.covariances, &evaluation, &error));
  EXPECT_EQ(error,
            "covariance entry 3 is at t 2.5, the trajectory's pose at 2");
  setup = Draw(5, 1.0, 9);
  setup.covariances[1].covariance.setZero();
  EXPECT_FALSE(EvaluateConsistency(setup.truth, setup.estimate,
                                   setup.covariances, &evaluation, &error));
  EXPECT_EQ(error,
            "the covariance at t 1 is singular: no consistency to measure");
  EXPECT_FALSE(evaluation.consistency.evaluated);
}

}  // namespace
}  // namespace rff
