#include "rff_ceres/initialization.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "gtest/gtest.h"
#include "rff_ceres/feature_trajectory.h"
#include "rff_ceres/mean/mean_function.h"
#include "rff_ceres/se2.h"

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

}  // namespace
}  // namespace rff
