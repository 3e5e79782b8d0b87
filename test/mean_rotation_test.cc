#include "rff_ceres/mean_rotation.h"

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "Eigen/Geometry"
#include "costs/wnoa_prior_cost.h"
#include "gtest/gtest.h"
#include "rff_ceres/feature_trajectory.h"
#include "rff_ceres/metrics.h"
#include "rff_ceres/simulate.h"
#include "rff_ceres/slam_solver.h"
#include "rff_ceres/wnoa_trajectory.h"

namespace rff {
namespace {

// A curved mean: the rotation's arm changes along the run.
class ArcMean : public MeanFunction {
 public:
  Eigen::Vector3d Evaluate(double t) const override {
    return Eigen::Vector3d(3.0 + 5.0 * std::sin(0.1 * t),
                           -1.0 + 5.0 * (1.0 - std::cos(0.1 * t)), 0.1 * t);
  }
};

std::unique_ptr<MeanRotationTrajectory> MakeModel(double sigma) {
  std::string error;
  auto mean = std::make_shared<ArcMean>();
  std::unique_ptr<TrajectoryModel> inner =
      WnoaTrajectory::Create(WnoaOptions(), mean, {0.0, 10.0, 20.0}, &error);
  EXPECT_NE(inner, nullptr) << error;
  return std::make_unique<MeanRotationTrajectory>(std::move(inner), mean,
                                                  /*anchor_time=*/0.0, sigma);
}

// pose(t) = inner(t) + delta (-(m_y - a_y), m_x - a_x, 1): the first-order
// rotation of the mean about its value at the anchor time.
TEST(MeanRotationTest, DeltaTurnsTheMeanToFirstOrder) {
  std::unique_ptr<MeanRotationTrajectory> model = MakeModel(0.5);
  ASSERT_EQ(model->num_blocks(), 4);
  EXPECT_EQ(model->block_size(0), 1);
  EXPECT_EQ(model->block_size(1), 6);
  model->mutable_block(2)[0] = 0.3;  // Inner state 1, x deviation.
  const Eigen::Vector3d before = model->Pose(5.0);
  *model->mutable_block(0) = 0.02;
  const Eigen::Vector3d after = model->Pose(5.0);
  const ArcMean mean;
  const Eigen::Vector3d arm = mean.Evaluate(5.0) - mean.Evaluate(0.0);
  EXPECT_NEAR(after.x() - before.x(), -0.02 * arm.y(), 1e-12);
  EXPECT_NEAR(after.y() - before.y(), 0.02 * arm.x(), 1e-12);
  EXPECT_NEAR(after.z() - before.z(), 0.02, 1e-12);
  // At the anchor the position does not move.
  EXPECT_NEAR(model->Pose(0.0).x(), mean.Evaluate(0.0).x(), 1e-12);
}

// More modes of a rotated feature model: the inner model's, turned by the
// same delta (the wrapper's first block), so the poses are this model's;
// WNOA states have no basis to extend.
TEST(MeanRotationTest, MoreModesKeepTheRotation) {
  std::string error;
  auto mean = std::make_shared<ArcMean>();
  FeatureTrajectoryOptions options;
  options.num_position_features = 10;
  options.num_heading_features = 10;
  auto inner = FeatureTrajectory::Create(options, mean, 0.0, 30.0, &error);
  ASSERT_NE(inner, nullptr) << error;
  inner->mutable_block(0)[3] = 0.4;
  MeanRotationTrajectory model(std::move(inner), mean, 0.0, 0.5);
  *model.mutable_block(0) = 0.03;
  const std::unique_ptr<TrajectoryModel> wider =
      model.WithMoreModes(0.05, 4, &error);
  ASSERT_NE(wider, nullptr) << error;
  ASSERT_EQ(wider->num_blocks(), model.num_blocks());
  EXPECT_EQ(*wider->block(0), 0.03);
  EXPECT_GT(wider->block_size(1), model.block_size(1));
  for (double t = 0.0; t <= 30.0; t += 2.5) {
    EXPECT_LT((wider->Pose(t) - model.Pose(t)).norm(), 1e-12) << t;
  }
  EXPECT_EQ(MakeModel(0.5)->WithMoreModes(0.05, 4, &error), nullptr);
  EXPECT_EQ(error, "the model has no basis to extend");
}

// Folding applies the exact rotation: poses change by the second-order
// part only, which LinearizationError bounds, and delta becomes zero.
TEST(MeanRotationTest, FoldingAppliesTheExactRotation) {
  std::unique_ptr<MeanRotationTrajectory> model = MakeModel(0.5);
  const double delta = 0.2;
  *model->mutable_block(0) = delta;
  const std::vector<double> times = {0.0, 4.0, 12.0, 20.0};
  const double bound = model->LinearizationError(times);
  std::vector<Eigen::Vector3d> linear;
  for (const double t : times) linear.push_back(model->Pose(t));
  model->FoldRotation();
  EXPECT_EQ(model->delta(), 0.0);
  const ArcMean mean;
  const Eigen::Vector2d anchor = mean.Evaluate(0.0).head<2>();
  double largest = 0.0;
  for (std::size_t k = 0; k < times.size(); ++k) {
    const Eigen::Vector3d m = mean.Evaluate(times[k]);
    const Eigen::Vector3d exact = model->Pose(times[k]);
    const Eigen::Vector2d rotated =
        anchor + Eigen::Rotation2Dd(delta) * (m.head<2>() - anchor);
    EXPECT_NEAR(exact.x(), rotated.x(), 1e-12);
    EXPECT_NEAR(exact.y(), rotated.y(), 1e-12);
    EXPECT_NEAR(exact.z(), m.z() + delta, 1e-12);
    largest = std::max(largest, (exact - linear[k]).head<2>().norm());
  }
  EXPECT_NEAR(largest, bound, 1e-12);
  EXPECT_GT(bound, 0.01);
}

TEST(MeanRotationTest, OnlyTheInnerPriorIsRescaledAndDeltaIsShared) {
  std::unique_ptr<MeanRotationTrajectory> model = MakeModel(0.5);
  using Scale = TrajectoryModel::PriorScale;
  EXPECT_EQ(model->PriorRowScales({model->mutable_block(0)}, 1),
            std::vector<Scale>{Scale::kNone});
  EXPECT_EQ(model->PriorRowScales(
                {model->mutable_block(1), model->mutable_block(2)}, 6),
            (std::vector<Scale>{Scale::kPosition, Scale::kPosition,
                                Scale::kHeading, Scale::kPosition,
                                Scale::kPosition, Scale::kHeading}));
  EXPECT_TRUE(model->IsSharedBlock(0));
  EXPECT_FALSE(model->IsSharedBlock(1));
}

// Simulated runs whose start heading prior is turned by 90 degrees and
// made uninformative (sigma pi): the solve resolves the heading, turns the
// dead-reckoning mean and ends as accurate as with the true start heading
// known to 1 mrad, over three seeds (one run varies by 15% either way with
// the learned noise scales). Measured: 0.212 m known, 0.224 m unknown (WNOA
// and RFF alike); before the rotation block a turned run ended at 0.54 m.
// The prior costs a problem holds follow the inner model's scales: a
// motion prior built with other densities becomes the inner model's own.
TEST(MeanRotationTest, PriorCostsFollowTheInnerModel) {
  std::unique_ptr<MeanRotationTrajectory> model = MakeModel(0.5);
  const WnoaOptions inner;  // MakeModel's.
  WnoaPriorCost cost(10.0, 5.0, 5.0, 3.0);
  model->UpdatePriorCosts({&cost});
  const WnoaPriorCost expected(10.0, inner.position_qc, inner.position_qc,
                               inner.heading_qc);
  EXPECT_TRUE(cost.sqrt_information() == expected.sqrt_information());
}

TEST(MeanRotationTest, UnknownStartHeadingSolvesLikeAKnownOne) {
  std::vector<Dataset> known, turned;
  for (const int seed : {31, 32, 33}) {
    SimulationOptions sim = PaperOptions(seed);
    sim.landmark_prior_sigma = 1.0;
    std::string error;
    known.emplace_back();
    ASSERT_TRUE(Simulate(sim, &known.back(), &error)) << error;
    turned.push_back(known.back());
    PosePrior& start = EarliestPosePrior(&turned.back());
    start.pose.theta = WrapAngle(start.pose.theta + 0.5 * M_PI);
    start.sigma_theta = M_PI;
  }
  for (const std::string prior : {"wnoa", "rff"}) {
    SlamOptions options;
    options.prior = prior;
    double ape[2] = {0.0, 0.0};  // Mean over the seeds.
    for (int k = 0; k < 2; ++k) {
      for (const Dataset& dataset : k == 0 ? known : turned) {
        SlamResult result;
        std::string error;
        ASSERT_TRUE(RunSlam(dataset, options, &result, &error)) << error;
        Evaluation evaluation;
        ASSERT_TRUE(Evaluate(dataset.ground_truth,
                             dataset.ground_truth_landmarks, result.trajectory,
                             nullptr, EvaluationOptions(), &evaluation, &error))
            << error;
        ape[k] += evaluation.ape_translation.rms / known.size();
      }
    }
    std::printf("%s: known start heading %.4f m, unknown %.4f m\n",
                prior.c_str(), ape[0], ape[1]);
    EXPECT_LT(ape[1], 1.1 * ape[0] + 0.01) << prior;
    EXPECT_LT(ape[0], 0.5) << prior;
  }
}

}  // namespace
}  // namespace rff
