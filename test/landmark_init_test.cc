#include "rff_ceres/landmark_init.h"

#include <cmath>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace rff {
namespace {

using ::testing::HasSubstr;

// Robot moving along x at 1 m/s, heading +x.
Eigen::Vector3d StraightLine(double t) { return Eigen::Vector3d(t, 0.0, 0.0); }

Observation Make(ObservationType type, double t, LandmarkId id,
                 const Eigen::Vector2d& l) {
  const Eigen::Vector3d p = StraightLine(t);
  Observation o;
  o.type = type;
  o.t = t;
  o.id = id;
  o.range = (l - p.head<2>()).norm();
  o.bearing = std::atan2(l.y() - p.y(), l.x() - p.x()) - p.z();
  o.sigma_range = 1.0;
  o.sigma_bearing = 0.01;
  return o;
}

TEST(LandmarkInitTest, UsesPriorThenRangeBearingThenBearings) {
  const Eigen::Vector2d truth(4.0, 3.0);
  Dataset d;
  d.landmark_priors.push_back({7, 1.0, 2.0, 5.0});
  for (int t = 0; t < 5; ++t) {
    d.observations.push_back(Make(ObservationType::kRange, t, 7, truth));
    d.observations.push_back(Make(ObservationType::kRangeBearing, t, 8, truth));
    d.observations.push_back(Make(ObservationType::kBearing, t, 9, truth));
  }
  std::map<LandmarkId, Eigen::Vector2d> landmarks;
  std::string error;
  ASSERT_TRUE(InitializeLandmarks(d, StraightLine, &landmarks, &error))
      << error;
  ASSERT_EQ(landmarks.size(), 3u);
  EXPECT_EQ(landmarks[7], Eigen::Vector2d(1.0, 2.0));  // The prior wins.
  EXPECT_NEAR((landmarks[8] - truth).norm(), 0.0, 1e-12);
  EXPECT_NEAR((landmarks[9] - truth).norm(), 0.0, 1e-9);
}

// A prior mean exactly on a pose that sees the landmark by a bearing (no
// bearing there) starts one prior sigma along that bearing; a range alone
// there, or a prior off the robot, leaves the prior mean.
TEST(LandmarkInitTest, APriorOnTheRobotStartsAlongTheBearing) {
  Dataset d;
  d.landmark_priors.push_back({1, 2.0, 0.0, 0.5});  // On the pose at t = 2.
  d.landmark_priors.push_back({2, 3.0, 0.0, 0.5});  // On the pose at t = 3.
  d.landmark_priors.push_back({3, 4.0, 1e-6, 0.5});
  Observation bearing = Make(ObservationType::kBearing, 2, 1, {2.0, 1.0});
  d.observations.push_back(bearing);
  d.observations.push_back(Make(ObservationType::kRange, 3, 2, {3.0, 1.0}));
  d.observations.push_back(Make(ObservationType::kBearing, 4, 3, {4.0, 1.0}));
  std::map<LandmarkId, Eigen::Vector2d> landmarks;
  std::string error;
  ASSERT_TRUE(InitializeLandmarks(d, StraightLine, &landmarks, &error))
      << error;
  ASSERT_DOUBLE_EQ(bearing.bearing, M_PI / 2);
  EXPECT_NEAR((landmarks[1] - Eigen::Vector2d(2.0, 0.5)).norm(), 0.0, 1e-15);
  EXPECT_EQ(landmarks[2], Eigen::Vector2d(3.0, 0.0));
  EXPECT_EQ(landmarks[3], Eigen::Vector2d(4.0, 1e-6));
}

TEST(LandmarkInitTest, RangesFromAStraightLineAreAmbiguous) {
  // The mirror image across the line fits the ranges as well: refuse.
  Dataset d;
  for (int t = 0; t < 5; ++t) {
    d.observations.push_back(
        Make(ObservationType::kRange, t, 10, Eigen::Vector2d(4.0, 3.0)));
  }
  std::map<LandmarkId, Eigen::Vector2d> landmarks;
  std::string error;
  EXPECT_FALSE(InitializeLandmarks(d, StraightLine, &landmarks, &error));
  EXPECT_THAT(error, HasSubstr("landmark 10"));
  EXPECT_THAT(error, HasSubstr("5 range(s)"));
}

TEST(LandmarkInitTest, MultilaterationFromNonCollinearPlaces) {
  const Eigen::Vector2d truth(-2.0, 5.0);
  auto curve = [](double t) { return Eigen::Vector3d(t, 0.1 * t * t, 0.0); };
  Dataset d;
  for (int t = 0; t < 6; ++t) {
    Observation o;
    o.type = ObservationType::kRange;
    o.t = t;
    o.id = 3;
    o.range = (truth - curve(t).head<2>()).norm();
    o.sigma_range = 1.0;
    d.observations.push_back(o);
  }
  std::map<LandmarkId, Eigen::Vector2d> landmarks;
  std::string error;
  ASSERT_TRUE(InitializeLandmarks(d, curve, &landmarks, &error)) << error;
  EXPECT_NEAR((landmarks[3] - truth).norm(), 0.0, 1e-9);
}

TEST(LandmarkInitTest, UnlocatableLandmarkIsAnErrorNamingIt) {
  Dataset d;
  d.observations.push_back(
      Make(ObservationType::kRange, 0.0, 42, Eigen::Vector2d(1, 1)));
  std::map<LandmarkId, Eigen::Vector2d> landmarks;
  std::string error;
  EXPECT_FALSE(InitializeLandmarks(d, StraightLine, &landmarks, &error));
  EXPECT_THAT(error, HasSubstr("landmark 42 has no PRIOR_LANDMARK"));
  EXPECT_THAT(error, HasSubstr("1 range(s)"));
}

}  // namespace
}  // namespace rff
