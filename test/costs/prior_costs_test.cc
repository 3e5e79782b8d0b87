#include "costs/landmark_prior_cost.h"
#include "costs/pose_prior_cost.h"
#include "costs/weight_prior_cost.h"
#include "test/costs/cost_test_util.h"

namespace rff {
namespace {

using testing::PoseOf;
using testing::Wrap;

struct PosePriorAutoDiff {
  PoseMap map;
  Eigen::Vector3d prior, sigma;
  template <typename T>
  bool operator()(T const* const* p, T* r) const {
    const auto pose = PoseOf(map, p);
    r[0] = (pose[0] - prior.x()) / sigma.x();
    r[1] = (pose[1] - prior.y()) / sigma.y();
    r[2] = Wrap(T(pose[2] - prior.z())) / sigma.z();
    return true;
  }
};

TEST(PosePriorCostTest, AnalyticJacobianMatchesAutoDiff) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 10; ++trial) {
    const PoseMap map = testing::RandomPoseMap(&rng);
    const Eigen::Vector3d prior(1.0, -2.0, 3.1), sigma(0.1, 0.1, 0.01);
    const PosePriorCost cost(map, prior, sigma);
    auto autodiff =
        testing::MakeAutoDiff(new PosePriorAutoDiff{map, prior, sigma}, cost);
    testing::ExpectSameCost(
        cost, *autodiff,
        testing::RandomParameters(cost.parameter_block_sizes(), &rng));
  }
}

TEST(LandmarkPriorCostTest, ResidualAndJacobian) {
  const LandmarkPriorCost cost(Eigen::Vector2d(1.0, 2.0), 0.5);
  const double l[2] = {2.0, 1.0};
  const double* parameters[1] = {l};
  double r[2], j[4];
  double* jacobians[1] = {j};
  ASSERT_TRUE(cost.Evaluate(parameters, r, jacobians));
  EXPECT_DOUBLE_EQ(r[0], 2.0);
  EXPECT_DOUBLE_EQ(r[1], -2.0);
  EXPECT_DOUBLE_EQ(j[0], 2.0);
  EXPECT_DOUBLE_EQ(j[1], 0.0);
  EXPECT_DOUBLE_EQ(j[2], 0.0);
  EXPECT_DOUBLE_EQ(j[3], 2.0);
}

TEST(WeightPriorCostTest, ResidualIsTheWeightsAndJacobianIdentity) {
  const WeightPriorCost cost(3);
  const double b[3] = {0.5, -1.0, 2.0};
  const double* parameters[1] = {b};
  double r[3], j[9];
  double* jacobians[1] = {j};
  ASSERT_TRUE(cost.Evaluate(parameters, r, jacobians));
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(r[i], b[i]);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(j[3 * i + k], i == k ? 1.0 : 0.0);
  }
}

}  // namespace
}  // namespace rff
