#include "costs/range_bearing_cost.h"

#include "test/costs/cost_test_util.h"

namespace rff {
namespace {

using testing::PoseOf;
using testing::Wrap;

struct RangeBearingAutoDiff {
  PoseMap map;
  double range, bearing, sigma_range, sigma_bearing;
  int landmark_block;
  template <typename T>
  bool operator()(T const* const* p, T* r) const {
    const auto pose = PoseOf(map, p);
    const auto [dx, dy] = testing::LandmarkOffset(pose, p[landmark_block]);
    r[0] = (sqrt(dx * dx + dy * dy) - range) / sigma_range;
    r[1] = Wrap(T(atan2(dy, dx) - pose[2] - bearing)) / sigma_bearing;
    return true;
  }
};

TEST(RangeBearingCostTest, AnalyticJacobianMatchesAutoDiff) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 20; ++trial) {
    const PoseMap map = testing::RandomPoseMap(&rng);
    const RangeBearingCost cost(map, 6.0, 0.4, 0.3, 0.02);
    auto autodiff = testing::MakeAutoDiff(
        new RangeBearingAutoDiff{map, 6.0, 0.4, 0.3, 0.02, 3}, cost);
    auto parameters =
        testing::RandomParameters(cost.parameter_block_sizes(), &rng);
    parameters[3] = {5.0 - trial, 4.0 + 0.5 * trial};
    testing::ExpectSameCost(cost, *autodiff, parameters);
  }
}

}  // namespace
}  // namespace rff
