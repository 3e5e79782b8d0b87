// .rffd -> PyFG -> .rffd and .rffd -> g2o -> .rffd on the bundled data: every
// record the format can express comes back, and the round-tripped Plaza 1
// solves (configs/plaza.flags) to the original's trajectory within 1e-6 m.
#include <gflags/gflags.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <sstream>
#include <string>

#include "apps/slam_flags.h"
#include "gtest/gtest.h"
#include "rff_ceres/convert/g2o.h"
#include "rff_ceres/convert/pyfg.h"
#include "rff_ceres/io/dataset_io.h"
#include "rff_ceres/slam_solver.h"
#include "test/test_files.h"

namespace rff {
namespace {

Dataset ReadBundled(const std::string& name) {
  Dataset d;
  std::string error;
  EXPECT_TRUE(
      ReadDataset(std::string(RFF_SOURCE_DIR) + "/data/" + name, &d, &error))
      << error;
  return d;
}

Dataset ThroughPyfg(const Dataset& dataset) {
  std::stringstream text;
  PyfgWriteSummary written;
  PyfgReadSummary read;
  Dataset back;
  std::string error;
  EXPECT_TRUE(WritePyfg(dataset, &text, &written, &error)) << error;
  EXPECT_TRUE(ParsePyfg(&text, "round_trip.pyfg", {}, &back, &read, &error))
      << error;
  return back;
}

Dataset ThroughG2o(const Dataset& dataset) {
  std::stringstream text;
  G2oWriteSummary written;
  G2oReadSummary read;
  Dataset back;
  std::string error;
  EXPECT_TRUE(WriteG2o(dataset, &text, &written, &error)) << error;
  EXPECT_TRUE(ParseG2o(&text, "round_trip.g2o", {}, &back, &read, &error))
      << error;
  return back;
}

// A sigma whose square overflows (PyFG's covariance is inf) or whose
// information underflows (g2o's is 0) makes a file its own reader refuses:
// not written, with the reader's words.
TEST(RoundTripTest, AFileItsReaderWouldRefuseIsNotWritten) {
  std::istringstream in(
      "RFFD 1\n"
      "PRIOR_POSE 0 0 0 0 0.1 0.01\n"
      "ODOM 0 1 1 0 0 1e200 0.1 0.01\n"
      "BEARING 1 3 0.5 0.01\n");
  Dataset d;
  std::string error;
  ASSERT_TRUE(ParseDataset(&in, "wide.rffd", &d, &error)) << error;
  const std::string dir = testing::TempDir("RoundTripTest");
  const std::string pyfg = dir + "/wide.pyfg", g2o = dir + "/wide.g2o";
  PyfgWriteSummary pyfg_summary;
  EXPECT_FALSE(WritePyfg(d, pyfg, &pyfg_summary, &error));
  EXPECT_EQ(error, pyfg + ": not written: its reader would refuse it: " + pyfg +
                       ":5: field 8 'inf' is not a finite number");
  EXPECT_FALSE(std::filesystem::exists(pyfg));
  G2oWriteSummary g2o_summary;
  EXPECT_FALSE(WriteG2o(d, g2o, &g2o_summary, &error));
  EXPECT_EQ(error, g2o + ": not written: its reader would refuse it: " + g2o +
                       ":6: EDGE_SE2 information entry (1,1) = 0 is not > 0");
  EXPECT_FALSE(std::filesystem::exists(g2o));
  // With a sigma both formats carry, both files are written.
  d.odometry[0].sigma_x = 0.1;
  EXPECT_TRUE(WritePyfg(d, pyfg, &pyfg_summary, &error)) << error;
  EXPECT_TRUE(WriteG2o(d, g2o, &g2o_summary, &error)) << error;
}

// What g2o's 2D types express: pose priors, odometry, bearings and
// range-bearings (no RANGE, no landmark prior, no ground truth).
Dataset G2oPart(const Dataset& dataset) {
  Dataset part;
  part.pose_priors = dataset.pose_priors;
  part.odometry = dataset.odometry;
  for (const Observation& o : dataset.observations) {
    if (o.type != ObservationType::kRange) part.observations.push_back(o);
  }
  return part;
}

// Equal to `a` up to a relative `tolerance` (0: exactly).
void ExpectClose(double a, double b, double tolerance) {
  EXPECT_LE(std::abs(a - b), tolerance * std::abs(a)) << a << " vs " << b;
}

void ExpectSameRecords(const Dataset& a, const Dataset& b, double tolerance) {
  ASSERT_EQ(a.pose_priors.size(), b.pose_priors.size());
  for (std::size_t i = 0; i < a.pose_priors.size(); ++i) {
    EXPECT_EQ(a.pose_priors[i].pose.t, b.pose_priors[i].pose.t);
    EXPECT_EQ(a.pose_priors[i].pose.x, b.pose_priors[i].pose.x);
    ExpectClose(a.pose_priors[i].sigma_xy, b.pose_priors[i].sigma_xy,
                tolerance);
  }
  ASSERT_EQ(a.odometry.size(), b.odometry.size());
  for (std::size_t i = 0; i < a.odometry.size(); ++i) {
    const Odometry &x = a.odometry[i], &y = b.odometry[i];
    ASSERT_EQ(x.t0, y.t0);
    ASSERT_EQ(x.t1, y.t1);
    ASSERT_EQ(x.dx, y.dx);
    ASSERT_EQ(x.dy, y.dy);
    ASSERT_EQ(x.dtheta, y.dtheta);
    ExpectClose(x.sigma_x, y.sigma_x, tolerance);
    ExpectClose(x.sigma_y, y.sigma_y, tolerance);
    ExpectClose(x.sigma_theta, y.sigma_theta, tolerance);
  }
  ASSERT_EQ(a.observations.size(), b.observations.size());
  for (std::size_t i = 0; i < a.observations.size(); ++i) {
    const Observation &x = a.observations[i], &y = b.observations[i];
    ASSERT_EQ(x.type, y.type);
    ASSERT_EQ(x.t, y.t);
    ASSERT_EQ(x.id, y.id);
    // A range-bearing passes through x = r cos(b), y = r sin(b).
    const double rb = x.type == ObservationType::kRangeBearing ? 4e-15 : 0.0;
    ExpectClose(x.range, y.range, rb);
    EXPECT_LE(std::abs(x.bearing - y.bearing), rb);
    ExpectClose(x.sigma_range, y.sigma_range, std::max(rb, tolerance));
    ExpectClose(x.sigma_bearing, y.sigma_bearing, std::max(rb, tolerance));
  }
  ASSERT_EQ(a.landmark_priors.size(), b.landmark_priors.size());
  for (std::size_t i = 0; i < a.landmark_priors.size(); ++i) {
    EXPECT_EQ(a.landmark_priors[i].id, b.landmark_priors[i].id);
    EXPECT_EQ(a.landmark_priors[i].sigma, b.landmark_priors[i].sigma);
  }
}

// The solve with configs/plaza.flags; without its range calibration where
// the data have no ranges (the g2o part), which refuses it.
SlamResult SolvePlaza(const Dataset& dataset) {
  gflags::FlagSaver saver;
  gflags::ReadFromFlagsFile(
      std::string(RFF_SOURCE_DIR) + "/configs/plaza.flags", "round_trip_test",
      true);
  SlamOptions options = SlamOptionsFromFlags();
  options.solver.log_progress = false;  // The app's per-iteration log.
  options.problem.range_calibration.estimate &=
      std::any_of(dataset.observations.begin(), dataset.observations.end(),
                  [](const Observation& o) { return o.HasRange(); });
  SlamResult result;
  std::string error;
  EXPECT_TRUE(RunSlam(dataset, options, &result, &error)) << error;
  return result;
}

// Largest position difference at the times both trajectories have; every
// time of `a` must be in `b`.
double MaxDifference(const SlamResult& a, const SlamResult& b) {
  std::map<double, TimedPose> poses;
  for (const TimedPose& p : b.trajectory) poses[p.t] = p;
  double largest = 0.0;
  for (const TimedPose& p : a.trajectory) {
    const auto it = poses.find(p.t);
    EXPECT_NE(it, poses.end()) << "no pose at " << p.t;
    if (it == poses.end()) continue;
    largest =
        std::max(largest, std::hypot(p.x - it->second.x, p.y - it->second.y));
  }
  return largest;
}

TEST(PyfgRoundTripTest, PlazaKeepsEveryRecordAndSolvesTheSame) {
  const Dataset original = ReadBundled("plaza1.rffd");
  const Dataset back = ThroughPyfg(original);
  // Variances: sqrt(s * s) == s exactly in binary floating point.
  ExpectSameRecords(original, back, 0.0);
  // Ground truth at every pose vertex: the GT_POSE rows, and interpolated
  // at the 3526 range times between them.
  EXPECT_EQ(back.ground_truth.size(), 9658u + 3526u);
  EXPECT_EQ(back.ground_truth_landmarks.size(), 4u);
  const double difference =
      MaxDifference(SolvePlaza(original), SolvePlaza(back));
  std::cout << "Plaza 1 through PyFG: largest position difference "
            << difference << " m\n";
  EXPECT_LE(difference, 1e-6);
}

TEST(G2oRoundTripTest, PlazaKeepsWhatG2oExpressesAndSolvesTheSame) {
  const Dataset original = G2oPart(ReadBundled("plaza1.rffd"));
  const Dataset back = ThroughG2o(original);
  // Information 1 / s^2 and back: a few ulp.
  ExpectSameRecords(original, back, 1e-15);
  const double difference =
      MaxDifference(SolvePlaza(original), SolvePlaza(back));
  std::cout << "Plaza 1 (odometry and prior) through g2o: largest position "
               "difference "
            << difference << " m\n";
  EXPECT_LE(difference, 1e-6);
}

TEST(RoundTripTest, MrclamRangeBearingThroughBothFormats) {
  const Dataset original = ReadBundled("mrclam6_robot1.rffd");
  ExpectSameRecords(original, ThroughPyfg(original), 0.0);
  const Dataset part = G2oPart(original);
  ExpectSameRecords(part, ThroughG2o(part), 1e-15);
}

}  // namespace
}  // namespace rff
