#include "rff_ceres/initialization.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "ceres/problem.h"
#include "ceres/solver.h"
#include "gtest/gtest.h"
#include "rff_ceres/feature_trajectory.h"
#include "rff_ceres/mean/mean_function.h"
#include "rff_ceres/se2.h"
#include "rff_ceres/simulate.h"

namespace rff {
namespace {

// A robot that turns at 0.3 rad/s for 100 s: its recorded headings wrap
// about five times. The fit follows the turn (the heading residual wraps, so
// a fit aimed at the wrapped values from a constant mean would turn the
// wrong way wherever the target is more than pi away).
TEST(FitModelToPosesTest, FollowsAHeadingThatWindsPastPi) {
  std::vector<TimedPose> poses;
  for (int k = 0; k <= 100; ++k) {
    const double t = k;
    poses.push_back({t, 5.0 * std::cos(0.1 * t), 5.0 * std::sin(0.1 * t),
                     WrapAngle(0.3 * t)});
  }
  FeatureTrajectoryOptions options;
  options.position_kernel = {"rbf", 25.0, 10.0};
  options.heading_kernel = {"rbf", 400.0, 10.0};
  std::string error;
  std::unique_ptr<FeatureTrajectory> model = FeatureTrajectory::Create(
      options,
      std::make_shared<PiecewiseLinearMean>(std::vector<TimedPose>{poses[0]}),
      0.0, 100.0, &error);
  ASSERT_TRUE(model) << error;
  ASSERT_TRUE(FitModelToPoses(poses, model.get(), &error)) << error;
  double largest_heading_miss = 0.0, largest_position_miss = 0.0;
  for (const TimedPose& p : poses) {
    const Eigen::Vector3d fitted = model->Pose(p.t);
    largest_heading_miss = std::max(largest_heading_miss,
                                    std::abs(WrapAngle(fitted.z() - p.theta)));
    largest_position_miss = std::max(
        largest_position_miss, std::hypot(fitted.x() - p.x, fitted.y() - p.y));
  }
  EXPECT_LT(largest_heading_miss, 0.05);
  EXPECT_LT(largest_position_miss, 0.05);
  // The fitted heading is continuous: it has turned by 30 rad at the end.
  EXPECT_NEAR(model->Pose(100.0).z() - model->Pose(0.0).z(), 30.0, 0.05);
}

// Windowed weights are fitted on their envelope (BANDED_CHOLESKY): the same
// MAP as Ceres's sparse Cholesky of the same costs, to the fit's own
// tolerances (a thousandth of its sigmas; they stop it at about 1e-5 m).
TEST(FitModelToPosesTest, WindowedFitIsCeresMap) {
  std::vector<TimedPose> poses;
  for (int k = 0; k <= 200; ++k) {
    const double t = 0.5 * k;
    poses.push_back({t, 3.0 * std::sin(0.05 * t) + 0.1 * t,
                     2.0 * std::cos(0.07 * t), 0.2 * std::sin(0.03 * t)});
  }
  FeatureTrajectoryOptions options;
  options.position_kernel = {"rbf", 8.0, 4.0};
  options.heading_kernel = {"rbf", 20.0, 1.0};
  options.num_position_features = 12;
  options.num_heading_features = 6;
  options.segment_length = 30.0;
  options.segment_overlap = 10.0;
  const auto mean =
      std::make_shared<PiecewiseLinearMean>(std::vector<TimedPose>{poses[0]});
  std::string error;
  std::unique_ptr<FeatureTrajectory> fitted =
      FeatureTrajectory::Create(options, mean, 0.0, 100.0, &error);
  std::unique_ptr<FeatureTrajectory> reference =
      FeatureTrajectory::Create(options, mean, 0.0, 100.0, &error);
  ASSERT_TRUE(fitted && reference) << error;
  ASSERT_GT(fitted->num_blocks(), 3);
  ASSERT_TRUE(FitModelToPoses(poses, fitted.get(), &error)) << error;

  ceres::Problem problem;
  AddPoseFitCosts(poses, reference.get(), &problem);
  ceres::Solver::Options ceres_options;
  ceres_options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  ceres_options.function_tolerance = 1e-14;
  ceres_options.gradient_tolerance = 1e-14;
  ceres_options.parameter_tolerance = 1e-14;
  ceres::Solver::Summary summary;
  ceres::Solve(ceres_options, &problem, &summary);
  ASSERT_TRUE(summary.IsSolutionUsable()) << summary.message;
  for (const TimedPose& p : poses) {
    EXPECT_NEAR((fitted->Pose(p.t) - reference->Pose(p.t)).norm(), 0.0, 5e-5)
        << "t = " << p.t;
  }
}

// A simulated run whose start carries two PRIOR_POSEs, both turned by 90
// degrees, with heading sigmas `sigma_a` and `sigma_b`.
Dataset TwoStartPriors(double sigma_a, double sigma_b) {
  SimulationOptions sim = PaperOptions(31);
  sim.landmark_prior_sigma = 1.0;
  Dataset dataset;
  std::string error;
  EXPECT_TRUE(Simulate(sim, &dataset, &error)) << error;
  PosePrior& start = EarliestPosePrior(&dataset);
  start.pose.theta = WrapAngle(start.pose.theta + 0.5 * M_PI);
  start.sigma_theta = sigma_a;
  PosePrior second = start;
  second.sigma_theta = sigma_b;
  dataset.pose_priors.push_back(second);
  return dataset;
}

// Every PRIOR_POSE at the start is turned to the heading found: one left
// would hold the start at the heading the search corrected.
TEST(ResolveStartHeadingTest, TurnsEveryPriorAtTheStart) {
  const Dataset dataset = TwoStartPriors(M_PI, M_PI);
  StartHeading report;
  const Dataset resolved = ResolveStartHeading(dataset, &report);
  ASSERT_TRUE(report.resolved);
  const double truth = dataset.ground_truth.front().theta;
  EXPECT_LT(std::abs(WrapAngle(report.heading - truth)), 0.1);
  ASSERT_EQ(resolved.pose_priors.size(), dataset.pose_priors.size());
  EXPECT_EQ(resolved.pose_priors.front().pose.theta, report.heading);
  EXPECT_EQ(resolved.pose_priors.back().pose.theta, report.heading);
}

// A tight prior beside a loose one at the start fixes the heading: nothing
// is searched or turned.
TEST(ResolveStartHeadingTest, ATightPriorAtTheStartKeepsItsHeading) {
  const Dataset dataset = TwoStartPriors(M_PI, 0.01);
  StartHeading report;
  const Dataset resolved = ResolveStartHeading(dataset, &report);
  EXPECT_FALSE(report.resolved);
  for (std::size_t k = 0; k < dataset.pose_priors.size(); ++k) {
    EXPECT_EQ(resolved.pose_priors[k].pose.theta,
              dataset.pose_priors[k].pose.theta);
  }
}

}  // namespace
}  // namespace rff
