#include "rff_ceres/truncation_covariance.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "Eigen/Dense"
#include "gtest/gtest.h"
#include "rff_ceres/consistency.h"
#include "rff_ceres/metrics.h"
#include "rff_ceres/simulate.h"
#include "rff_ceres/simulate_gp_draw.h"
#include "rff_ceres/slam_solver.h"
#include "test/exact_gp/exact_gp_map.h"
#include "test/paper_dataset.h"

namespace rff {
namespace {

// A gp_draw run of 200 poses with the map known (priors 0.1 m about the
// truth): each run's errors are local, not one shift of its frame, so the
// mean position NEES over a few runs says how consistent a covariance is.
Dataset KnownMapDraw(std::uint64_t seed, const std::string& kernel,
                     double lengthscale) {
  SimulationOptions options = GpDrawOptions(seed);
  options.num_steps = 200;
  options.gp_kernel = kernel;
  options.gp_lengthscale = lengthscale;
  options.landmark_prior_sigma = 0.1;
  Dataset dataset;
  std::string error;
  EXPECT_TRUE(Simulate(options, &dataset, &error)) << error;
  return dataset;
}

ExactGpOptions Truth(const Dataset& dataset) {
  ExactGpOptions options;
  std::string error;
  EXPECT_TRUE(SetTruthKernels(dataset, &options, &error)) << error;
  return options;
}

// rff_slam's defaults with the draw's kernel family (--kernel) and the
// covariance; `truncation` adds the truncation term.
SlamOptions DefaultRff(const std::string& kernel, bool truncation) {
  SlamOptions options;
  options.prior = "rff";
  options.features.position_kernel.name = kernel;
  options.features.heading_kernel.name = kernel;
  options.output.covariance = true;
  options.output.covariance_truncation = truncation;
  return options;
}

double MeanPositionNees(const Dataset& dataset, const SlamResult& result) {
  std::vector<PoseCovariance> covariances;
  for (std::size_t k = 0; k < result.trajectory.size(); ++k) {
    covariances.push_back({result.trajectory[k].t, result.pose_covariances[k]});
  }
  Evaluation evaluation;
  std::string error;
  EXPECT_TRUE(EvaluateConsistency(dataset.ground_truth, result.trajectory,
                                  covariances, &evaluation, &error))
      << error;
  return evaluation.consistency.mean_position_nees;
}

// The default solve's covariance against the exact GP posterior's (dense
// kernel matrix, the true hyperparameters) on twenty draws, rbf and Matern
// 5/2, lengthscales 5, 10 and 20 s: the pooled mean position NEES is
// within 10% of the exact GP's on the same draws. Without the truncation
// term the capacity rule's missed motion made it 1.56x (3.24 against 2.08).
TEST(TruncationCovarianceTest, DefaultRffIsAsConsistentAsTheExactGp) {
  const double lengthscales[] = {5.0, 10.0, 20.0};
  double exact_sum = 0.0, rff_sum = 0.0;
  int runs = 0;
  for (std::uint64_t seed = 301; seed <= 320; ++seed) {
    const std::string kernel = seed % 2 == 1 ? "rbf" : "matern52";
    const Dataset dataset =
        KnownMapDraw(seed, kernel, lengthscales[(seed - 301) % 3]);
    ExactGpOptions exact_options = Truth(dataset);
    exact_options.compute_covariance = true;
    ExactGpResult exact;
    Evaluation exact_evaluation;
    std::string error;
    ASSERT_TRUE(SolveExactGpMapFromGroundTruth(dataset, exact_options, &exact,
                                               &exact_evaluation, &error))
        << error;
    // At its MAP: some draws stall at rounding just above the 1e-6 of
    // `converged` (seed 311: 1.3e-6 in whitened units).
    ASSERT_LT(exact.gradient_max_norm, 1e-5);
    double exact_nees = 0.0;
    ASSERT_TRUE(PositionNees(dataset, exact, &exact_nees, &error)) << error;

    SlamResult rff;
    ASSERT_TRUE(RunSlam(dataset, DefaultRff(kernel, true), &rff, &error))
        << error;
    ASSERT_EQ(rff.covariance_truncation.rfind("added: the next ", 0), 0u)
        << rff.covariance_truncation;
    const double rff_nees = MeanPositionNees(dataset, rff);
    std::printf("seed %llu %s: position NEES exact GP %.3f, RFF %.3f\n",
                static_cast<unsigned long long>(seed), kernel.c_str(),
                exact_nees, rff_nees);
    exact_sum += exact_nees;
    rff_sum += rff_nees;
    ++runs;
  }
  const double exact_pooled = exact_sum / runs, rff_pooled = rff_sum / runs;
  std::printf("pooled position NEES over %d draws: exact GP %.3f, RFF %.3f\n",
              runs, exact_pooled, rff_pooled);
  EXPECT_NEAR(rff_pooled / exact_pooled, 1.0, 0.10);
}

// The term is a covariance (every pose's and landmark's grows by a positive
// semi-definite matrix); it vanishes where the basis misses nothing (rbf on
// one global map of 128 modes) and is much of the variance where the
// capacity rule cuts a Matern 5/2 spectrum (the default).
TEST(TruncationCovarianceTest, GrowsOnlyWhereTheBasisMissesMotion) {
  struct Case {
    std::string kernel;
    int features;  // 0: the capacity rule.
  };
  for (const Case& c : {Case{"rbf", 128}, Case{"matern52", 0}}) {
    const Dataset dataset = KnownMapDraw(7, c.kernel, 5.0);
    const ExactGpOptions truth = Truth(dataset);
    auto solve = [&](bool truncation) {
      SlamOptions options = DefaultRff(c.kernel, truncation);
      options.learn_hyperparameters = "off";
      options.features.position_kernel = truth.position_kernel;
      options.features.heading_kernel = truth.heading_kernel;
      options.features.num_position_features = c.features;
      options.features.num_heading_features = c.features;
      SlamResult result;
      std::string error;
      EXPECT_TRUE(RunSlam(dataset, options, &result, &error)) << error;
      return result;
    };
    const SlamResult with = solve(true);
    const SlamResult without = solve(false);
    EXPECT_EQ(without.covariance_truncation, "none: not asked for");
    ASSERT_EQ(with.pose_covariances.size(), without.pose_covariances.size());
    double smallest = 0.0, largest = 0.0, mean = 0.0;
    for (std::size_t k = 0; k < with.pose_covariances.size(); ++k) {
      const Eigen::Matrix3d added =
          with.pose_covariances[k] - without.pose_covariances[k];
      const Eigen::Vector3d eigenvalues =
          Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(added).eigenvalues();
      const double scale = without.pose_covariances[k].trace();
      smallest = std::min(smallest, eigenvalues.minCoeff() / scale);
      const double share =
          added.topLeftCorner<2, 2>().trace() /
          without.pose_covariances[k].topLeftCorner<2, 2>().trace();
      largest = std::max(largest, share);
      mean += share / with.pose_covariances.size();
    }
    ASSERT_EQ(with.landmarks.size(), without.landmarks.size());
    for (std::size_t i = 0; i < with.landmarks.size(); ++i) {
      EXPECT_GE(with.landmarks[i].sxx, without.landmarks[i].sxx);
      EXPECT_GE(with.landmarks[i].syy, without.landmarks[i].syy);
    }
    std::printf(
        "%s, %d features (0: the capacity rule), %s: position "
        "variance up by %.2e on average, %.2e at most\n",
        c.kernel.c_str(), c.features, with.covariance_truncation.c_str(), mean,
        largest);
    EXPECT_GT(smallest, -1e-12);
    if (c.features > 0) {
      EXPECT_LT(largest, 1e-6);
    } else {
      EXPECT_GT(mean, 0.2);
    }
  }
}

// Where nothing is added the summary says why, and the covariance is the
// truncated model's own: random features have no next modes; an
// incremental solve is not rebuilt.
TEST(TruncationCovarianceTest, NotesSayWhyNothingWasAdded) {
  const Dataset dataset = testing::PaperDataset(3, 60, 20, 2);
  struct Case {
    std::string features;
    int incremental_every;
    std::string note;
  };
  for (const Case& c :
       {Case{"rff", 0,
             "none: more modes of the same basis need the hilbert family, "
             "not rff"},
        Case{"hilbert", 20, "none: an incremental solve"}}) {
    SlamOptions options = DefaultRff("rbf", true);
    options.features.family = c.features;
    options.incremental.every = c.incremental_every;
    SlamResult result;
    std::string error;
    ASSERT_TRUE(RunSlam(dataset, options, &result, &error)) << error;
    EXPECT_EQ(result.covariance_truncation, c.note);
    EXPECT_EQ(result.pose_covariances.size(), result.trajectory.size());
  }
}

}  // namespace
}  // namespace rff
