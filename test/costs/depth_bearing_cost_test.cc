#include "costs/depth_bearing_cost.h"

#include <cmath>

#include "costs/calibrated_range_cost.h"
#include "test/costs/cost_test_util.h"

namespace rff {
namespace {

using testing::PoseOf;
using testing::Wrap;

// Independent twin: the depth as distance times the cosine of the bearing,
// (s |l - p| cos(b) + o - z_d) / sigma_d, then the bearing row.
struct DepthBearingAutoDiff {
  PoseMap map;
  double depth, bearing, sigma_depth, sigma_bearing;
  int landmark_block;
  bool calibrated;
  template <typename T>
  bool operator()(T const* const* p, T* r) const {
    const auto pose = PoseOf(map, p);
    const auto [dx, dy] = testing::LandmarkOffset(pose, p[landmark_block]);
    const T seen = atan2(dy, dx) - pose[2];
    T predicted = sqrt(dx * dx + dy * dy) * cos(seen);
    if (calibrated) {
      const T* c = p[landmark_block + 1];
      predicted = c[0] * predicted + c[1];
    }
    r[0] = (predicted - depth) / sigma_depth;
    r[1] = Wrap(T(seen - bearing)) / sigma_bearing;
    return true;
  }
};

TEST(DepthBearingCostTest, AnalyticJacobianMatchesAutoDiff) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    const PoseMap map = testing::RandomPoseMap(&rng);
    const double bearing = -2.5 + 0.25 * trial;
    const DepthBearingCost cost(map, 4.0, bearing, 0.3, 0.02);
    auto autodiff = testing::MakeAutoDiff(
        new DepthBearingAutoDiff{map, 4.0, bearing, 0.3, 0.02, 3, false}, cost);
    auto parameters =
        testing::RandomParameters(cost.parameter_block_sizes(), &rng);
    parameters[3] = {5.0 - trial, 4.0 + 0.5 * trial};
    testing::ExpectSameCost(cost, *autodiff, parameters);
  }
}

TEST(DepthBearingCostTest, CalibratedJacobianMatchesAutoDiff) {
  std::mt19937 rng(9);
  for (int trial = 0; trial < 20; ++trial) {
    const PoseMap map = testing::RandomPoseMap(&rng);
    const double bearing = 1.2 - 0.1 * trial;
    const CalibratedDepthBearingCost cost(map, 3.5, bearing, 0.3, 0.02);
    auto autodiff = testing::MakeAutoDiff(
        new DepthBearingAutoDiff{map, 3.5, bearing, 0.3, 0.02, 3, true}, cost);
    auto parameters =
        testing::RandomParameters(cost.parameter_block_sizes(), &rng);
    parameters[3] = {6.0 - trial, 3.0 + 0.3 * trial};
    parameters[4] = {1.0 + 0.01 * trial, 0.2 - 0.03 * trial};
    testing::ExpectSameCost(cost, *autodiff, parameters);
  }
}

TEST(DepthBearingCostTest, ResidualIsTheDepthAlongTheHeading) {
  // Pose (1, 2) heading 0.3; landmark (4, 6) at distance 5, depth
  // 3 cos(0.3) + 4 sin(0.3) against a reading of 4.5.
  PoseMap map;
  map.mean << 1.0, 2.0, 0.3;
  map.terms.push_back(
      {0, 0, std::make_shared<Eigen::VectorXd>(Eigen::VectorXd::Ones(1))});
  const double bearing = std::atan2(4.0, 3.0) - 0.3;
  const DepthBearingCost cost(map, 4.5, bearing, 0.5, 0.02);
  const double b[1] = {0.0};
  const double l[2] = {4.0, 6.0};
  const double* parameters[2] = {b, l};
  double r[2];
  ASSERT_TRUE(cost.Evaluate(parameters, r, nullptr));
  const double depth = 3.0 * std::cos(0.3) + 4.0 * std::sin(0.3);
  EXPECT_NEAR(depth, 5.0 * std::cos(bearing), 1e-12);
  EXPECT_NEAR(r[0], (depth - 4.5) / 0.5, 1e-12);
  EXPECT_NEAR(r[1], 0.0, 1e-12);
}

}  // namespace
}  // namespace rff
