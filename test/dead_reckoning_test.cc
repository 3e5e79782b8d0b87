#include "rff_ceres/dead_reckoning.h"

#include <cmath>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "rff_ceres/se2.h"

namespace rff {
namespace {

Odometry Odom(double t0, double t1, double dx, double dy, double dtheta) {
  return {t0, t1, dx, dy, dtheta, 0.1, 0.1, 0.01};
}

Observation RangeAt(double t) {
  Observation o;
  o.t = t;
  o.id = 1;
  o.range = 1.0;
  o.sigma_range = 0.1;
  return o;
}

// Four sides of 2 m, each ending with a quarter turn left: back at the start.
Dataset Square() {
  Dataset d;
  d.pose_priors.push_back({{0.0, 1.0, 2.0, 0.5}, 0.1, 0.01});
  for (int k = 0; k < 4; ++k) {
    d.odometry.push_back(Odom(k, k + 1, 2.0, 0.0, M_PI / 2));
  }
  return d;
}

void ExpectPose(const TimedPose& p, double t, double x, double y,
                double theta) {
  EXPECT_NEAR(p.t, t, 1e-12);
  EXPECT_NEAR(p.x, x, 1e-12);
  EXPECT_NEAR(p.y, y, 1e-12);
  EXPECT_NEAR(WrapAngle(p.theta - theta), 0.0, 1e-12) << p.theta;
}

TEST(DeadReckoningTest, SquarePathReturnsToTheStart) {
  Dataset d = Square();
  d.observations.push_back(RangeAt(0.5));
  DeadReckoningResult r;
  std::string error;
  ASSERT_TRUE(DeadReckon(d, {}, &r, &error)) << error;
  ASSERT_EQ(r.poses.size(), 6u);  // Endpoints 0..4 and the observation.
  ExpectPose(r.poses[0], 0.0, 1.0, 2.0, 0.5);
  // (1, 2) + 2 (cos .5, sin .5), heading 0.5 + pi/2.
  ExpectPose(r.poses[2], 1.0, 2.7551651237807455, 2.958851077208406,
             2.0707963267948966);
  // Halfway along the first side, the heading halfway through the turn.
  ExpectPose(r.poses[1], 0.5, 1.8775825618903728, 2.479425538604203,
             0.5 + M_PI / 4);
  ExpectPose(r.poses[5], 4.0, 1.0, 2.0, 0.5);
  EXPECT_EQ(r.odometry_records, 4);
  EXPECT_EQ(r.span_begin, 0.0);
  EXPECT_EQ(r.span_end, 4.0);
  EXPECT_TRUE(r.gaps.empty());
  EXPECT_EQ(r.times_outside_span, 0);
}

TEST(DeadReckoningTest, RecordOrderDoesNotMatter) {
  Dataset d = Square();
  std::swap(d.odometry[0], d.odometry[3]);
  std::swap(d.odometry[1], d.odometry[2]);
  DeadReckoningResult r;
  std::string error;
  ASSERT_TRUE(DeadReckon(d, {}, &r, &error)) << error;
  ASSERT_EQ(r.poses.size(), 5u);
  ExpectPose(r.poses[1], 1.0, 2.7551651237807455, 2.958851077208406,
             2.0707963267948966);
  ExpectPose(r.poses[4], 4.0, 1.0, 2.0, 0.5);
}

TEST(DeadReckoningTest, GapIsAnErrorByDefault) {
  Dataset d;
  d.pose_priors.push_back({{0.0, 0.0, 0.0, 0.0}, 0.1, 0.01});
  d.odometry = {Odom(0, 1, 1, 0, 0), Odom(2, 3, 1, 0, 0),
                Odom(3.5, 4, 1, 0, 0)};
  DeadReckoningResult r;
  std::string error;
  EXPECT_FALSE(DeadReckon(d, {}, &r, &error));
  EXPECT_EQ(error,
            "odometry gap: no ODOM record covers (1, 2) (2 gap(s), 1.5 s in "
            "all); use hold_through_gaps (--hold_through_gaps) to hold the "
            "pose through gaps");
}

TEST(DeadReckoningTest, HoldsThePoseThroughGapsWhenAsked) {
  Dataset d;
  d.pose_priors.push_back({{0.0, 0.0, 0.0, 0.0}, 0.1, 0.01});
  d.odometry = {Odom(0, 1, 1, 0, M_PI / 2), Odom(2, 3, 1, 0, 0)};
  d.observations.push_back(RangeAt(1.5));
  DeadReckoningOptions options;
  options.hold_through_gaps = true;
  DeadReckoningResult r;
  std::string error;
  ASSERT_TRUE(DeadReckon(d, options, &r, &error)) << error;
  ASSERT_EQ(r.gaps.size(), 1u);
  EXPECT_EQ(r.gaps[0].begin, 1.0);
  EXPECT_EQ(r.gaps[0].end, 2.0);
  ASSERT_EQ(r.poses.size(), 5u);
  ExpectPose(r.poses[1], 1.0, 1.0, 0.0, M_PI / 2);
  ExpectPose(r.poses[2], 1.5, 1.0, 0.0, M_PI / 2);  // Held.
  ExpectPose(r.poses[3], 2.0, 1.0, 0.0, M_PI / 2);
  ExpectPose(r.poses[4], 3.0, 1.0, 1.0, M_PI / 2);
}

TEST(DeadReckoningTest, TouchingWithinToleranceIsNoGap) {
  Dataset d;
  d.pose_priors.push_back({{0.0, 0.0, 0.0, 0.0}, 0.1, 0.01});
  d.odometry = {Odom(0, 1, 1, 0, 0), Odom(1 + 1e-9, 2, 1, 0, 0)};
  DeadReckoningResult r;
  std::string error;
  ASSERT_TRUE(DeadReckon(d, {}, &r, &error)) << error;
  ASSERT_EQ(r.poses.size(), 3u);
  ExpectPose(r.poses[2], 2.0, 2.0, 0.0, 0.0);
}

TEST(DeadReckoningTest, OverlapIsAnError) {
  Dataset d;
  d.pose_priors.push_back({{0.0, 0.0, 0.0, 0.0}, 0.1, 0.01});
  d.odometry = {Odom(1, 3, 1, 0, 0), Odom(0, 2, 1, 0, 0)};
  DeadReckoningResult r;
  std::string error;
  EXPECT_FALSE(DeadReckon(d, {}, &r, &error));
  EXPECT_EQ(error,
            "ODOM records [0, 2] and [1, 3] overlap (the motion in between "
            "would be counted twice)");
  d.odometry = {Odom(0, 1, 1, 0, 0), Odom(0, 1, 1, 0, 0)};  // Duplicate.
  EXPECT_FALSE(DeadReckon(d, {}, &r, &error));
  EXPECT_EQ(error,
            "ODOM records [0, 1] and [0, 1] overlap (the motion in between "
            "would be counted twice)");
}

TEST(DeadReckoningTest, NoOdometryIsAnError) {
  Dataset d;
  d.pose_priors.push_back({{0.0, 0.0, 0.0, 0.0}, 0.1, 0.01});
  DeadReckoningResult r;
  std::string error;
  EXPECT_FALSE(DeadReckon(d, {}, &r, &error));
  EXPECT_EQ(error,
            "the dataset has no ODOM records: dead reckoning integrates "
            "odometry");
}

TEST(DeadReckoningTest, StartsFromTheEarliestPriorInsideTheChain) {
  // The earliest prior (t = 1.5) lies halfway through the second record:
  // the chain is integrated backward and forward from it.
  Dataset d;
  d.pose_priors.push_back({{3.0, 9.0, 9.0, 0.0}, 0.1, 0.01});
  d.pose_priors.push_back({{1.5, 0.0, 0.0, 0.0}, 0.1, 0.01});
  d.odometry = {Odom(0, 1, 1, 0, 0), Odom(1, 2, 1, 0, M_PI / 2)};
  DeadReckoningResult r;
  std::string error;
  ASSERT_TRUE(DeadReckon(d, {}, &r, &error)) << error;
  EXPECT_EQ(r.start.t, 1.5);
  ASSERT_EQ(r.poses.size(), 4u);
  // Node at 1: heading -pi/4 (half the turn earlier), position half the
  // second step back: -0.5 (cos -pi/4, sin -pi/4).
  const double h = std::sqrt(0.5);
  ExpectPose(r.poses[0], 0.0, -1.5 * h, 1.5 * h, -M_PI / 4);
  ExpectPose(r.poses[1], 1.0, -0.5 * h, 0.5 * h, -M_PI / 4);
  ExpectPose(r.poses[2], 1.5, 0.0, 0.0, 0.0);  // The prior itself.
  ExpectPose(r.poses[3], 2.0, 0.5 * h, -0.5 * h, M_PI / 4);
  const Pose2 second = Between(ToPose2(r.poses[1]), ToPose2(r.poses[3]));
  EXPECT_NEAR(second.x, 1.0, 1e-12);
  EXPECT_NEAR(second.y, 0.0, 1e-12);
  EXPECT_NEAR(second.theta, M_PI / 2, 1e-12);
}

TEST(DeadReckoningTest, PriorOutsideTheSpanIsAnError) {
  Dataset d = Square();
  d.pose_priors[0].pose.t = 5.0;
  DeadReckoningResult r;
  std::string error;
  EXPECT_FALSE(DeadReckon(d, {}, &r, &error));
  EXPECT_EQ(error,
            "the earliest PRIOR_POSE time 5 lies outside the odometry span "
            "[0, 4]");
}

TEST(DeadReckoningTest, TimesOutsideTheSpanAreCountedNotWritten) {
  Dataset d = Square();
  d.observations = {RangeAt(-1.0), RangeAt(2.25), RangeAt(2.25)};
  d.ground_truth = {{4.5, 0.0, 0.0, 0.0}, {3.0, 0.0, 0.0, 0.0}};
  DeadReckoningResult r;
  std::string error;
  ASSERT_TRUE(DeadReckon(d, {}, &r, &error)) << error;
  EXPECT_EQ(r.times_outside_span, 2);
  ASSERT_EQ(r.poses.size(), 6u);  // 0..4 and 2.25 once.
  EXPECT_EQ(r.poses[3].t, 2.25);
  EXPECT_EQ(r.poses.front().t, 0.0);
  EXPECT_EQ(r.poses.back().t, 4.0);
}

}  // namespace
}  // namespace rff
