#include "costs/near_landmark_cost.h"

#include "test/costs/cost_test_util.h"

namespace rff {
namespace {

using testing::PoseOf;

struct NearLandmarkAutoDiff {
  PoseMap map;
  double range, bearing, sigma_range;
  int landmark_block;
  template <typename T>
  bool operator()(T const* const* p, T* r) const {
    const auto pose = PoseOf(map, p);
    const auto [dx, dy] = testing::LandmarkOffset(pose, p[landmark_block]);
    // The landmark in the robot's frame against the measured point.
    const T forward = cos(pose[2]) * dx + sin(pose[2]) * dy;
    const T left = -sin(pose[2]) * dx + cos(pose[2]) * dy;
    r[0] = (forward - range * std::cos(bearing)) / sigma_range;
    r[1] = (left - range * std::sin(bearing)) / sigma_range;
    return true;
  }
};

TEST(NearLandmarkCostTest, AnalyticJacobianMatchesAutoDiff) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const PoseMap map = testing::RandomPoseMap(&rng);
    const NearLandmarkCost cost(map, 0.15, -2.0, 0.3);
    auto autodiff = testing::MakeAutoDiff(
        new NearLandmarkAutoDiff{map, 0.15, -2.0, 0.3, 3}, cost);
    auto parameters =
        testing::RandomParameters(cost.parameter_block_sizes(), &rng);
    testing::ExpectSameCost(cost, *autodiff, parameters);
  }
}

TEST(NearLandmarkCostTest, IsSmoothWhereTheLandmarkMeetsTheRobot) {
  // Pose (1, 2, pi/2) through the map's mean alone; landmark on the robot.
  PoseMap map;
  map.mean << 1.0, 2.0, M_PI / 2;
  const NearLandmarkCost cost(map, 0.2, 0.0, 0.5);
  const double landmark[2] = {1.0, 2.0};
  const double* parameters[] = {landmark};
  double residuals[2];
  double landmark_jacobian[4];
  double* jacobians[] = {landmark_jacobian};
  ASSERT_TRUE(cost.Evaluate(parameters, residuals, jacobians));
  // q = 0 against the measured point 0.2 m ahead.
  EXPECT_NEAR(residuals[0], -0.4, 1e-12);
  EXPECT_NEAR(residuals[1], 0.0, 1e-12);
  // R(pi/2)^T / sigma: finite, of norm 2 in each row.
  EXPECT_NEAR(landmark_jacobian[0], 0.0, 1e-12);
  EXPECT_NEAR(landmark_jacobian[1], 2.0, 1e-12);
  EXPECT_NEAR(landmark_jacobian[2], -2.0, 1e-12);
  EXPECT_NEAR(landmark_jacobian[3], 0.0, 1e-12);
}

}  // namespace
}  // namespace rff
