#include "rff_ceres/priors/trajectory_prior.h"

#include <sstream>
#include <string>
#include <vector>

#include "gtest/gtest.h"
#include "rff_ceres/io/dataset_io.h"
#include "rff_ceres/mean/mean_function.h"
#include "rff_ceres/simulate.h"
#include "rff_ceres/slam_report.h"
#include "rff_ceres/slam_solver.h"

namespace rff {
namespace {

// Ten seconds of range records to one landmark, the start pinned.
Dataset TenSeconds() {
  Dataset dataset;
  dataset.pose_priors.push_back({{0.0, 0.0, 0.0, 0.0}, 0.1, 0.1});
  dataset.landmark_priors.push_back({1, 5.0, 5.0, 0.5});
  for (int k = 0; k <= 10; ++k) {
    Observation o;
    o.type = ObservationType::kRange;
    o.t = k;
    o.id = 1;
    o.range = 7.0;
    o.sigma_range = 0.1;
    dataset.observations.push_back(o);
  }
  return dataset;
}

TEST(TrajectoryPriorTest, RegistryNamesEachPriorOnce) {
  EXPECT_EQ(PriorNames(), (std::vector<std::string>{"rff", "wnoa", "wnoj"}));
  EXPECT_EQ(FindPrior("rff"), &FeaturePrior());
  EXPECT_EQ(FindPrior("wnoa"), &WnoaPrior());
  EXPECT_EQ(FindPrior("wnoj"), &WnojPrior());
  EXPECT_EQ(FindPrior("brownian"), nullptr);
  EXPECT_EQ(FindPrior(""), nullptr);
  EXPECT_TRUE(FindPrior("rff")->has_features());
  EXPECT_FALSE(FindPrior("wnoa")->has_features());
  EXPECT_FALSE(FindPrior("wnoj")->has_features());
}

TEST(TrajectoryPriorTest, ScalesAreTheOptionsLearningRescales) {
  SlamOptions options;
  const TrajectoryPrior& rff = *FindPrior("rff");
  *rff.PositionScale(&options) = 2.0;
  *rff.HeadingScale(&options) = 3.0;
  EXPECT_EQ(options.features.position_kernel.variance, 2.0);
  EXPECT_EQ(options.features.heading_kernel.variance, 3.0);
  EXPECT_STREQ(rff.scales_name(), "variances");
  const TrajectoryPrior& wnoa = *FindPrior("wnoa");
  *wnoa.PositionScale(&options) = 4.0;
  *wnoa.HeadingScale(&options) = 5.0;
  EXPECT_EQ(options.wnoa.position_qc, 4.0);
  EXPECT_EQ(options.wnoa.heading_qc, 5.0);
  EXPECT_STREQ(wnoa.scales_name(), "Q_c");
  const TrajectoryPrior& wnoj = *FindPrior("wnoj");
  *wnoj.PositionScale(&options) = 6.0;
  *wnoj.HeadingScale(&options) = 7.0;
  EXPECT_EQ(options.wnoj.position_qc, 6.0);
  EXPECT_EQ(options.wnoj.heading_qc, 7.0);
  EXPECT_EQ(options.wnoa.position_qc, 4.0);  // Each prior its own scales.
  EXPECT_STREQ(wnoj.scales_name(), "Q_c");
}

TEST(TrajectoryPriorTest, FactoryBuildsTheNamedModel) {
  const Dataset dataset = TenSeconds();
  const std::shared_ptr<const MeanFunction> mean = UnitWindowMean();
  SlamOptions options;
  options.mean.name = "constant";
  std::string error;
  options.prior = "wnoa";
  std::unique_ptr<TrajectoryModel> wnoa =
      CreateTrajectoryModel(dataset, options, mean, &error);
  ASSERT_NE(wnoa, nullptr) << error;
  EXPECT_EQ(wnoa->num_blocks(), 11);  // A state at each record's time.
  EXPECT_FALSE(wnoa->HasDenseReducedSystem());
  EXPECT_EQ(wnoa->block_size(0), 6);
  options.prior = "wnoj";
  std::unique_ptr<TrajectoryModel> wnoj =
      CreateTrajectoryModel(dataset, options, mean, &error);
  ASSERT_NE(wnoj, nullptr) << error;
  EXPECT_EQ(wnoj->num_blocks(), 11);  // The same state times.
  EXPECT_EQ(wnoj->block_size(0), 9);  // Position, velocity, acceleration.
  EXPECT_FALSE(wnoj->HasDenseReducedSystem());
  options.prior = "rff";
  std::unique_ptr<TrajectoryModel> rff =
      CreateTrajectoryModel(dataset, options, mean, &error);
  ASSERT_NE(rff, nullptr) << error;
  EXPECT_TRUE(rff->HasDenseReducedSystem());
}

TEST(TrajectoryPriorTest, UnknownPriorIsAnOptionError) {
  SlamOptions options;
  options.prior = "brownian";
  std::string error;
  EXPECT_EQ(
      CreateTrajectoryModel(TenSeconds(), options, UnitWindowMean(), &error),
      nullptr);
  EXPECT_EQ(error,
            "--prior=brownian: unknown prior; allowed rff, wnoa or wnoj");
}

TEST(TrajectoryPriorTest, WnoaModelLine) {
  SlamResult result;
  result.wnoa_options.position_qc = 0.5;
  result.wnoa_options.heading_qc = 0.25;
  result.prior_mean = "constant";
  std::ostringstream out;
  FindPrior("wnoa")->PrintModel(result, &out);
  EXPECT_EQ(out.str(),
            "  model        WNOA (LTV-SDE) prior, Q_c = 0.5 (x, y), 0.25 "
            "(theta), constant mean\n");
}

TEST(TrajectoryPriorTest, WnojModelLine) {
  SlamResult result;
  result.wnoj_options.position_qc = 0.125;
  result.wnoj_options.heading_qc = 2.0;
  result.prior_mean = "constant";
  std::ostringstream out;
  FindPrior("wnoj")->PrintModel(result, &out);
  EXPECT_EQ(out.str(),
            "  model        WNOJ (white noise on jerk) prior, Q_c = 0.125 (x, "
            "y), 2 (theta), constant mean\n");
}

// Rounds that stopped at a failed factorisation are not rounds that ran to
// the cap: the scales line says so, and the warning says why.
TEST(TrajectoryPriorTest, ScalesLineOfRoundsThatStoppedShort) {
  SlamOptions options;
  options.prior = "wnoj";
  SlamResult result;
  result.prior_mean = "constant";
  result.learning_rounds = 3;
  result.scales_not_learned =
      "the Gauss-Newton Hessian is not positive definite";
  std::ostringstream out;
  PrintSlamSummary(options, result, &out);
  EXPECT_NE(out.str().find("  scales       Q_c learned by variance "
                           "components, 3 rounds (stopped short: see the "
                           "warning)\n"),
            std::string::npos)
      << out.str();
  result.scales_not_learned.clear();
  std::ostringstream capped;
  PrintSlamSummary(options, result, &capped);
  EXPECT_NE(capped.str().find("3 rounds (stopped at the round cap, the "
                              "factors still moving)"),
            std::string::npos)
      << capped.str();
}

// Sightings at one time leave a Markov prior no rows to learn its Q_c
// from (nor the noise theirs): the scales line says it kept them, not that
// it learned them.
TEST(TrajectoryPriorTest, ScalesLineOfDataThatLeaveNothingToLearn) {
  std::istringstream text(
      "RFFD 1\n"
      "PRIOR_POSE 0 0 0 0 0.1 0.05\n"
      "PRIOR_LANDMARK 1 5 0 1\n"
      "PRIOR_LANDMARK 2 0 5 1\n"
      "RANGE_BEARING 0 1 5.1 0.02 0.1 0.02\n"
      "RANGE_BEARING 0 2 4.9 1.55 0.1 0.02\n");
  Dataset dataset;
  std::string error;
  ASSERT_TRUE(ParseDataset(&text, "one time", &dataset, &error)) << error;
  for (const char* name : {"wnoa", "wnoj"}) {
    SlamOptions options;
    options.prior = name;
    SlamResult result;
    ASSERT_TRUE(RunSlam(dataset, options, &result, &error)) << error;
    std::ostringstream out;
    PrintSlamSummary(options, result, &out);
    EXPECT_NE(out.str().find("  scales       Q_c kept as given: the data "
                             "leave its rows under 10 of redundancy (rows "
                             "less the parameters they determine); no noise "
                             "factor learned either, 1 round\n"),
              std::string::npos)
        << name << "\n"
        << out.str();
  }
}

// The default Q_c (1 m^2/s^3) is about 50 times what a 10 Hz wheel run
// learns from it; started from its odometry's second differences, within a
// factor 2, the Laplace evidence falls at the first round and the rounds
// keep the start (the data state their sigmas truthfully).
TEST(TrajectoryPriorTest, WnoaLearningStartsFromTheOdometry) {
  SimulationOptions sim = Laser10HzOptions(11);
  sim.num_steps = 1500;
  Dataset dataset;
  std::string error;
  ASSERT_TRUE(Simulate(sim, &dataset, &error)) << error;
  SlamOptions options;
  options.prior = "wnoa";
  SlamResult started, given;
  ASSERT_TRUE(RunSlam(dataset, options, &started, &error)) << error;
  options.wnoa.qc_start = "given";
  ASSERT_TRUE(RunSlam(dataset, options, &given, &error)) << error;
  EXPECT_EQ(given.qc_from_odometry.windows, 0);
  EXPECT_EQ(started.qc_from_odometry.windows, 298);  // 149.9 s of records.
  const double start = started.qc_from_odometry.position_qc;
  const double learned = given.wnoa_options.position_qc;
  // Within a factor 2 (its noise adds to the second differences), where the
  // default is 1 / learned = 50 times off.
  EXPECT_GT(start / learned, 1.0);
  EXPECT_LT(start / learned, 2.0);
  EXPECT_GT(1.0 / learned, 40.0);
  EXPECT_EQ(started.learning_rounds, 2);
  EXPECT_EQ(given.learning_rounds, 7);
  EXPECT_TRUE(started.learning_evidence_fell);
  EXPECT_EQ(started.wnoa_options.position_qc, start);
  EXPECT_EQ(started.noise.range, 1.0);
  std::ostringstream out;
  options.wnoa.qc_start = "odometry";
  PrintSlamSummary(options, started, &out);
  std::ostringstream expected;
  expected << "Q_c learned by variance components, 2 rounds (ended at the "
              "round before the Laplace evidence fell); from the odometry's "
           << start << " (x, y), " << started.qc_from_odometry.heading_qc
           << " (theta)\n";
  EXPECT_NE(out.str().find(expected.str()), std::string::npos) << out.str();
  // A start over 10^6 times off the given Q_c is a degenerate estimate.
  options.wnoa.position_qc = 1e5 * start;
  SlamResult far;
  ASSERT_TRUE(RunSlam(dataset, options, &far, &error)) << error;
  EXPECT_EQ(far.qc_from_odometry.windows, 298);
  EXPECT_EQ(far.qc_start_kept, "");
  options.wnoa.position_qc = 1e7 * start;
  ASSERT_TRUE(RunSlam(dataset, options, &far, &error)) << error;
  EXPECT_EQ(far.qc_from_odometry.windows, 0);
  std::ostringstream far_why;
  far_why << "the odometry's " << start << " (x, y), "
          << started.qc_from_odometry.heading_qc
          << " (theta) are over 1e+06 times off the given values";
  EXPECT_EQ(far.qc_start_kept, far_why.str());
  options.wnoa.position_qc = WnoaOptions().position_qc;
  // Where the odometry's scale is estimated, it says nothing of the size.
  options.problem.odometry_calibration.estimate = true;
  SlamResult calibrated;
  ASSERT_TRUE(RunSlam(dataset, options, &calibrated, &error)) << error;
  EXPECT_EQ(calibrated.qc_from_odometry.windows, 0);
  EXPECT_EQ(calibrated.qc_start_kept, "the odometry's scale is estimated");
  std::ostringstream calibrated_out;
  PrintSlamSummary(options, calibrated, &calibrated_out);
  EXPECT_NE(calibrated_out.str().find(
                "; started as given: the odometry's scale is estimated\n"),
            std::string::npos)
      << calibrated_out.str();
  options.wnoa.qc_start = "dead reckoning";
  EXPECT_FALSE(RunSlam(dataset, options, &started, &error));
  EXPECT_EQ(error, "--wnoa_qc_start=dead reckoning: allowed odometry or given");
}

}  // namespace
}  // namespace rff
