#include "rff_ceres/range_reading.h"

#include <cmath>
#include <map>
#include <random>
#include <sstream>
#include <string>

#include "Eigen/Dense"
#include "gtest/gtest.h"
#include "rff_ceres/metrics.h"
#include "rff_ceres/simulate.h"
#include "rff_ceres/slam_report.h"
#include "rff_ceres/slam_solver.h"
#include "test/trajectory_difference.h"

namespace rff {
namespace {

// A robot at the origin heading along x, and landmarks at distances of 2-8 m
// seen at bearings in [-0.6, 0.6] rad (a camera's view): their ranges read
// as `scale` times the distance or the depth plus `offset`, with white
// errors of 0.05 m.
struct CameraRows {
  Dataset dataset;
  std::map<LandmarkId, Eigen::Vector2d> landmarks;
};
CameraRows MakeCameraRows(bool depth, int count, std::uint64_t seed,
                          double scale = 1.0, double offset = 0.0) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.05);
  CameraRows rows;
  for (int i = 0; i < count; ++i) {
    const double bearing = -0.6 + 1.2 * i / (count - 1);
    const double distance = 2.0 + 6.0 * ((i * 7) % count) / count;
    Observation o;
    o.type = ObservationType::kRangeBearing;
    o.t = i;
    o.id = i;
    o.range = scale * distance * (depth ? std::cos(bearing) : 1.0) + offset +
              noise(rng);
    o.bearing = bearing;
    o.sigma_range = 0.05;
    o.sigma_bearing = 0.01;
    rows.dataset.observations.push_back(o);
    rows.landmarks[i] =
        distance * Eigen::Vector2d(std::cos(bearing), std::sin(bearing));
  }
  return rows;
}

Eigen::Vector3d AtOrigin(double /*t*/) { return Eigen::Vector3d::Zero(); }

TEST(RangeReadingTest, DepthsGiveASlopeOfOneAndDistancesNone) {
  const CameraRows depths = MakeCameraRows(true, 400, 1);
  const DepthEvidence evidence =
      MeasureDepthEvidence(depths.dataset, AtOrigin, depths.landmarks);
  EXPECT_EQ(evidence.rows, 400);
  EXPECT_NEAR(evidence.slope, 1.0, 0.05);
  EXPECT_GT(evidence.t_statistic, 10.0);
  const CameraRows distances = MakeCameraRows(false, 400, 1);
  const DepthEvidence none =
      MeasureDepthEvidence(distances.dataset, AtOrigin, distances.landmarks);
  EXPECT_EQ(none.rows, 400);
  EXPECT_LT(std::abs(none.t_statistic), 3.0);
}

// A distance sensor that reads 5% short and 0.2 m under (what the range
// calibration takes) is no camera: the offset and scale columns take it.
TEST(RangeReadingTest, ABiasedDistanceSensorIsNotTakenForDepths) {
  const CameraRows biased = MakeCameraRows(false, 400, 2, 0.95, -0.2);
  const DepthEvidence evidence =
      MeasureDepthEvidence(biased.dataset, AtOrigin, biased.landmarks);
  EXPECT_EQ(evidence.rows, 400);
  EXPECT_LT(std::abs(evidence.t_statistic), 3.0);
  // Depths through the same sensor still are.
  const CameraRows camera = MakeCameraRows(true, 400, 2, 0.95, -0.2);
  EXPECT_GT(MeasureDepthEvidence(camera.dataset, AtOrigin, camera.landmarks)
                .t_statistic,
            10.0);
}

TEST(RangeReadingTest, TheFitIsLeastSquaresOverTheRowsItKeeps) {
  CameraRows rows = MakeCameraRows(true, 8, 3);
  // The regression in the test's own terms: Householder QR of the rows.
  Eigen::MatrixXd a(8, 3);
  Eigen::VectorXd r(8);
  for (int i = 0; i < 8; ++i) {
    const Observation& o = rows.dataset.observations[i];
    const double d = rows.landmarks.at(o.id).norm();
    a.row(i) << 1.0 / 0.05, d / 0.05, -d * (1.0 - std::cos(o.bearing)) / 0.05;
    r[i] = (o.range - d) / 0.05;
  }
  const Eigen::Vector3d x = a.householderQr().solve(r);
  const double misfit = (r - a * x).squaredNorm() / (8 - 3);
  const double t =
      x[2] / std::sqrt(misfit * (a.transpose() * a).inverse()(2, 2));
  // Left out: a range-only record, a landmark not placed, a range under 2
  // sigmas (the near-landmark form) and a residual beyond 5 robust sigmas.
  Observation range_only = rows.dataset.observations[1];
  range_only.type = ObservationType::kRange;
  Observation unplaced = rows.dataset.observations[1];
  unplaced.id = 99;
  Observation near = rows.dataset.observations[1];
  near.range = 0.09;
  Observation outlier = rows.dataset.observations[1];
  outlier.range += 100.0;
  for (const Observation& o : {range_only, unplaced, near, outlier}) {
    rows.dataset.observations.push_back(o);
  }
  const DepthEvidence evidence =
      MeasureDepthEvidence(rows.dataset, AtOrigin, rows.landmarks);
  EXPECT_EQ(evidence.rows, 8);
  EXPECT_NEAR(evidence.slope, x[2], 1e-9 * std::abs(x[2]));
  EXPECT_NEAR(evidence.t_statistic, t, 1e-7 * std::abs(t));
  // Too few rows, or none varying: nothing told.
  rows.dataset.observations.resize(3);
  EXPECT_EQ(MeasureDepthEvidence(rows.dataset, AtOrigin, rows.landmarks).slope,
            0.0);
}

