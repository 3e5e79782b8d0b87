#include "rff_ceres/convert/pyfg.h"

#include <cmath>
#include <sstream>
#include <string>

#include "gtest/gtest.h"
#include "rff_ceres/io/dataset_io.h"

namespace rff {
namespace {

// Robot A at three poses (0, 1, 2.5 s), landmark L7 at (4, 3); lines out of
// order (edges before some vertices), as PyFG allows.
const char kSingleRobot[] =
    "VERTEX_SE2 0 A0 0 0 0\n"
    "VERTEX_SE2 1 A1 1 0 0.5\n"
    "EDGE_SE2 1 A0 A1 1 0 0.5 0.01 0 0 0.04 0 0.0001\n"
    "EDGE_SE2 2.5 A1 A2 0.5 0.25 -0.5 0.01 0 0 0.01 0 0.0004\n"
    "VERTEX_SE2 2.5 A2 1.5 0.5 0\n"
    "VERTEX_XY L7 4 3\n"
    "VERTEX_SE2:PRIOR 0 A0 0 0 0 0.0004 0 0 0.0004 0 0.0001\n"
    "VERTEX_XY:PRIOR 0 L7 4 3 0.25 0 0.25\n"
    "EDGE_RANGE 0 A0 L7 5.1 0.01\n"
    "EDGE_SE2_XY 2.5 A2 L7 3 0 0.04 0 0.09\n";

bool Parse(const std::string& text, const PyfgReadOptions& options,
           Dataset* dataset, PyfgReadSummary* summary, std::string* error) {
  std::istringstream in(text);
  return ParsePyfg(&in, "f.pyfg", options, dataset, summary, error);
}

TEST(PyfgReadTest, SingleRobotFile) {
  Dataset d;
  PyfgReadSummary s;
  std::string error;
  ASSERT_TRUE(Parse(kSingleRobot, {}, &d, &s, &error)) << error;
  EXPECT_EQ(s.robot, "A");
  EXPECT_EQ(s.records, 10u);
  EXPECT_FALSE(s.prior_added);
  ASSERT_EQ(d.pose_priors.size(), 1u);
  EXPECT_EQ(d.pose_priors[0].pose.t, 0.0);
  EXPECT_EQ(d.pose_priors[0].sigma_xy, 0.02);
  EXPECT_EQ(d.pose_priors[0].sigma_theta, 0.01);
  ASSERT_EQ(d.odometry.size(), 2u);
  EXPECT_EQ(d.odometry[1].t0, 1.0);
  EXPECT_EQ(d.odometry[1].t1, 2.5);
  EXPECT_EQ(d.odometry[1].dy, 0.25);
  EXPECT_EQ(d.odometry[1].dtheta, -0.5);
  EXPECT_EQ(d.odometry[0].sigma_y, 0.2);
  EXPECT_EQ(d.odometry[1].sigma_theta, 0.02);
  ASSERT_EQ(d.landmark_priors.size(), 1u);
  EXPECT_EQ(d.landmark_priors[0].id, 7);
  EXPECT_EQ(d.landmark_priors[0].sigma, 0.5);
  ASSERT_EQ(d.observations.size(), 2u);
  EXPECT_EQ(d.observations[0].type, ObservationType::kRange);
  EXPECT_EQ(d.observations[0].t, 0.0);
  EXPECT_EQ(d.observations[0].range, 5.1);
  EXPECT_EQ(d.observations[0].sigma_range, 0.1);
  // (3, 0) with covariance diag(0.04, 0.09): range 3 +- 0.2, bearing 0 +-
  // 0.3 m / 3 m = 0.1 rad.
  const Observation& rb = d.observations[1];
  EXPECT_EQ(rb.type, ObservationType::kRangeBearing);
  EXPECT_EQ(rb.t, 2.5);
  EXPECT_EQ(rb.range, 3.0);
  EXPECT_EQ(rb.bearing, 0.0);
  EXPECT_EQ(rb.sigma_range, 0.2);
  EXPECT_DOUBLE_EQ(rb.sigma_bearing, 0.1);
  // Vertex values are the truth.
  ASSERT_EQ(d.ground_truth.size(), 3u);
  EXPECT_EQ(d.ground_truth[1].t, 1.0);
  EXPECT_EQ(d.ground_truth[1].theta, 0.5);
  ASSERT_EQ(d.ground_truth_landmarks.size(), 1u);
  EXPECT_EQ(d.ground_truth_landmarks[0].x, 4.0);
}

TEST(PyfgReadTest, RateTimesPosesByTheirNumber) {
  PyfgReadOptions options;
  options.rate = 4.0;
  Dataset d;
  PyfgReadSummary s;
  std::string error;
  ASSERT_TRUE(Parse(kSingleRobot, options, &d, &s, &error)) << error;
  EXPECT_EQ(d.odometry[1].t0, 0.25);
  EXPECT_EQ(d.odometry[1].t1, 0.5);
  EXPECT_EQ(d.observations[1].t, 0.5);
  EXPECT_EQ(d.metadata[1].second,
            "rff_convert --format=pyfg --robot=A --rate=4");
}

// Robots A and B see landmark L0; A ranges to B and has a loop closure to B;
// neither has a prior.
const char kTwoRobots[] =
    "VERTEX_SE2 0 A0 0 0 0\nVERTEX_SE2 1 A1 1 0 0\n"
    "VERTEX_SE2 0 B0 0 5 0\nVERTEX_SE2 1 B1 1 5 0\n"
    "VERTEX_XY L0 3 3\n"
    "EDGE_SE2 1 A0 A1 1 0 0 0.01 0 0 0.01 0 0.01\n"
    "EDGE_SE2 1 B0 B1 1 0 0 0.01 0 0 0.01 0 0.01\n"
    "EDGE_SE2 1 A1 B0 -1 5 0 0.01 0 0 0.01 0 0.01\n"
    "EDGE_RANGE 1 A1 B1 5 0.01\n"
    "EDGE_RANGE 1 B1 L0 2.8 0.01\n"
    "EDGE_RANGE 1 A1 L0 3.6 0.01\n";

TEST(PyfgReadTest, MultiRobotFileReadsOneRobot) {
  PyfgReadOptions options;
  options.robot = "B";
  options.prior_sigma_xy = 0.5;
  Dataset d;
  PyfgReadSummary s;
  std::string error;
  ASSERT_TRUE(Parse(kTwoRobots, options, &d, &s, &error)) << error;
  EXPECT_EQ(s.robots, "A or B");
  EXPECT_EQ(s.num_robots, 2u);
  EXPECT_EQ(s.inter_robot_edges, 2u);
  EXPECT_EQ(s.other_robot_records, 4u);  // A0, A1, A0 -> A1, A1 -> L0.
  EXPECT_TRUE(s.prior_added);
  ASSERT_EQ(d.pose_priors.size(), 1u);
  EXPECT_EQ(d.pose_priors[0].pose.y, 5.0);
  EXPECT_EQ(d.pose_priors[0].sigma_xy, 0.5);
  ASSERT_EQ(d.odometry.size(), 1u);
  ASSERT_EQ(d.observations.size(), 1u);
  EXPECT_EQ(d.observations[0].range, 2.8);
  EXPECT_EQ(d.ground_truth.size(), 2u);

  options.robot = "";
  EXPECT_FALSE(Parse(kTwoRobots, options, &d, &s, &error));
  EXPECT_EQ(error, "--robot=: f.pyfg has 2 robots: pick one; allowed A or B");
  options.robot = "C";
  EXPECT_FALSE(Parse(kTwoRobots, options, &d, &s, &error));
  EXPECT_EQ(error, "--robot=C: f.pyfg has 2 robots; allowed A or B");
}

// The error for `text` (an empty string on success).
std::string ErrorOf(const std::string& text) {
  Dataset d;
  PyfgReadSummary s;
  std::string error;
  EXPECT_FALSE(Parse(text, {}, &d, &s, &error));
  return error;
}

TEST(PyfgReadTest, MalformedLinesNameFileAndLine) {
  const std::string a0 = "VERTEX_SE2 0 A0 0 0 0\n";
  const std::string a1 = "VERTEX_SE2 1 A1 1 0 0\nVERTEX_XY L1 2 2\n";
  EXPECT_EQ(ErrorOf(""), "f.pyfg: no records (empty file?)");
  EXPECT_EQ(ErrorOf(a0 + "VERTEX_SE3:QUAT 0 A1 0 0 0 0 0 0 1\n"),
            "f.pyfg:2: unknown record 'VERTEX_SE3:QUAT' (2D PyFG has "
            "VERTEX_SE2, VERTEX_XY, their :PRIOR, EDGE_SE2, EDGE_SE2_XY and "
            "EDGE_RANGE)");
  EXPECT_EQ(ErrorOf("VERTEX_SE2 0 A0 0 0\n"),
            "f.pyfg:1: VERTEX_SE2 needs 5 fields, got 4");
  EXPECT_EQ(ErrorOf("VERTEX_SE2 0 A0 0 nan 0\n"),
            "f.pyfg:1: field 5 'nan' is not a finite number");
  EXPECT_EQ(ErrorOf("VERTEX_SE2 0 robot1 0 0 0\n"),
            "f.pyfg:1: field 3 'robot1' is not a vertex name (a pose: one "
            "capital letter other than L and a number, A12; a landmark: L and "
            "a number, L3)");
  EXPECT_EQ(ErrorOf(a0 + "VERTEX_SE2 0 A0 1 0 0\n"),
            "f.pyfg:2: second VERTEX_SE2 A0 (first on line 1)");
  EXPECT_EQ(ErrorOf(a0 + "VERTEX_SE2 0 A1 1 0 0\n"),
            "f.pyfg:2: poses A0 and A1 have the same time 0");
  EXPECT_EQ(ErrorOf("VERTEX_XY L1 0 0\n"),
            "f.pyfg: no VERTEX_SE2 record (no pose)");
  EXPECT_EQ(ErrorOf(a0 + a1 + "EDGE_SE2 0 A1 A0 1 0 0 1 0 0 1 0 1\n"),
            "f.pyfg:4: EDGE_SE2 A1 -> A0 does not go forward in time (1 -> 0; "
            ".rffd ODOM needs t1 > t0)");
  EXPECT_EQ(ErrorOf(a0 + a1 + "EDGE_SE2 0 A0 A1 1 0 0 1 0.5 0 1 0 1\n"),
            "f.pyfg:4: EDGE_SE2 covariance entry (1,2) = 0.5 is not 0 (.rffd "
            "sigmas are independent)");
  EXPECT_EQ(ErrorOf(a0 + a1 + "EDGE_SE2 0 A0 A2 1 0 0 1 0 0 1 0 1\n"),
            "f.pyfg:4: EDGE_SE2 refers to A2, which no VERTEX_SE2 defines");
  EXPECT_EQ(ErrorOf(a0 + a1 + "EDGE_SE2 0 A0 L1 1 0 0 1 0 0 1 0 1\n"),
            "f.pyfg:4: EDGE_SE2 L1: expected a pose (A12)");
  EXPECT_EQ(ErrorOf(a0 + a1 + "EDGE_RANGE 0 A0 A1 1 0.01\n"),
            "f.pyfg:4: EDGE_RANGE between two poses of robot A (A0, A1): "
            ".rffd ranges go to landmarks");
  EXPECT_EQ(ErrorOf(a0 + a1 + "EDGE_RANGE 0 A0 L1 1 0\n"),
            "f.pyfg:4: EDGE_RANGE variance must be > 0, got 0");
  EXPECT_EQ(ErrorOf(a0 + a1 + "EDGE_SE2_XY 0 A0 L1 1 1 0.04 0 0.01\n"),
            "f.pyfg:4: EDGE_SE2_XY as range and bearing the covariance has "
            "correlation -0.6 (.rffd RANGE_BEARING sigmas are independent; at "
            "most 1e-06)");
  EXPECT_EQ(ErrorOf(a0 + "VERTEX_SE2:PRIOR 0 A0 0 0 0 1 0 0 2 0 1\n"),
            "f.pyfg:2: VERTEX_SE2:PRIOR x and y variances differ (1, 2; .rffd "
            "priors have one position sigma)");
  EXPECT_EQ(ErrorOf(a0 + "VERTEX_XY A1 0 0\n"),
            "f.pyfg:2: VERTEX_XY A1: a landmark name is L and a number");
}

// A small .rffd dataset with every record type.
const char kRffd[] =
    "# source: test\n"
    "RFFD 1\n"
    "PRIOR_POSE 10 0 0 0 0.1 0.01\n"
    "PRIOR_LANDMARK 3 4 3 0.5\n"
    "ODOM 10 11 1 0 0 0.1 0.2 0.01\n"
    "RANGE 10.5 3 4.2 0.3\n"
    "RANGE_BEARING 11 3 3 0 0.2 0.1\n"
    "BEARING 11 3 0 0.1\n"
    "GT_POSE 10 0 0 0\n"
    "GT_POSE 11 1 0 0.5\n"
    "GT_LANDMARK 3 4 3\n";

TEST(PyfgWriteTest, WritesEveryRecordPyfgExpresses) {
  std::istringstream in(kRffd);
  Dataset d;
  std::string error;
  ASSERT_TRUE(ParseDataset(&in, "small.rffd", &d, &error)) << error;
  std::ostringstream out;
  PyfgWriteSummary s;
  ASSERT_TRUE(WritePyfg(d, &out, &s, &error)) << error;
  // The range at 10.5 s gets a vertex of its own, between the ODOM ends,
  // valued by interpolating the truth (heading halfway: 0.25).
  EXPECT_EQ(out.str(),
            "VERTEX_SE2 10 A0 0 0 0\n"
            "VERTEX_SE2 10.5 A1 0.5 0 0.25\n"
            "VERTEX_SE2 11 A2 1 0 0.5\n"
            "VERTEX_XY L3 4 3\n"
            "VERTEX_SE2:PRIOR 10 A0 0 0 0 0.010000000000000002 0 0 "
            "0.010000000000000002 0 1e-04\n"
            "VERTEX_XY:PRIOR 10 L3 4 3 0.25 0 0.25\n"
            "EDGE_SE2 11 A0 A2 1 0 0 0.010000000000000002 0 0 "
            "0.04000000000000001 0 1e-04\n"
            "EDGE_RANGE 10.5 A1 L3 4.2 0.09\n"
            "EDGE_SE2_XY 11 A2 L3 3 0 0.04000000000000001 0 "
            "0.09000000000000002\n");
  EXPECT_EQ(s.pose_vertices, 3u);
  EXPECT_EQ(s.poses_from_truth, 2u);
  EXPECT_EQ(s.poses_interpolated, 1u);
  EXPECT_EQ(s.poses_dead_reckoned, 0u);
  EXPECT_EQ(s.poses_without_odometry, 1u);
  EXPECT_EQ(s.bearings_left_out, 1u);

  // Back: every record but the BEARING, exactly; GT_POSE at every vertex.
  std::istringstream pyfg(out.str());
  Dataset back;
  PyfgReadSummary read;
  ASSERT_TRUE(ParsePyfg(&pyfg, "small.pyfg", {}, &back, &read, &error))
      << error;
  std::ostringstream rffd;
  WriteDataset(back, &rffd);
  EXPECT_EQ(rffd.str(),
            "# source: PyFG file 'small.pyfg', robot A\n"
            "# converter: rff_convert --format=pyfg --robot=A\n"
            "RFFD 1\n"
            "PRIOR_POSE 10 0 0 0 0.1 0.01\n"
            "PRIOR_LANDMARK 3 4 3 0.5\n"
            "ODOM 10 11 1 0 0 0.1 0.2 0.01\n"
            "RANGE 10.5 3 4.2 0.3\n"
            "RANGE_BEARING 11 3 3 0 0.2 0.1\n"
            "GT_POSE 10 0 0 0\n"
            "GT_POSE 10.5 0.5 0 0.25\n"
            "GT_POSE 11 1 0 0.5\n"
            "GT_LANDMARK 3 4 3\n");
}

TEST(PyfgWriteTest, DeadReckoningWhereNoTruthAndBadRange) {
  Dataset d;
  d.pose_priors.push_back({{0, 1, 2, 0}, 0.1, 0.1});
  d.odometry.push_back({0, 1, 1, 0, M_PI / 2, 0.1, 0.1, 0.1});
  Observation o;
  o.type = ObservationType::kRangeBearing;
  o.t = 1;
  o.id = 4;
  o.range = 2;
  o.sigma_range = o.sigma_bearing = 0.1;
  d.observations.push_back(o);
  std::ostringstream out;
  PyfgWriteSummary s;
  std::string error;
  ASSERT_TRUE(WritePyfg(d, &out, &s, &error)) << error;
  EXPECT_EQ(s.poses_dead_reckoned, 2u);
  EXPECT_EQ(s.landmarks_without_truth, 1u);
  const std::string vertices =
      "VERTEX_SE2 0 A0 1 2 0\nVERTEX_SE2 1 A1 2 2 1.5707963267948966\n"
      "VERTEX_XY L4 0 0\n";
  EXPECT_EQ(out.str().substr(0, vertices.size()), vertices);
  d.observations[0].range = -1;
  std::ostringstream none;
  EXPECT_FALSE(WritePyfg(d, &none, &s, &error));
  EXPECT_EQ(error,
            "RANGE_BEARING at t = 1 to landmark 4: range -1 is not > 0: no "
            "relative position with a covariance");
  EXPECT_EQ(none.str(), "");
}

}  // namespace
}  // namespace rff
