#include "costs/calibrated_range_cost.h"

#include "costs/diagonal_prior_cost.h"
#include "test/costs/cost_test_util.h"

namespace rff {
namespace {

using testing::PoseOf;

// Independent twin: (s |l - p| + o - z) / sigma.
struct CalibratedRangeAutoDiff {
  PoseMap map;
  double range, sigma;
  int landmark_block;
  template <typename T>
  bool operator()(T const* const* p, T* r) const {
    const auto pose = PoseOf(map, p);
    const auto [dx, dy] = testing::LandmarkOffset(pose, p[landmark_block]);
    const T* calibration = p[landmark_block + 1];
    r[0] = (calibration[0] * sqrt(dx * dx + dy * dy) + calibration[1] - range) /
           sigma;
    return true;
  }
};

// Random blocks for a cost over the random pose map's blocks 0-2, a landmark
// (block 3) and the calibration (block 4), the last two set by `trial`.
std::vector<std::vector<double>> CalibratedParameters(
    const ceres::CostFunction& cost, int trial, std::mt19937* rng) {
  auto parameters =
      testing::RandomParameters(cost.parameter_block_sizes(), rng);
  parameters[3] = {8.0 - trial, 5.0 + 0.2 * trial};
  parameters[4] = {1.0 + 0.01 * trial, 0.3 - 0.05 * trial};
  return parameters;
}

TEST(CalibratedRangeCostTest, AnalyticJacobianMatchesAutoDiff) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 20; ++trial) {
    const PoseMap map = testing::RandomPoseMap(&rng);
    const CalibratedRangeCost cost(map, 6.1, 0.4);
    auto autodiff = testing::MakeAutoDiff(
        new CalibratedRangeAutoDiff{map, 6.1, 0.4, 3}, cost);
    testing::ExpectSameCost(cost, *autodiff,
                            CalibratedParameters(cost, trial, &rng));
  }
}

TEST(CalibratedRangeCostTest, ResidualAppliesScaleAndOffset) {
  // Pose (1, 2) from one block with phi = (1) and b = 0; landmark at
  // distance 5; model 1.1 * 5 + 0.2 = 5.7 against a reading of 5.2.
  PoseMap map;
  map.mean << 1.0, 2.0, 0.0;
  map.terms.push_back(
      {0, 0, std::make_shared<Eigen::VectorXd>(Eigen::VectorXd::Ones(1))});
  const CalibratedRangeCost cost(map, 5.2, 0.5);
  const double b[1] = {0.0};
  const double l[2] = {4.0, 6.0};
  const double c[2] = {1.1, 0.2};
  const double* parameters[3] = {b, l, c};
  double r;
  ASSERT_TRUE(cost.Evaluate(parameters, &r, nullptr));
  EXPECT_NEAR(r, (5.7 - 5.2) / 0.5, 1e-12);
}

// Independent twin: the calibrated range row (the twin above) over the plain
// bearing row.
struct CalibratedRangeBearingAutoDiff {
  PoseMap map;
  double range, bearing, sigma_range, sigma_bearing;
  int landmark_block;
  template <typename T>
  bool operator()(T const* const* p, T* r) const {
    CalibratedRangeAutoDiff{map, range, sigma_range, landmark_block}(p, r);
    const auto pose = PoseOf(map, p);
    const auto [dx, dy] = testing::LandmarkOffset(pose, p[landmark_block]);
    r[1] = testing::Wrap(T(atan2(dy, dx) - pose[2] - bearing)) / sigma_bearing;
    return true;
  }
};

TEST(CalibratedRangeBearingCostTest, AnalyticJacobianMatchesAutoDiff) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const PoseMap map = testing::RandomPoseMap(&rng);
    const double bearing = -2.5 + 0.25 * trial;
    const CalibratedRangeBearingCost cost(map, 6.1, bearing, 0.4, 0.03);
    auto autodiff = testing::MakeAutoDiff(
        new CalibratedRangeBearingAutoDiff{map, 6.1, bearing, 0.4, 0.03, 3},
        cost);
    testing::ExpectSameCost(cost, *autodiff,
                            CalibratedParameters(cost, trial, &rng));
  }
}

TEST(CalibratedRangeBearingCostTest, CalibrationDoesNotTouchTheBearing) {
  // Pose (1, 2, 0.1); landmark at distance 5 on a bearing of
  // atan2(4, 3) - 0.1; model 1.1 * 5 + 0.2 = 5.7 against a reading of 5.2.
  PoseMap map;
  map.mean << 1.0, 2.0, 0.1;
  map.terms.push_back(
      {0, 0, std::make_shared<Eigen::VectorXd>(Eigen::VectorXd::Ones(1))});
  const double true_bearing = std::atan2(4.0, 3.0) - 0.1;
  const CalibratedRangeBearingCost cost(map, 5.2, true_bearing + 0.01, 0.5,
                                        0.02);
  const double b[1] = {0.0};
  const double l[2] = {4.0, 6.0};
  const double c[2] = {1.1, 0.2};
  const double* parameters[3] = {b, l, c};
  double r[2];
  double jb[2], jl[4], jc[4];
  double* jacobians[3] = {jb, jl, jc};
  ASSERT_TRUE(cost.Evaluate(parameters, r, jacobians));
  EXPECT_NEAR(r[0], (5.7 - 5.2) / 0.5, 1e-12);
  EXPECT_NEAR(r[1], -0.01 / 0.02, 1e-12);
  // The bearing row has no calibration Jacobian.
  EXPECT_DOUBLE_EQ(jc[2], 0.0);
  EXPECT_DOUBLE_EQ(jc[3], 0.0);
}

TEST(DiagonalPriorCostTest, ResidualAndJacobian) {
  const DiagonalPriorCost cost(Eigen::Vector2d(1.0, 0.0),
                               Eigen::Vector2d(0.1, 2.0));
  const double x[2] = {1.05, -1.0};
  const double* parameters[1] = {x};
  double r[2];
  double j[4];
  double* jacobians[1] = {j};
  ASSERT_TRUE(cost.Evaluate(parameters, r, jacobians));
  EXPECT_NEAR(r[0], 0.5, 1e-12);
  EXPECT_NEAR(r[1], -0.5, 1e-12);
  EXPECT_DOUBLE_EQ(j[0], 10.0);
  EXPECT_DOUBLE_EQ(j[1], 0.0);
  EXPECT_DOUBLE_EQ(j[2], 0.0);
  EXPECT_DOUBLE_EQ(j[3], 0.5);
}

}  // namespace
}  // namespace rff