TEST(RangeReadingTest, AutoSettlesOnTheEvidenceAndAGivenReadingStays) {
  ProblemOptions options;
  EXPECT_EQ(options.range_bearing_ranges, "auto");
  DepthEvidence strong;
  strong.slope = 0.2;
  strong.t_statistic = kMinDepthEvidence + 0.1;
  EXPECT_TRUE(SettleRangeReading(strong, &options));
  EXPECT_EQ(options.range_bearing_ranges, "depth");
  EXPECT_TRUE(options.range_calibration.estimate);

  ProblemOptions weak_options;
  DepthEvidence weak = strong;
  weak.t_statistic = kMinDepthEvidence - 0.1;
  EXPECT_FALSE(SettleRangeReading(weak, &weak_options));
  EXPECT_EQ(weak_options.range_bearing_ranges, "distance");
  EXPECT_FALSE(weak_options.range_calibration.estimate);
  // Ranges that read long at the edges are no camera's depths.
  ProblemOptions negative_options;
  DepthEvidence negative = strong;
  negative.slope = -0.2;
  negative.t_statistic = -50.0;
  EXPECT_FALSE(SettleRangeReading(negative, &negative_options));
  EXPECT_EQ(negative_options.range_bearing_ranges, "distance");

  ProblemOptions given;
  given.range_bearing_ranges = "distance";
  EXPECT_FALSE(SettleRangeReading(strong, &given));
  EXPECT_EQ(given.range_bearing_ranges, "distance");
  EXPECT_FALSE(given.range_calibration.estimate);
}

TEST(RangeReadingTest, UnknownReadingIsRefusedNamingTheFlag) {
  SlamOptions options;
  options.problem.range_bearing_ranges = "depths";
  std::string error;
  EXPECT_FALSE(ValidateSlamOptions(options, &error));
  EXPECT_EQ(error,
            "--range_bearing_ranges=depths: unknown reading of the ranges; "
            "allowed auto, distance or depth");
}

// A camera robot: the paper's path with range-bearing to landmarks within
// 8 m and 0.6 rad of the heading, landmark priors 1 m off.
Dataset CameraRun(std::uint64_t seed) {
  SimulationOptions simulation = PaperOptions(seed);
  simulation.num_steps = 200;
  simulation.sensor_range = 8.0;
  simulation.min_range = 1.0;
  simulation.field_of_view = 1.2;
  simulation.min_visible_landmarks = 2;
  simulation.sigma_range = 0.05;
  simulation.sigma_bearing = 0.01;
  simulation.landmark_prior_sigma = 1.0;
  Dataset dataset;
  std::string error;
  EXPECT_TRUE(Simulate(simulation, &dataset, &error)) << error;
  return dataset;
}

// The same run with every range moved by `share` of the way from the
// landmark's distance to its depth along the heading (its error kept):
// z + share d (cos(b) - 1) with the truth's d and b; 1 reads depths.
Dataset AsDepths(Dataset dataset, double share = 1.0) {
  std::map<LandmarkId, Eigen::Vector2d> truth;
  for (const Landmark& l : dataset.ground_truth_landmarks) {
    truth[l.id] = Eigen::Vector2d(l.x, l.y);
  }
  std::map<double, TimedPose> poses;
  for (const TimedPose& p : dataset.ground_truth) poses[p.t] = p;
  for (Observation& o : dataset.observations) {
    const TimedPose& p = poses.at(o.t);
    const Eigen::Vector2d delta = truth.at(o.id) - Eigen::Vector2d(p.x, p.y);
    const double bearing = std::atan2(delta.y(), delta.x()) - p.theta;
    o.range += share * delta.norm() * (std::cos(bearing) - 1.0);
  }
  return dataset;
}

