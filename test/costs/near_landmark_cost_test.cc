#include "costs/near_landmark_cost.h"

#include <cmath>

#include "test/costs/cost_test_util.h"

namespace rff {
namespace {

using testing::PoseOf;

struct NearLandmarkAutoDiff {
  PoseMap map;
  double range, bearing, sigma_range, sigma_bearing, stated_sigma_range;
  int landmark_block;
  template <typename T>
  bool operator()(T const* const* p, T* r) const {
    const auto pose = PoseOf(map, p);
    const auto [dx, dy] = testing::LandmarkOffset(pose, p[landmark_block]);
    // The landmark in the robot's frame, then along and across the ray.
    const T forward = cos(pose[2]) * dx + sin(pose[2]) * dy;
    const T left = -sin(pose[2]) * dx + cos(pose[2]) * dy;
    const double c = std::cos(bearing), s = std::sin(bearing);
    const double across =
        std::sqrt(range * range + stated_sigma_range * stated_sigma_range) *
        sigma_bearing;
    r[0] = (c * forward + s * left - range) / sigma_range;
    r[1] = (-s * forward + c * left) / across;
    return true;
  }
};

TEST(NearLandmarkCostTest, AnalyticJacobianMatchesAutoDiff) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const PoseMap map = testing::RandomPoseMap(&rng);
    const double range = 0.1 * trial - 0.5;  // Negative ones too.
    const NearLandmarkCost cost(map, range, -2.0, 0.3, 0.05, 0.4);
    auto autodiff = testing::MakeAutoDiff(
        new NearLandmarkAutoDiff{map, range, -2.0, 0.3, 0.05, 0.4, 3}, cost);
    auto parameters =
        testing::RandomParameters(cost.parameter_block_sizes(), &rng);
    testing::ExpectSameCost(cost, *autodiff, parameters);
  }
}

TEST(NearLandmarkCostTest, IsSmoothWhereTheLandmarkMeetsTheRobot) {
  // Pose (1, 2, pi/2) through the map's mean alone; landmark on the robot;
  // measured 0.2 m straight ahead.
  PoseMap map;
  map.mean << 1.0, 2.0, M_PI / 2;
  const NearLandmarkCost cost(map, 0.2, 0.0, 0.5, 0.1, 0.5);
  const double landmark[2] = {1.0, 2.0};
  const double* parameters[] = {landmark};
  double residuals[2];
  double landmark_jacobian[4];
  double* jacobians[] = {landmark_jacobian};
  ASSERT_TRUE(cost.Evaluate(parameters, residuals, jacobians));
  // Along the ray: (0 - 0.2) / 0.5; across: 0.
  EXPECT_NEAR(residuals[0], -0.4, 1e-12);
  EXPECT_NEAR(residuals[1], 0.0, 1e-12);
  // Finite: R(pi/2)^T, scaled by 1 / 0.5 along the ray and by
  // 1 / (hypot(0.2, 0.5) 0.1) across it.
  const double across = 1.0 / (std::hypot(0.2, 0.5) * 0.1);
  EXPECT_NEAR(landmark_jacobian[0], 0.0, 1e-12);
  EXPECT_NEAR(landmark_jacobian[1], 2.0, 1e-12);
  EXPECT_NEAR(landmark_jacobian[2], -across, 1e-9);
  EXPECT_NEAR(landmark_jacobian[3], 0.0, 1e-12);
}

}  // namespace
}  // namespace rff
