#include "costs/bearing_cost.h"

#include "test/costs/cost_test_util.h"

namespace rff {
namespace {

using testing::PoseOf;
using testing::Wrap;

struct BearingAutoDiff {
  PoseMap map;
  double bearing, sigma;
  int landmark_block;
  template <typename T>
  bool operator()(T const* const* p, T* r) const {
    const auto pose = PoseOf(map, p);
    const T predicted =
        atan2(p[landmark_block][1] - pose[1], p[landmark_block][0] - pose[0]) -
        pose[2];
    r[0] = Wrap(T(predicted - bearing)) / sigma;
    return true;
  }
};

TEST(BearingCostTest, AnalyticJacobianMatchesAutoDiff) {
  std::mt19937 rng(2);
  for (int trial = 0; trial < 20; ++trial) {
    const PoseMap map = testing::RandomPoseMap(&rng);
    const double z = -3.0 + 0.3 * trial;
    const BearingCost cost(map, z, 0.05);
    auto autodiff =
        testing::MakeAutoDiff(new BearingAutoDiff{map, z, 0.05, 3}, cost);
    auto parameters =
        testing::RandomParameters(cost.parameter_block_sizes(), &rng);
    parameters[3] = {-6.0 + trial, 7.0 - trial};
    testing::ExpectSameCost(cost, *autodiff, parameters);
  }
}

TEST(BearingCostTest, ResidualIsWrappedAcrossPi) {
  PoseMap map;  // Pose (0, 0, 0), no weights touch it.
  map.terms.push_back(
      {0, 0, std::make_shared<Eigen::VectorXd>(Eigen::VectorXd::Zero(1))});
  // Landmark straight behind at bearing just below pi; measured just above
  // -pi: the error is 0.02 rad, not 2 pi - 0.02.
  const BearingCost cost(map, -M_PI + 0.01, 0.01);
  const double b[1] = {0.0};
  const double l[2] = {-1.0, std::tan(0.01)};
  const double* parameters[2] = {b, l};
  double r;
  ASSERT_TRUE(cost.Evaluate(parameters, &r, nullptr));
  EXPECT_NEAR(r, (M_PI - 0.01 - (-M_PI + 0.01) - 2.0 * M_PI) / 0.01, 1e-9);
  EXPECT_NEAR(r, -2.0, 1e-9);
}

TEST(BearingCostTest, LandmarkOnTheRobotIsAnEvaluationFailure) {
  PoseMap map;
  map.terms.push_back(
      {0, 0, std::make_shared<Eigen::VectorXd>(Eigen::VectorXd::Zero(1))});
  const BearingCost cost(map, 0.0, 0.01);
  const double b[1] = {0.0};
  const double l[2] = {0.0, 0.0};
  const double* parameters[2] = {b, l};
  double r;
  EXPECT_FALSE(cost.Evaluate(parameters, &r, nullptr));
}

}  // namespace
}  // namespace rff
