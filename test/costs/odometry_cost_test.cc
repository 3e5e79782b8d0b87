#include "costs/odometry_cost.h"

#include "test/costs/cost_test_util.h"

namespace rff {
namespace {

using testing::PoseOf;
using testing::Wrap;

struct OdometryAutoDiff {
  PoseMap map0, map1;
  Eigen::Vector3d motion;
  Eigen::Matrix3d sqrt_information;
  template <typename T>
  bool operator()(T const* const* p, T* r) const {
    const auto p0 = PoseOf(map0, p);
    const auto p1 = PoseOf(map1, p);
    const T c = cos(p0[2]), s = sin(p0[2]);
    const T dx = p1[0] - p0[0], dy = p1[1] - p0[1];
    const T e[3] = {c * dx + s * dy - motion.x(), -s * dx + c * dy - motion.y(),
                    Wrap(T(p1[2] - p0[2] - motion.z()))};
    testing::Whiten3(sqrt_information, e, r);
    return true;
  }
};

TEST(OdometryCostTest, AnalyticJacobianMatchesAutoDiff) {
  std::mt19937 rng(4);
  for (int trial = 0; trial < 20; ++trial) {
    // Both poses see the same blocks with different features, as two times
    // of one trajectory do.
    const PoseMap map0 = testing::RandomPoseMap(&rng);
    const PoseMap map1 = testing::RandomPoseMap(&rng);
    const Eigen::Vector3d motion(1.0, 0.2, 3.0 - 0.3 * trial);
    const Eigen::Vector3d sigma(0.05, 0.1, 0.01);
    const OdometryCost cost(map0, map1, motion, sigma);
    auto autodiff = testing::MakeAutoDiff(
        new OdometryAutoDiff{
            map0, map1, motion,
            Eigen::Matrix3d(sigma.cwiseInverse().asDiagonal())},
        cost);
    auto parameters =
        testing::RandomParameters(cost.parameter_block_sizes(), &rng);
    testing::ExpectSameCost(cost, *autodiff, parameters);
  }
}

TEST(OdometryCostTest, FullSquareRootInformationMatchesAutoDiff) {
  std::mt19937 rng(14);
  Eigen::Matrix3d sqrt_information;
  sqrt_information << 20.0, 3.0, -1.0, 0.0, 15.0, 2.0, 0.0, 0.0, 90.0;
  for (int trial = 0; trial < 10; ++trial) {
    const PoseMap map0 = testing::RandomPoseMap(&rng);
    const PoseMap map1 = testing::RandomPoseMap(&rng);
    const Eigen::Vector3d motion(2.0, -0.3, 0.2 * trial);
    const OdometryCost cost(map0, map1, motion, sqrt_information);
    auto autodiff = testing::MakeAutoDiff(
        new OdometryAutoDiff{map0, map1, motion, sqrt_information}, cost);
    testing::ExpectSameCost(
        cost, *autodiff,
        testing::RandomParameters(cost.parameter_block_sizes(), &rng));
  }
}

TEST(OdometryCostTest, ExactMotionHasZeroResidual) {
  auto one = std::make_shared<Eigen::VectorXd>(Eigen::VectorXd::Ones(1));
  PoseMap map0, map1;
  map0.mean << 1.0, 1.0, M_PI / 2;  // Facing +y.
  map1.mean << 1.0, 3.0, M_PI;      // Moved 2 m forward, turned left.
  map0.terms.push_back({0, 0, one});
  map1.terms.push_back({0, 0, one});
  const OdometryCost cost(map0, map1, Eigen::Vector3d(2.0, 0.0, M_PI / 2),
                          Eigen::Vector3d(0.1, 0.1, 0.1));
  const double b[1] = {0.0};
  const double* parameters[1] = {b};
  double r[3];
  ASSERT_TRUE(cost.Evaluate(parameters, r, nullptr));
  EXPECT_NEAR(r[0], 0.0, 1e-12);
  EXPECT_NEAR(r[1], 0.0, 1e-12);
  EXPECT_NEAR(r[2], 0.0, 1e-12);
}

}  // namespace
}  // namespace rff
