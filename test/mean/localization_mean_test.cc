#include "rff_ceres/mean/localization_mean.h"

#include <cmath>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/mean/prior_mean.h"
#include "rff_ceres/simulate.h"

namespace rff {
namespace {

using ::testing::HasSubstr;

// The paper's protocol, shortened, without noise: the landmark priors are
// the true positions and every measurement is exact.
Dataset NoiseFree(MeasurementKind kind, bool odometry) {
  SimulationOptions sim = PaperOptions(7);
  sim.num_steps = 80;
  sim.num_landmarks = 12;
  sim.kind = kind;
  sim.odometry = odometry;
  sim.noise_free = true;
  // Sigmas that say so, so that the smoother follows the exact fixes.
  sim.landmark_prior_sigma = 0.01;
  sim.sigma_range = 0.01;
  sim.sigma_bearing = 1e-3;
  Dataset dataset;
  std::string error;
  EXPECT_TRUE(Simulate(sim, &dataset, &error)) << error;
  return dataset;
}

const TimedPose& TruthAt(const Dataset& dataset, double t) {
  for (const TimedPose& p : dataset.ground_truth) {
    if (p.t == t) return p;
  }
  ADD_FAILURE() << "no ground truth at " << t;
  return dataset.ground_truth.front();
}

void ExpectExactFixesAndCloseMean(MeasurementKind kind, bool odometry,
                                  double mean_tolerance,
                                  double heading_tolerance) {
  const Dataset dataset = NoiseFree(kind, odometry);
  LocalizationReport report;
  std::string error;
  std::shared_ptr<const MeanFunction> mean =
      BuildLocalizationMean(dataset, LocalizationOptions(), &report, &error);
  ASSERT_NE(mean, nullptr) << error;
  EXPECT_EQ(report.times, 80);
  EXPECT_EQ(report.localized, 80);
  EXPECT_EQ(report.rejected, 0);
  EXPECT_EQ(report.fused_odometry, odometry);
  EXPECT_EQ(report.heading_from_velocity,
            kind == MeasurementKind::kRange && !odometry);
  for (const PoseFix& fix : report.fixes) {
    const TimedPose& truth = TruthAt(dataset, fix.pose.t);
    EXPECT_NEAR(fix.pose.x, truth.x, 1e-6) << fix.pose.t;
    EXPECT_NEAR(fix.pose.y, truth.y, 1e-6) << fix.pose.t;
    if (fix.has_heading) {
      EXPECT_NEAR(WrapAngle(fix.pose.theta - truth.theta), 0.0, 1e-6);
    }
  }
  for (const TimedPose& truth : dataset.ground_truth) {
    const Eigen::Vector3d p = mean->Evaluate(truth.t);
    EXPECT_NEAR(std::hypot(p.x() - truth.x, p.y() - truth.y), 0.0,
                mean_tolerance)
        << truth.t;
    EXPECT_NEAR(WrapAngle(p.z() - truth.theta), 0.0, heading_tolerance)
        << truth.t;
  }
}

TEST(LocalizationMeanTest, RangeBearingNoiseFreeIsRecovered) {
  ExpectExactFixesAndCloseMean(MeasurementKind::kRangeBearing, false, 0.02,
                               0.01);
}

TEST(LocalizationMeanTest, BearingOnlyNoiseFreeIsRecovered) {
  ExpectExactFixesAndCloseMean(MeasurementKind::kBearing, false, 0.02, 0.01);
}

TEST(LocalizationMeanTest, RangeOnlyTakesTheHeadingFromTheMotion) {
  // Position fixes are exact; the heading is the direction of the smoothed
  // velocity, which the unicycle's heading equals.
  ExpectExactFixesAndCloseMean(MeasurementKind::kRange, false, 0.02, 0.05);
}

TEST(LocalizationMeanTest, FusesOdometryAsADriftCorrection) {
  ExpectExactFixesAndCloseMean(MeasurementKind::kRangeBearing, true, 1e-3,
                               1e-3);
}

TEST(LocalizePoseTest, OneRangeBearingWithAHeldHeading) {
  std::map<LandmarkId, KnownLandmark> landmarks = {
      {4, {Eigen::Vector2d(3.0, 4.0), 0.0}}};
  Observation o;
  o.type = ObservationType::kRangeBearing;
  o.id = 4;
  o.range = 5.0;
  o.bearing = std::atan2(4.0, 3.0) - 0.25;  // Robot at the origin, theta 0.25.
  o.sigma_range = 0.1;
  o.sigma_bearing = 0.01;
  const double heading = 0.25;
  PoseFix fix;
  ASSERT_TRUE(LocalizePose({o}, landmarks, {Eigen::Vector3d(1.0, -1.0, 0.0)},
                           &heading, 0.1, &fix));
  EXPECT_NEAR(fix.pose.x, 0.0, 1e-9);
  EXPECT_NEAR(fix.pose.y, 0.0, 1e-9);
  EXPECT_FALSE(fix.has_heading);
  EXPECT_EQ(fix.dof, 0);
  // Without the heading, one landmark does not fix (x, y, theta).
  EXPECT_FALSE(LocalizePose({o}, landmarks, {Eigen::Vector3d::Zero()}, nullptr,
                            0.1, &fix));
  // Landmarks without a prior are ignored.
  o.id = 5;
  EXPECT_FALSE(LocalizePose({o}, landmarks, {Eigen::Vector3d::Zero()}, &heading,
                            0.1, &fix));
}

TEST(LocalizationMeanTest, NoLocalisableTimeIsAClearError) {
  // Range-only with one landmark in view per step: never enough ranges.
  SimulationOptions sim = PaperOptions(3);
  sim.num_steps = 10;
  sim.kind = MeasurementKind::kRange;
  sim.odometry = false;
  sim.observations_per_step = 1;
  Dataset dataset;
  std::string error;
  ASSERT_TRUE(Simulate(sim, &dataset, &error)) << error;
  LocalizationReport report;
  EXPECT_EQ(
      BuildLocalizationMean(dataset, LocalizationOptions(), &report, &error),
      nullptr);
  EXPECT_EQ(error,
            "prior mean 'localization': none of the 10 observation times "
            "could be localised against the 50 landmark priors (too few "
            "observations of landmarks with priors at each time, or none "
            "that fit)");
  dataset.landmark_priors.clear();
  EXPECT_EQ(
      BuildLocalizationMean(dataset, LocalizationOptions(), &report, &error),
      nullptr);
  EXPECT_EQ(error,
            "prior mean 'localization': the dataset has no PRIOR_LANDMARK "
            "records to localise against");
}

TEST(PriorMeanTest, RegistryRejectsUnknownNames) {
  const Dataset dataset = NoiseFree(MeasurementKind::kRangeBearing, false);
  std::string error;
  EXPECT_EQ(BuildPriorMean("magic", dataset, &error), nullptr);
  EXPECT_EQ(error,
            "unknown prior mean 'magic' (expected auto, odometry, "
            "localization, spline or constant)");
  EXPECT_THAT(PriorMeanNames(), ::testing::Contains("localization"));
  // Odometry is asked for but the dataset has none.
  EXPECT_EQ(BuildPriorMean("odometry", dataset, &error), nullptr);
  EXPECT_THAT(error, HasSubstr("prior mean 'odometry'"));
}

TEST(PriorMeanTest, AutoLocalisesWithoutOdometryAndSplineFollows) {
  const Dataset dataset = NoiseFree(MeasurementKind::kRangeBearing, false);
  const TimedPose& last = dataset.ground_truth.back();
  for (const char* name : {"auto", "localization", "spline"}) {
    std::string error;
    std::shared_ptr<const MeanFunction> mean =
        BuildPriorMean(name, dataset, &error);
    ASSERT_NE(mean, nullptr) << name << ": " << error;
    const Eigen::Vector3d p = mean->Evaluate(last.t);
    EXPECT_LT(std::hypot(p.x() - last.x, p.y() - last.y), 0.1) << name;
  }
  // "constant" stays at the first pose, far from the end of the run.
  std::string error;
  const Eigen::Vector3d p =
      BuildPriorMean("constant", dataset, &error)->Evaluate(last.t);
  EXPECT_GT(std::hypot(p.x() - last.x, p.y() - last.y), 5.0);
}

}  // namespace
}  // namespace rff
