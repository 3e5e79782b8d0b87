// A cost given new weights in place is the cost its constructor builds with
// them, bit for bit: a learning round's rescale then solves the problem a
// rebuild would.
#include <random>

#include "costs/calibrated_odometry_cost.h"
#include "costs/calibrated_range_cost.h"
#include "costs/near_landmark_cost.h"
#include "costs/wnoa_prior_cost.h"
#include "test/costs/cost_test_util.h"

namespace rff {
namespace {

constexpr double kExact = 0.0;

// Random values, the landmark block (after the pose blocks) kept away from
// the pose, the calibration (last, when there is one) near one.
std::vector<std::vector<double>> Parameters(const ceres::CostFunction& cost,
                                            int landmark, int calibration,
                                            std::mt19937* rng) {
  auto parameters =
      testing::RandomParameters(cost.parameter_block_sizes(), rng);
  if (landmark >= 0) parameters[landmark] = {4.0, 3.0};
  if (calibration >= 0) parameters[calibration] = {1.05, 0.97};
  return parameters;
}

TEST(NoiseWeightedTest, ObservationCostsTakeSigmasAsTheirConstructors) {
  std::mt19937 rng(11);
  const PoseMap map = testing::RandomPoseMap(&rng);
  const double sr = 0.3 * 0.7, sb = 0.02 * 1.9;  // The new sigmas.
  {
    RangeCost cost(map, 5.0, 0.3);
    cost.SetSigmas(sr, sb);
    testing::ExpectSameCost(cost, RangeCost(map, 5.0, sr),
                            Parameters(cost, 3, -1, &rng), kExact);
  }
  {
    BearingCost cost(map, 0.4, 0.02);
    cost.SetSigmas(sr, sb);
    testing::ExpectSameCost(cost, BearingCost(map, 0.4, sb),
                            Parameters(cost, 3, -1, &rng), kExact);
  }
  {
    RangeBearingCost cost(map, 5.0, 0.4, 0.3, 0.02);
    cost.SetSigmas(sr, sb);
    testing::ExpectSameCost(cost, RangeBearingCost(map, 5.0, 0.4, sr, sb),
                            Parameters(cost, 3, -1, &rng), kExact);
  }
  {
    CalibratedRangeCost cost(map, 5.0, 0.3);
    cost.SetSigmas(sr, sb);
    testing::ExpectSameCost(cost, CalibratedRangeCost(map, 5.0, sr),
                            Parameters(cost, 3, 4, &rng), kExact);
  }
  {
    CalibratedRangeBearingCost cost(map, 5.0, 0.4, 0.3, 0.02);
    cost.SetSigmas(sr, sb);
    testing::ExpectSameCost(cost,
                            CalibratedRangeBearingCost(map, 5.0, 0.4, sr, sb),
                            Parameters(cost, 3, 4, &rng), kExact);
  }
  {
    // The across-ray distance scale stays the stated sigma's.
    NearLandmarkCost cost(map, 0.2, 0.4, 0.3, 0.02, 0.3);
    cost.SetSigmas(sr, sb);
    testing::ExpectSameCost(cost, NearLandmarkCost(map, 0.2, 0.4, sr, sb, 0.3),
                            Parameters(cost, 3, -1, &rng), kExact);
  }
}

TEST(NoiseWeightedTest, OdometryCostsTakeSqrtInformationAsTheirConstructors) {
  std::mt19937 rng(12);
  const PoseMap map0 = testing::RandomPoseMap(&rng);
  const PoseMap map1 = testing::RandomPoseMap(&rng);
  const Eigen::Vector3d motion(0.5, -0.1, 0.2);
  Eigen::Matrix3d stated;
  stated << 20.0, 1.0, 0.0, 0.0, 18.0, 2.0, 0.0, 0.0, 40.0;
  const Eigen::Matrix3d scaled = stated / 0.6;
  {
    OdometryCost cost(map0, map1, motion, stated);
    cost.SetSqrtInformation(scaled);
    testing::ExpectSameCost(cost, OdometryCost(map0, map1, motion, scaled),
                            Parameters(cost, -1, -1, &rng), kExact);
  }
  {
    CalibratedOdometryCost cost(map0, map1, motion, stated);
    cost.SetSqrtInformation(scaled);
    const int calibration =
        static_cast<int>(cost.parameter_block_sizes().size()) - 1;
    testing::ExpectSameCost(cost,
                            CalibratedOdometryCost(map0, map1, motion, scaled),
                            Parameters(cost, -1, calibration, &rng), kExact);
  }
}

TEST(NoiseWeightedTest, WnoaPriorTakesQcAsItsConstructor) {
  std::mt19937 rng(13);
  WnoaPriorCost cost(0.37, 1.0, 1.0, 0.1);
  cost.SetQc(0.03, 0.03, 2.5e-4);
  const WnoaPriorCost fresh(0.37, 0.03, 0.03, 2.5e-4);
  testing::ExpectSameCost(cost, fresh, Parameters(cost, -1, -1, &rng), kExact);
  EXPECT_TRUE(cost.sqrt_information() == fresh.sqrt_information());
}

}  // namespace
}  // namespace rff
