#include "costs/range_cost.h"

#include "test/costs/cost_test_util.h"

namespace rff {
namespace {

using testing::PoseOf;

struct RangeAutoDiff {
  PoseMap map;
  double range, sigma;
  int landmark_block;
  template <typename T>
  bool operator()(T const* const* p, T* r) const {
    const auto pose = PoseOf(map, p);
    const auto [dx, dy] = testing::LandmarkOffset(pose, p[landmark_block]);
    r[0] = (sqrt(dx * dx + dy * dy) - range) / sigma;
    return true;
  }
};

TEST(RangeCostTest, AnalyticJacobianMatchesAutoDiff) {
  std::mt19937 rng(1);
  for (int trial = 0; trial < 20; ++trial) {
    const PoseMap map = testing::RandomPoseMap(&rng);
    const RangeCost cost(map, 4.2, 0.7);
    auto autodiff =
        testing::MakeAutoDiff(new RangeAutoDiff{map, 4.2, 0.7, 3}, cost);
    auto parameters =
        testing::RandomParameters(cost.parameter_block_sizes(), &rng);
    parameters[3] = {8.0 + trial, -5.0 + 0.3 * trial};
    testing::ExpectSameCost(cost, *autodiff, parameters);
  }
}

TEST(RangeCostTest, ResidualIsScaledDistanceError) {
  // One block, pose = mean + phi * b with phi = (1), b = 0: pose (1, 2).
  PoseMap map;
  map.mean << 1.0, 2.0, 0.3;
  map.terms.push_back(
      {0, 0, std::make_shared<Eigen::VectorXd>(Eigen::VectorXd::Ones(1))});
  const RangeCost cost(map, 4.0, 0.5);
  const double b[1] = {0.0};
  const double l[2] = {4.0, 6.0};  // Distance 5.
  const double* parameters[2] = {b, l};
  double r;
  ASSERT_TRUE(cost.Evaluate(parameters, &r, nullptr));
  EXPECT_DOUBLE_EQ(r, (5.0 - 4.0) / 0.5);
}

}  // namespace
}  // namespace rff