double ApeOf(const Dataset& dataset, const SlamResult& result) {
  Evaluation evaluation;
  std::string error;
  EXPECT_TRUE(Evaluate(dataset.ground_truth, dataset.ground_truth_landmarks,
                       result.trajectory, nullptr, EvaluationOptions(),
                       &evaluation, &error))
      << error;
  return evaluation.ape_translation.rms;
}

// Measured (seed 3): distances judged as such (t 0.51) and solved as
// before, bit for bit (APE 0.149 m); the same run with depths judged as
// depths (t 20.8, calibration 0.9999 and 0.011 m) and solved to 0.150 m,
// where reading them as distances ends 0.260 m off.
TEST(RangeReadingSolveTest, AutoReadsACamerasDepthsAndLeavesDistances) {
  const Dataset distances = CameraRun(3);
  SlamOptions options;
  options.prior = "wnoa";
  SlamOptions as_distances = options;
  as_distances.problem.range_bearing_ranges = "distance";
  std::string error;
  SlamResult judged, given;
  ASSERT_TRUE(RunSlam(distances, options, &judged, &error)) << error;
  ASSERT_TRUE(RunSlam(distances, as_distances, &given, &error)) << error;
  EXPECT_TRUE(judged.range_reading_judged);
  EXPECT_FALSE(given.range_reading_judged);
  EXPECT_EQ(judged.range_bearing_ranges, "distance");
  EXPECT_LT(std::abs(judged.depth_evidence.t_statistic), 3.0);
  EXPECT_EQ(testing::LargestPositionDifference(judged, given), 0.0);
  EXPECT_FALSE(judged.range_calibrated);

  const Dataset depths = AsDepths(distances);
  SlamResult auto_depths, misread;
  ASSERT_TRUE(RunSlam(depths, options, &auto_depths, &error)) << error;
  ASSERT_TRUE(RunSlam(depths, as_distances, &misread, &error)) << error;
  EXPECT_EQ(auto_depths.range_bearing_ranges, "depth");
  EXPECT_GT(auto_depths.depth_evidence.t_statistic, kMinDepthEvidence);
  EXPECT_TRUE(auto_depths.range_calibrated);
  EXPECT_NEAR(auto_depths.range_calibration[0], 1.0, 0.02);
  EXPECT_NEAR(auto_depths.range_calibration[1], 0.0, 0.05);
  const double ape = ApeOf(depths, auto_depths);
  EXPECT_LT(ape, 1.2 * ApeOf(distances, judged));
  EXPECT_GT(ApeOf(depths, misread), 1.5 * ape);
  std::ostringstream summary;
  PrintSlamSummary(options, auto_depths, &summary);
  EXPECT_NE(summary.str().find("ranges       RANGE_BEARING ranges read as "
                               "depths along the heading (auto:"),
            std::string::npos)
      << summary.str();
  EXPECT_NE(summary.str().find(" * depth + "), std::string::npos);
}

// Evidence without a minimum, or for a reading that fits worse, reads
// distances: the first solve cut at one iteration is not judged, and ranges
// a third of the way to depths (slope 0.17, t 20.2) fit worse
// read as depths, so they are read as distances and said to be.
TEST(RangeReadingSolveTest, DepthsWithoutAMinimumOrABetterFitAreNotTaken) {
  const Dataset distances = CameraRun(3);
  SlamOptions options;
  options.prior = "wnoa";
  SlamOptions cut = options;
  cut.solver.max_iterations = 1;
  std::string error;
  SlamResult result;
  ASSERT_TRUE(RunSlam(AsDepths(distances), cut, &result, &error)) << error;
  EXPECT_FALSE(result.range_reading_judged);
  EXPECT_EQ(result.range_bearing_ranges, "distance");

  ASSERT_TRUE(RunSlam(AsDepths(distances, 0.3), options, &result, &error))
      << error;
  EXPECT_TRUE(result.range_reading_judged);
  EXPECT_GT(result.depth_evidence.t_statistic, kMinDepthEvidence);
  EXPECT_TRUE(result.depth_rejected);
  EXPECT_EQ(result.range_bearing_ranges, "distance");
  EXPECT_FALSE(result.range_calibrated);
  std::ostringstream summary;
  PrintSlamSummary(options, result, &summary);
  EXPECT_NE(summary.str().find("ranges       RANGE_BEARING ranges read as "
                               "distances: their residuals follow"),
            std::string::npos)
      << summary.str();
}

}  // namespace
}  // namespace rff
