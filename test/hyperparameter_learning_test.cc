#include "rff_ceres/hyperparameter_learning.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <memory>
#include <ostream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "Eigen/Dense"
#include "gtest/gtest.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/kernels/kernel.h"
#include "rff_ceres/mean/prior_mean.h"
#include "rff_ceres/pose_evidence.h"
#include "rff_ceres/simulate.h"
#include "rff_ceres/simulate_gp_draw.h"
#include "rff_ceres/slam_report.h"
#include "rff_ceres/slam_solver.h"

namespace rff {
namespace {

// A small linearised likelihood: random per-time information factors (one
// of them rank-deficient, as a range-only fix) and whitened observations.
PoseLikelihood RandomLikelihood(int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  PoseLikelihood likelihood;
  for (int i = 0; i < n; ++i) {
    Eigen::Matrix3d l;
    for (int k = 0; k < 9; ++k) l(k) = normal(rng);
    if (i == 1) l.col(2).setZero();
    likelihood.times.push_back(1.5 * i + 0.3 * normal(rng));
    likelihood.factors.push_back(l);
    Eigen::Vector3d y(normal(rng), normal(rng), normal(rng));
    if (i == 1) y.z() = 0.0;
    likelihood.whitened.push_back(3.0 * y);
  }
  return likelihood;
}

// The restricted likelihood is the limit of the plain Gaussian likelihood
// with a constant offset of variance s^2, plus 3 log s and (3n / 2) log 2 pi
// (Rasmussen & Williams 2006, eq. 2.45); the level is the offset's
// posterior mean in that limit.
TEST(PoseLogEvidenceTest, IsTheRestrictedLikelihoodOfADenseGaussian) {
  const int n = 7;
  const PoseLikelihood likelihood = RandomLikelihood(n, 5);
  std::string error;
  for (const std::string name : {"rbf", "matern52"}) {
    const std::unique_ptr<Kernel> position =
        CreateKernel({name, 4.0, 3.0}, &error);
    const std::unique_ptr<Kernel> heading =
        CreateKernel({name, 0.3, 6.0}, &error);
    ASSERT_TRUE(position && heading) << error;
    Eigen::Vector3d level;
    const double value =
        PoseLogEvidence(likelihood, *position, *heading, &level);

    const double s = 1e4;
    Eigen::MatrixXd k = Eigen::MatrixXd::Zero(3 * n, 3 * n);
    Eigen::MatrixXd l = Eigen::MatrixXd::Zero(3 * n, 3 * n);
    Eigen::MatrixXd ones(3 * n, 3);
    Eigen::VectorXd y(3 * n);
    for (int i = 0; i < n; ++i) {
      l.block<3, 3>(3 * i, 3 * i) = likelihood.factors[i];
      ones.middleRows<3>(3 * i).setIdentity();
      y.segment<3>(3 * i) = likelihood.whitened[i];
      for (int j = 0; j < n; ++j) {
        const double tau = likelihood.times[i] - likelihood.times[j];
        k(3 * i, 3 * j) = k(3 * i + 1, 3 * j + 1) = position->Evaluate(tau);
        k(3 * i + 2, 3 * j + 2) = heading->Evaluate(tau);
      }
    }
    const Eigen::MatrixXd prior = k + s * s * ones * ones.transpose();
    const Eigen::MatrixXd covariance =
        Eigen::MatrixXd::Identity(3 * n, 3 * n) + l.transpose() * prior * l;
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(covariance);
    const double log_normal = -0.5 * y.dot(ldlt.solve(y)) -
                              0.5 * ldlt.vectorD().array().log().sum() -
                              1.5 * n * std::log(2.0 * M_PI);
    EXPECT_NEAR(value,
                log_normal + 3.0 * std::log(s) + 1.5 * n * std::log(2.0 * M_PI),
                1e-5)
        << name;
    const Eigen::Vector3d offset =
        s * s * (l.transpose() * ones).transpose() * ldlt.solve(y);
    EXPECT_LT((level - offset).norm(), 1e-5) << name;
  }
}

struct RecoveryCase {
  std::string kernel;
  double lengthscale;
};

std::ostream& operator<<(std::ostream& out, const RecoveryCase& c) {
  return out << c.kernel << " " << c.lengthscale << " s";
}

class LearningRecoveryTest : public ::testing::TestWithParam<RecoveryCase> {};

// Draws from the prior (gp_draw preset: 600 poses, range-bearing, map priors
// 1 m off): learning about the WNOA solve, as RunSlam does without
// odometry, finds the x/y lengthscale of every draw within 20%.
TEST_P(LearningRecoveryTest, LengthscaleWithinTwentyPercent) {
  const RecoveryCase& c = GetParam();
  for (const std::uint64_t seed : {301, 302, 303}) {
    SimulationOptions simulation = GpDrawOptions(seed);
    simulation.gp_kernel = c.kernel;
    simulation.gp_lengthscale = c.lengthscale;
    Dataset dataset;
    std::string error;
    ASSERT_TRUE(Simulate(simulation, &dataset, &error)) << error;

    SlamOptions wnoa_options;
    wnoa_options.prior = "wnoa";
    wnoa_options.output.covariance = false;
    SlamResult wnoa;
    ASSERT_TRUE(RunSlam(dataset, wnoa_options, &wnoa, &error)) << error;
    std::map<LandmarkId, Eigen::Vector2d> landmarks;
    for (const Landmark& l : wnoa.landmarks) landmarks[l.id] = {l.x, l.y};
    const std::shared_ptr<const MeanFunction> mean =
        BuildPriorMean("constant", dataset, &error);
    ASSERT_TRUE(mean) << error;

    FeatureTrajectoryOptions trajectory;
    trajectory.position_kernel.name = c.kernel;
    trajectory.heading_kernel.name = c.kernel;
    LearningReport report;
    ASSERT_TRUE(LearnHyperparameters(dataset, mean, wnoa.trajectory, landmarks,
                                     ProblemOptions(), LearningOptions(),
                                     &trajectory, &report, &error))
        << error;
    const double learned = trajectory.position_kernel.lengthscale;
    std::printf(
        "%s %g s, seed %llu: learned %.3f s (heading %.3f s), %d "
        "evaluations\n",
        c.kernel.c_str(), c.lengthscale, static_cast<unsigned long long>(seed),
        learned, trajectory.heading_kernel.lengthscale, report.evaluations);
    EXPECT_NEAR(learned, c.lengthscale, 0.2 * c.lengthscale)
        << c.kernel << " seed " << seed;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Kernels, LearningRecoveryTest,
    ::testing::Values(RecoveryCase{"rbf", 8.0}, RecoveryCase{"matern52", 8.0},
                      RecoveryCase{"matern52", 3.0}, RecoveryCase{"rbf", 30.0}),
    [](const ::testing::TestParamInfo<RecoveryCase>& info) {
      return info.param.kernel + "_" +
             std::to_string(static_cast<int>(info.param.lengthscale)) + "s";
    });

// The default solve of a run without odometry learns (RFF prior, the
// truth's kernel only): the summary JSON carries the learned values under
// the flags' names, the objective and the level the mean moved to.
TEST(LearningRunSlamTest, DefaultSolveLearnsAndReportsTheValues) {
  SimulationOptions simulation = GpDrawOptions(311);
  simulation.num_steps = 300;
  simulation.gp_kernel = "rbf";
  Dataset dataset;
  std::string error;
  ASSERT_TRUE(Simulate(simulation, &dataset, &error)) << error;
  SlamOptions options;
  options.features.position_kernel.name = "rbf";
  options.features.heading_kernel.name = "rbf";
  SlamResult result;
  ASSERT_TRUE(RunSlam(dataset, options, &result, &error)) << error;
  EXPECT_TRUE(result.learned);
  EXPECT_EQ(result.initial_trajectory, "wnoa");
  EXPECT_GT(result.learning.evaluations, 10);
  EXPECT_TRUE(result.learning.level.allFinite());
  const double lengthscale =
      result.trajectory_options.position_kernel.lengthscale;
  EXPECT_NEAR(lengthscale, 8.0, 0.3 * 8.0);

  const std::string path = testing::TempDir() + "/learning_summary.json";
  ASSERT_TRUE(WriteSummaryJson(options, result, path, &error)) << error;
  std::ifstream in(path);
  std::stringstream json;
  json << in.rdbuf();
  EXPECT_NE(json.str().find("\"learn_hyperparameters\": true"),
            std::string::npos);
  EXPECT_NE(json.str().find("\"lengthscale\": " + FormatNumber(lengthscale)),
            std::string::npos)
      << json.str();
  EXPECT_NE(json.str().find("\"log_evidence\": " +
                            FormatNumber(result.learning.log_evidence)),
            std::string::npos);
  EXPECT_NE(json.str().find("\"learned_level\": ["), std::string::npos);
}

}  // namespace
}  // namespace rff
