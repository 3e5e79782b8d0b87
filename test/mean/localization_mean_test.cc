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
Dataset NoiseFree(ObservationType kind, bool odometry) {
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

void ExpectExactFixesAndCloseMean(ObservationType kind, bool odometry,
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
            kind == ObservationType::kRange && !odometry);
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
  ExpectExactFixesAndCloseMean(ObservationType::kRangeBearing, false, 0.02,
                               0.01);
}

TEST(LocalizationMeanTest, BearingOnlyNoiseFreeIsRecovered) {
  ExpectExactFixesAndCloseMean(ObservationType::kBearing, false, 0.02, 0.01);
}

TEST(LocalizationMeanTest, RangeOnlyTakesTheHeadingFromTheMotion) {
  // Position fixes are exact; the heading is the direction of the smoothed
  // velocity, which the unicycle's heading equals.
  ExpectExactFixesAndCloseMean(ObservationType::kRange, false, 0.02, 0.05);
}

TEST(LocalizationMeanTest, FusesOdometryAsADriftCorrection) {
  ExpectExactFixesAndCloseMean(ObservationType::kRangeBearing, true, 1e-3,
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

// Range-bearing observations of four landmarks whose priors are 5 m wide,
// as in the paper's protocol: the spread, not the sensor, sets the bearing's
// sigma, and it moves with the range.
struct WideMapScene {
  std::map<LandmarkId, KnownLandmark> landmarks;
  std::vector<Observation> observations;
};

WideMapScene MakeWideMapScene() {
  WideMapScene scene;
  const Eigen::Vector3d robot(1.0, -2.0, 0.4);
  const Eigen::Vector2d positions[] = {
      {9.0, 3.0}, {-6.0, 5.0}, {4.0, -12.0}, {-3.0, -7.0}};
  // Measurement errors of a few sigma, fixed so the test is repeatable.
  const double range_errors[] = {0.8, -1.3, 0.4, 1.1};
  const double bearing_errors[] = {-0.05, 0.03, 0.06, -0.02};
  for (int i = 0; i < 4; ++i) {
    scene.landmarks[i] = {positions[i], 5.0};
    const Eigen::Vector2d d = positions[i] - robot.head<2>();
    Observation o;
    o.type = ObservationType::kRangeBearing;
    o.id = i;
    o.range = d.norm() + range_errors[i];
    o.bearing =
        WrapAngle(std::atan2(d.y(), d.x()) - robot.z() + bearing_errors[i]);
    o.sigma_range = 1.0;
    o.sigma_bearing = 0.035;
    scene.observations.push_back(o);
  }
  return scene;
}

double MapCost(const WideMapScene& scene, const Eigen::Vector3d& p) {
  double cost = 0.0;
  for (const MapResidualRow& row :
       MapResiduals(scene.observations, scene.landmarks, p)) {
    cost += row.residual * row.residual;
  }
  return cost;
}

// The Jacobian is the residual's derivative; the measurement's (the fix's
// information) holds the sigma, so it differs only on bearings, only in
// position (the spread moves with the range) and by the residual's share.
TEST(MapResidualsTest, JacobianIsTheResidualsDerivative) {
  const WideMapScene scene = MakeWideMapScene();
  constexpr double kStep = 1e-6;
  for (const Eigen::Vector3d& p :
       {Eigen::Vector3d(1.0, -2.0, 0.4), Eigen::Vector3d(-4.0, 3.0, 2.5),
        Eigen::Vector3d(8.0, 1.0, -1.0)}) {
    const std::vector<MapResidualRow> rows =
        MapResiduals(scene.observations, scene.landmarks, p);
    ASSERT_EQ(rows.size(), 8u);
    for (std::size_t r = 0; r < rows.size(); ++r) {
      const Eigen::RowVector3d spread_term =
          rows[r].jacobian - rows[r].measurement_jacobian;
      if (r % 2 == 0) {  // Range: a sigma of its own.
        EXPECT_EQ(spread_term, Eigen::RowVector3d::Zero()) << r;
      } else {
        EXPECT_EQ(spread_term(2), 0.0) << r;
        EXPECT_GT(spread_term.norm(), 0.0) << r;
      }
    }
    for (int c = 0; c < 3; ++c) {
      Eigen::Vector3d step = Eigen::Vector3d::Zero();
      step[c] = kStep;
      const std::vector<MapResidualRow> plus =
          MapResiduals(scene.observations, scene.landmarks, p + step);
      const std::vector<MapResidualRow> minus =
          MapResiduals(scene.observations, scene.landmarks, p - step);
      for (std::size_t r = 0; r < rows.size(); ++r) {
        const double numeric =
            (plus[r].residual - minus[r].residual) / (2.0 * kStep);
        EXPECT_NEAR(rows[r].jacobian(c), numeric, 1e-7)
            << "row " << r << " column " << c << " at " << p.transpose();
      }
    }
  }
}

TEST(LocalizePoseTest, FixIsAStationaryPointOfItsCost) {
  const WideMapScene scene = MakeWideMapScene();
  // The prediction a metre and 0.3 rad off, and a seed turned half a turn.
  const std::vector<Eigen::Vector3d> seeds = {Eigen::Vector3d(2.0, -1.0, 0.1),
                                              Eigen::Vector3d(2.0, -1.0, 3.2)};
  PoseFix fix;
  ASSERT_TRUE(LocalizePose(scene.observations, scene.landmarks, seeds, nullptr,
                           0.1, &fix));
  const Eigen::Vector3d p(fix.pose.x, fix.pose.y, fix.pose.theta);
  EXPECT_NEAR(p.x(), 1.0, 2.0);
  EXPECT_NEAR(p.y(), -2.0, 2.0);
  EXPECT_NEAR(fix.chi2, MapCost(scene, p), 1e-12);
  // Central differences of the cost: zero at a minimum. Gauss-Newton on a
  // Jacobian that held the bearing's sigma fixed stopped at 1e-4 to 8e-3.
  constexpr double kStep = 1e-5;
  for (int c = 0; c < 3; ++c) {
    Eigen::Vector3d step = Eigen::Vector3d::Zero();
    step[c] = kStep;
    const double gradient =
        (MapCost(scene, p + step) - MapCost(scene, p - step)) / (2.0 * kStep);
    EXPECT_NEAR(gradient, 0.0, 1e-6) << "coordinate " << c;
  }
}

// Starts that head for the prediction's minimum are cut short (the fit's
// whitened distance to it under kSameMinimumChi2): sixteen starts turned
// around the circle give the fix of the prediction alone.
TEST(LocalizePoseTest, TurnedStartsGiveThePredictionsFix) {
  const WideMapScene scene = MakeWideMapScene();
  const Eigen::Vector3d prediction(2.0, -1.0, 0.1);
  std::vector<Eigen::Vector3d> seeds = {prediction};
  for (int k = 1; k < 16; ++k) {
    seeds.push_back(prediction + Eigen::Vector3d(0.0, 0.0, k * M_PI / 8.0));
  }
  PoseFix alone, turned;
  ASSERT_TRUE(LocalizePose(scene.observations, scene.landmarks, {prediction},
                           nullptr, 0.1, &alone));
  ASSERT_TRUE(LocalizePose(scene.observations, scene.landmarks, seeds, nullptr,
                           0.1, &turned));
  EXPECT_EQ(turned.pose.x, alone.pose.x);
  EXPECT_EQ(turned.pose.y, alone.pose.y);
  EXPECT_EQ(turned.pose.theta, alone.pose.theta);
  EXPECT_EQ(turned.chi2, alone.chi2);
}

// Ranges of two landmarks fit a pose and its mirror image; a third, 0.5 m
// off their line, tells them apart. From a prediction beside the mirror a
// second start 20 m away still reaches the true pose: a minimum found takes
// no start that does not come within the fit's noise of it.
TEST(LocalizePoseTest, AStartInAnotherBasinFindsTheBetterMinimum) {
  const std::map<LandmarkId, KnownLandmark> landmarks = {
      {0, {Eigen::Vector2d(0.0, 0.0), 0.0}},
      {1, {Eigen::Vector2d(10.0, 0.0), 0.0}},
      {2, {Eigen::Vector2d(5.0, 0.5), 0.0}}};
  const Eigen::Vector2d robot(5.0, 6.0);
  std::vector<Observation> observations;
  for (const auto& [id, landmark] : landmarks) {
    Observation o;
    o.type = ObservationType::kRange;
    o.id = id;
    o.range = (landmark.position - robot).norm();
    o.sigma_range = 0.1;
    observations.push_back(o);
  }
  const std::vector<Eigen::Vector3d> seeds = {Eigen::Vector3d(5.2, -5.8, 0.0),
                                              Eigen::Vector3d(-3.0, 25.0, 0.0)};
  PoseFix mirror, fix;
  ASSERT_TRUE(LocalizePose(observations, landmarks, {seeds.front()}, nullptr,
                           0.1, &mirror));
  EXPECT_LT(mirror.pose.y, 0.0);
  EXPECT_GT(mirror.chi2, 4.0);
  ASSERT_TRUE(LocalizePose(observations, landmarks, seeds, nullptr, 0.1, &fix));
  EXPECT_NEAR(fix.pose.x, robot.x(), 1e-6);
  EXPECT_NEAR(fix.pose.y, robot.y(), 1e-6);
  EXPECT_NEAR(fix.chi2, 0.0, 1e-9);
}

TEST(LocalizationMeanTest, NoLocalisableTimeIsAClearError) {
  // Range-only with one landmark in view per step: never enough ranges.
  SimulationOptions sim = PaperOptions(3);
  sim.num_steps = 10;
  sim.kind = ObservationType::kRange;
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
  const Dataset dataset = NoiseFree(ObservationType::kRangeBearing, false);
  std::string error;
  EXPECT_EQ(BuildPriorMean("magic", dataset, &error), nullptr);
  EXPECT_EQ(error,
            "--prior_mean=magic: unknown prior mean; allowed auto, odometry, "
            "wnoa, localization, spline or constant");
  EXPECT_THAT(PriorMeanNames(), ::testing::Contains("localization"));
  // Odometry is asked for but the dataset has none.
  EXPECT_EQ(BuildPriorMean("odometry", dataset, &error), nullptr);
  EXPECT_THAT(error, HasSubstr("prior mean 'odometry'"));
}

TEST(PriorMeanTest, LocalizationAndSplineFollowTheFixesAndAutoStaysOffData) {
  const Dataset dataset = NoiseFree(ObservationType::kRangeBearing, false);
  const TimedPose& last = dataset.ground_truth.back();
  for (const char* name : {"localization", "spline"}) {
    std::string error;
    std::shared_ptr<const MeanFunction> mean =
        BuildPriorMean(name, dataset, &error);
    ASSERT_NE(mean, nullptr) << name << ": " << error;
    const Eigen::Vector3d p = mean->Evaluate(last.t);
    EXPECT_LT(std::hypot(p.x() - last.x, p.y() - last.y), 0.1) << name;
  }
  // "constant" stays at the first pose, far from the end of the run, and
  // without odometry "auto" is that constant: the observations stay out of
  // the prior.
  for (const char* name : {"constant", "auto"}) {
    std::string error;
    const Eigen::Vector3d p =
        BuildPriorMean(name, dataset, &error)->Evaluate(last.t);
    EXPECT_GT(std::hypot(p.x() - last.x, p.y() - last.y), 5.0) << name;
    EXPECT_EQ(p, BuildPriorMean("constant", dataset, &error)->Evaluate(0.0))
        << name;
  }
}

// The spline mean takes its smoothing from the caller: p = 1 interpolates
// the localisation at the observation times, p = 0 is the straight line
// through it (De Boor's csaps), far from the run's end.
TEST(PriorMeanTest, SplineSmoothingReachesTheSplineMean) {
  const Dataset dataset = NoiseFree(ObservationType::kRangeBearing, false);
  std::string error;
  const auto localization = BuildPriorMean("localization", dataset, &error);
  const auto interpolating =
      BuildPriorMean("spline", dataset, LocalizationOptions(), 1.0, &error);
  const auto straight =
      BuildPriorMean("spline", dataset, LocalizationOptions(), 0.0, &error);
  ASSERT_TRUE(localization && interpolating && straight) << error;
  double interpolating_gap = 0.0, straight_gap = 0.0;
  for (const Observation& o : dataset.observations) {
    const Eigen::Vector3d target = localization->Evaluate(o.t);
    interpolating_gap =
        std::max(interpolating_gap,
                 (interpolating->Evaluate(o.t) - target).head<2>().norm());
    straight_gap = std::max(
        straight_gap, (straight->Evaluate(o.t) - target).head<2>().norm());
  }
  EXPECT_LT(interpolating_gap, 1e-6);
  EXPECT_GT(straight_gap, 1.0);
}

TEST(PriorMeanTest, LocalizationOptionsReachTheMean) {
  // With odometry fusion switched off, the mean is the smoothed fixes alone
  // (not exact between them); with it, dead reckoning makes it exact.
  const Dataset dataset = NoiseFree(ObservationType::kRangeBearing, true);
  LocalizationOptions fixes_only;
  fixes_only.use_odometry = false;
  std::string error;
  std::shared_ptr<const MeanFunction> fused =
      BuildPriorMean("localization", dataset, LocalizationOptions(),
                     kPaperSplineSmoothing, &error);
  std::shared_ptr<const MeanFunction> unfused = BuildPriorMean(
      "localization", dataset, fixes_only, kPaperSplineSmoothing, &error);
  ASSERT_NE(fused, nullptr) << error;
  ASSERT_NE(unfused, nullptr) << error;
  double fused_max = 0.0, unfused_max = 0.0;
  for (const TimedPose& truth : dataset.ground_truth) {
    const double t = truth.t + 0.5;  // Between the fixes.
    if (t > dataset.ground_truth.back().t) break;
    const Eigen::Vector3d a = fused->Evaluate(t);
    const Eigen::Vector3d b = unfused->Evaluate(t);
    const Eigen::Vector3d c = fused->Evaluate(truth.t);
    unfused_max = std::max(unfused_max, (a - b).head<2>().norm());
    fused_max =
        std::max(fused_max, std::hypot(c.x() - truth.x, c.y() - truth.y));
  }
  EXPECT_LT(fused_max, 1e-3);
  EXPECT_GT(unfused_max, 1e-3);
}

TEST(PriorMeanTest, BadLocalizationOptionsAreNamedForEveryMean) {
  const Dataset dataset = NoiseFree(ObservationType::kRangeBearing, true);
  LocalizationOptions options;
  options.correction_smoothing = 0.0;
  std::string error;
  EXPECT_EQ(BuildPriorMean("localization", dataset, options,
                           kPaperSplineSmoothing, &error),
            nullptr);
  EXPECT_EQ(error,
            "--localization_correction_smoothing=0: allowed more than 0");
  // "auto" would localise without odometry: it must not fall back silently.
  options = LocalizationOptions();
  options.position_smoothing = std::nan("");
  EXPECT_EQ(
      BuildPriorMean("auto", dataset, options, kPaperSplineSmoothing, &error),
      nullptr);
  EXPECT_EQ(error,
            "--localization_position_smoothing=nan: not a finite number; "
            "allowed more than 0");
  options = LocalizationOptions();
  options.held_heading_sigma = -0.1;
  LocalizationReport report;
  EXPECT_EQ(BuildLocalizationMean(dataset, options, &report, &error), nullptr);
  EXPECT_EQ(error,
            "--localization_held_heading_sigma=-0.1: allowed more than 0");
}

}  // namespace
}  // namespace rff
