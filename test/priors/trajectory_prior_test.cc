#include "rff_ceres/priors/trajectory_prior.h"

#include <sstream>
#include <string>
#include <vector>

#include "gtest/gtest.h"
#include "rff_ceres/mean/mean_function.h"
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
  EXPECT_EQ(PriorNames(), (std::vector<std::string>{"rff", "wnoa"}));
  EXPECT_EQ(FindPrior("rff"), &FeaturePrior());
  EXPECT_EQ(FindPrior("wnoa"), &WnoaPrior());
  EXPECT_EQ(FindPrior("brownian"), nullptr);
  EXPECT_EQ(FindPrior(""), nullptr);
  EXPECT_TRUE(FindPrior("rff")->has_features());
  EXPECT_FALSE(FindPrior("wnoa")->has_features());
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
  EXPECT_EQ(error, "--prior=brownian: unknown prior; allowed rff or wnoa");
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

}  // namespace
}  // namespace rff
