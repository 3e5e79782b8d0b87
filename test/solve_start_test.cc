#include "rff_ceres/solve_start.h"

#include <map>
#include <memory>
#include <string>

#include "gtest/gtest.h"
#include "test/paper_dataset.h"

namespace rff {
namespace {

// With a "wnoa" mean (the RFF prior's default on the paper's simulator, 60
// poses with odometry) the trajectory starts on the mean (the weights at
// zero) and every landmark at the WNOA solve's estimate, not at a fresh
// multilateration from the mean's poses.
TEST(BuildMeanTest, WnoaMeanStartsTheLandmarksAtItsSolve) {
  const Dataset dataset = testing::PaperDataset(3, 60, 10, 3);
  ASSERT_FALSE(dataset.odometry.empty());
  SlamOptions options;
  options.solver.num_threads = 1;
  SlamResult result;
  result.prior_mean = SettlePriorMean(options, dataset);
  ASSERT_EQ(result.prior_mean, "wnoa");
  SlamOptions warm = options, settled = options;
  SlamResult wnoa_solve;
  std::string error;
  const std::shared_ptr<const MeanFunction> mean = BuildMean(
      dataset, dataset, options, &warm, &settled, &wnoa_solve, &result, &error);
  ASSERT_NE(mean, nullptr) << error;
  EXPECT_TRUE(warm.start.poses.empty());
  ASSERT_EQ(wnoa_solve.landmarks.size(), 10u);
  ASSERT_EQ(warm.start.landmarks.size(), wnoa_solve.landmarks.size());
  for (const Landmark& l : wnoa_solve.landmarks) {
    ASSERT_EQ(warm.start.landmarks.count(l.id), 1u) << l.id;
    EXPECT_EQ(warm.start.landmarks.at(l.id).x(), l.x) << l.id;
    EXPECT_EQ(warm.start.landmarks.at(l.id).y(), l.y) << l.id;
  }
  // The mean is the solve's trajectory.
  const TimedPose& p = wnoa_solve.trajectory[wnoa_solve.trajectory.size() / 2];
  EXPECT_NEAR(mean->Evaluate(p.t).x(), p.x, 1e-12);
}

}  // namespace
}  // namespace rff
