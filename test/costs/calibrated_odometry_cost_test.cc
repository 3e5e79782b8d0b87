#include "costs/calibrated_odometry_cost.h"

#include "test/costs/cost_test_util.h"

namespace rff {
namespace {

using testing::PoseOf;
using testing::Wrap;

// Independent twin: L [s dx^ - dx, s dy^ - dy, wrap(w dtheta^ - dtheta)],
// the calibration (s, w) being the last block.
struct CalibratedOdometryAutoDiff {
  PoseMap map0, map1;
  Eigen::Vector3d motion;
  Eigen::Matrix3d sqrt_information;
  int calibration_block;
  template <typename T>
  bool operator()(T const* const* p, T* r) const {
    const auto p0 = PoseOf(map0, p);
    const auto p1 = PoseOf(map1, p);
    const T s = p[calibration_block][0];
    const T w = p[calibration_block][1];
    const T c = cos(p0[2]), sn = sin(p0[2]);
    const T dx = p1[0] - p0[0], dy = p1[1] - p0[1];
    const T turn = Wrap(T(p1[2] - p0[2]));
    const T e[3] = {s * (c * dx + sn * dy) - motion.x(),
                    s * (-sn * dx + c * dy) - motion.y(),
                    Wrap(T(w * turn - motion.z()))};
    testing::Whiten3(sqrt_information, e, r);
    return true;
  }
};

TEST(CalibratedOdometryCostTest, AnalyticJacobianMatchesAutoDiff) {
  std::mt19937 rng(7);
  Eigen::Matrix3d sqrt_information;
  sqrt_information << 20.0, 3.0, -1.0, 0.0, 15.0, 2.0, 0.0, 0.0, 90.0;
  for (int trial = 0; trial < 20; ++trial) {
    const PoseMap map0 = testing::RandomPoseMap(&rng);
    const PoseMap map1 = testing::RandomPoseMap(&rng);
    const Eigen::Vector3d motion(1.0, 0.2, 1.5 - 0.15 * trial);
    const CalibratedOdometryCost cost(map0, map1, motion, sqrt_information);
    const int calibration =
        static_cast<int>(cost.parameter_block_sizes().size()) - 1;
    auto autodiff = testing::MakeAutoDiff(
        new CalibratedOdometryAutoDiff{map0, map1, motion, sqrt_information,
                                       calibration},
        cost);
    auto parameters =
        testing::RandomParameters(cost.parameter_block_sizes(), &rng);
    parameters[calibration] = {0.9 + 0.01 * trial, 1.1 - 0.02 * trial};
    testing::ExpectSameCost(cost, *autodiff, parameters);
  }
}

TEST(CalibratedOdometryCostTest, ScalesTheTrueMotionToTheRecordedOne) {
  // True motion: 2 m forward, a quarter turn left. A sensor that reads 10%
  // long and turns 5% short records (2.2, 0, 0.95 pi / 2): zero residual at
  // c = (1.1, 0.95), and at c = (1, 1) the plain odometry error / sigma.
  auto one = std::make_shared<Eigen::VectorXd>(Eigen::VectorXd::Ones(1));
  PoseMap map0, map1;
  map0.mean << 1.0, 1.0, M_PI / 2;
  map1.mean << 1.0, 3.0, M_PI;
  map0.terms.push_back({0, 0, one});
  map1.terms.push_back({0, 0, one});
  const Eigen::Vector3d recorded(2.2, 0.0, 0.95 * M_PI / 2);
  const CalibratedOdometryCost cost(map0, map1, recorded,
                                    Eigen::Matrix3d::Identity() * 10.0);
  const double b[1] = {0.0};
  double r[3];
  const double matched[2] = {1.1, 0.95};
  const double* at_match[2] = {b, matched};
  ASSERT_TRUE(cost.Evaluate(at_match, r, nullptr));
  EXPECT_NEAR(r[0], 0.0, 1e-12);
  EXPECT_NEAR(r[1], 0.0, 1e-12);
  EXPECT_NEAR(r[2], 0.0, 1e-12);
  const double unit[2] = {1.0, 1.0};
  const double* at_unit[2] = {b, unit};
  ASSERT_TRUE(cost.Evaluate(at_unit, r, nullptr));
  EXPECT_NEAR(r[0], (2.0 - 2.2) * 10.0, 1e-12);
  EXPECT_NEAR(r[1], 0.0, 1e-12);
  EXPECT_NEAR(r[2], 0.05 * M_PI / 2 * 10.0, 1e-12);
}

}  // namespace
}  // namespace rff
