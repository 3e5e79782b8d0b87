#include "rff_ceres/convert/g2o.h"

#include <limits>
#include <sstream>
#include <string>

#include "gtest/gtest.h"
#include "rff_ceres/io/dataset_io.h"

namespace rff {
namespace {

// Poses 10, 11, 12 (listed out of order), landmark 3 at (4, 3); no times,
// no prior, vertex 11 fixed.
const char kG2o[] =
    "# source: hand-made\n"
    "VERTEX_SE2 11 1 0 0.5\n"
    "VERTEX_SE2 10 0 0 0\n"
    "VERTEX_SE2 12 1.5 0.5 0\n"
    "VERTEX_XY 3 4 3\n"
    "FIX 11\n"
    "EDGE_SE2 10 11 1 0 0.5 100 0 0 25 0 10000\n"
    "EDGE_SE2_XY 12 3 3 0 25 0 11.111111111111111\n"
    "EDGE_BEARING_SE2_XY 10 3 0.6435011087932844 400\n";

bool Parse(const std::string& text, const G2oReadOptions& options,
           Dataset* dataset, G2oReadSummary* summary, std::string* error) {
  std::istringstream in(text);
  return ParseG2o(&in, "f.g2o", options, dataset, summary, error);
}

TEST(G2oReadTest, VertexOrderGivesTimesAndFixGivesThePrior) {
  G2oReadOptions options;
  options.prior_sigma_xy = 0.5;
  Dataset d;
  G2oReadSummary s;
  std::string error;
  ASSERT_TRUE(Parse(kG2o, options, &d, &s, &error)) << error;
  EXPECT_EQ(s.pose_vertices, 3u);
  EXPECT_EQ(s.landmark_vertices, 1u);
  EXPECT_EQ(s.times, "the vertex id order, 1 s apart");
  EXPECT_EQ(s.priors_added, 1u);
  ASSERT_EQ(d.pose_priors.size(), 1u);  // At vertex 11, second in id order.
  EXPECT_EQ(d.pose_priors[0].pose.t, 1.0);
  EXPECT_EQ(d.pose_priors[0].pose.theta, 0.5);
  EXPECT_EQ(d.pose_priors[0].sigma_xy, 0.5);
  ASSERT_EQ(d.odometry.size(), 1u);
  EXPECT_EQ(d.odometry[0].t0, 0.0);
  EXPECT_EQ(d.odometry[0].t1, 1.0);
  EXPECT_EQ(d.odometry[0].sigma_x, 0.1);
  EXPECT_EQ(d.odometry[0].sigma_y, 0.2);
  EXPECT_EQ(d.odometry[0].sigma_theta, 0.01);
  ASSERT_EQ(d.observations.size(), 2u);
  EXPECT_EQ(d.observations[0].type, ObservationType::kBearing);
  EXPECT_EQ(d.observations[0].t, 0.0);
  EXPECT_EQ(d.observations[0].sigma_bearing, 0.05);
  // (3, 0) with information diag(25, 11.1): range 3 +- 0.2 m, bearing 0 +-
  // 0.3 m / 3 m.
  const Observation& rb = d.observations[1];
  EXPECT_EQ(rb.type, ObservationType::kRangeBearing);
  EXPECT_EQ(rb.t, 2.0);
  EXPECT_EQ(rb.id, 3);
  EXPECT_EQ(rb.range, 3.0);
  EXPECT_EQ(rb.sigma_range, 0.2);
  EXPECT_DOUBLE_EQ(rb.sigma_bearing, 0.1);
  EXPECT_TRUE(d.ground_truth.empty());  // g2o vertices are estimates.
  ASSERT_EQ(d.metadata.size(), 2u);
  EXPECT_EQ(d.metadata[0].second, "hand-made");
  EXPECT_EQ(d.metadata[1].second,
            "'f.g2o' read by rff_convert --format=g2o, times from the vertex "
            "id order, 1 s apart");

  options.rate = 4.0;
  ASSERT_TRUE(Parse(kG2o, options, &d, &s, &error)) << error;
  EXPECT_EQ(d.observations[1].t, 0.5);
  EXPECT_EQ(s.times, "--rate=4 in vertex id order");
}

std::string ErrorOf(const std::string& text) {
  Dataset d;
  G2oReadSummary s;
  std::string error;
  EXPECT_FALSE(Parse(text, {}, &d, &s, &error));
  return error;
}

TEST(G2oReadTest, MalformedLinesNameFileAndLine) {
  const std::string poses = "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\n";
  EXPECT_EQ(ErrorOf(""), "f.g2o: no VERTEX_SE2 record (no pose)");
  EXPECT_EQ(
      ErrorOf(poses + "EDGE_SE3:QUAT 0 1 0 0 0 0 0 0 1\n"),
      "f.g2o:3: unknown record 'EDGE_SE3:QUAT' (g2o 2D here: "
      "VERTEX_SE2, VERTEX_XY, EDGE_SE2, EDGE_SE2_XY, EDGE_BEARING_SE2_XY, "
      "EDGE_PRIOR_SE2 and FIX)");
  EXPECT_EQ(ErrorOf("VERTEX_SE2 0 0 0\n"),
            "f.g2o:1: VERTEX_SE2 needs 4 fields, got 3");
  EXPECT_EQ(ErrorOf("FIX\n"), "f.g2o:1: FIX needs at least 1 fields, got 0");
  EXPECT_EQ(ErrorOf("VERTEX_SE2 -1 0 0 0\n"),
            "f.g2o:1: field 2 '-1' is not a vertex id (a non-negative "
            "integer)");
  EXPECT_EQ(ErrorOf("VERTEX_SE2 0 0 inf 0\n"),
            "f.g2o:1: field 4 'inf' is not a finite number");
  EXPECT_EQ(ErrorOf(poses + "VERTEX_XY 1 0 0\n"),
            "f.g2o:3: second vertex 1 (first on line 2)");
  EXPECT_EQ(ErrorOf("VERTEX_SE2 0 0 0 0 # t=soon\n"),
            "f.g2o:1: time comment 't=soon' is not t=SECONDS with a finite "
            "number");
  EXPECT_EQ(ErrorOf("VERTEX_SE2 0 0 0 0 # t=5\nVERTEX_SE2 1 0 0 0\n"),
            "f.g2o:2: VERTEX_SE2 1 has no '# t=SECONDS' comment while line 1 "
            "has one (--rate=HZ times every vertex by its order)");
  EXPECT_EQ(ErrorOf("VERTEX_SE2 0 0 0 0 # t=5\nVERTEX_SE2 1 0 0 0 # t=5\n"),
            "f.g2o:2: VERTEX_SE2 1 has the time 5 of VERTEX_SE2 0");
  EXPECT_EQ(ErrorOf(poses + "EDGE_SE2 1 0 1 0 0 1 0 0 1 0 1\n"),
            "f.g2o:3: EDGE_SE2 1 -> 0 does not go forward in time (1 -> 0; "
            ".rffd ODOM needs t1 > t0)");
  EXPECT_EQ(ErrorOf(poses + "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 -1\n"),
            "f.g2o:3: EDGE_SE2 information entry (3,3) = -1 is not > 0");
  EXPECT_EQ(ErrorOf(poses + "EDGE_SE2 0 7 1 0 0 1 0 0 1 0 1\n"),
            "f.g2o:3: EDGE_SE2 refers to vertex 7, which no VERTEX_SE2 or "
            "VERTEX_XY defines");
  EXPECT_EQ(ErrorOf(poses + "EDGE_SE2_XY 0 1 1 1 1 0 1\n"),
            "f.g2o:3: EDGE_SE2_XY: vertex 1 is a pose, expected a landmark");
  const std::string landmark = poses + "VERTEX_XY 5 1 1\n";
  EXPECT_EQ(ErrorOf(landmark + "EDGE_SE2_XY 0 5 1 1 1 2 1\n"),
            "f.g2o:4: EDGE_SE2_XY information is not positive definite");
  EXPECT_EQ(ErrorOf(landmark + "EDGE_SE2_XY 0 5 0 0 1 0 1\n"),
            "f.g2o:4: EDGE_SE2_XY relative position (0, 0) has no bearing");
  EXPECT_EQ(ErrorOf(landmark + "EDGE_SE2_XY 0 5 1 1 1 0 2\n"),
            "f.g2o:4: EDGE_SE2_XY as range and bearing the covariance has "
            "correlation -0.33333333333333337 (.rffd RANGE_BEARING sigmas are "
            "independent; at most 1e-06)");
  EXPECT_EQ(ErrorOf(poses + "EDGE_PRIOR_SE2 0 0 0 0 1 0 0 4 0 1\n"),
            "f.g2o:3: EDGE_PRIOR_SE2 x and y information differ (1, 4; .rffd "
            "PRIOR_POSE has one position sigma)");
  EXPECT_EQ(ErrorOf(poses + "VERTEX_XY 5 1 1\nFIX 5\n"),
            "f.g2o:4: FIX: vertex 5 is a landmark, expected a pose");
}

const char kRffd[] =
    "# source: test\n"
    "RFFD 1\n"
    "PRIOR_POSE 10 0 0 0 0.1 0.01\n"
    "PRIOR_LANDMARK 3 4 3 0.5\n"
    "ODOM 10 11 1 0 0.5 0.1 0.2 0.01\n"
    "RANGE 10.5 3 4.2 0.3\n"
    "RANGE_BEARING 11 3 3 0 0.2 0.1\n"
    "BEARING 11 3 0 0.1\n"
    "GT_POSE 10 0 0 0\n"
    "GT_LANDMARK 3 4 3\n";

TEST(G2oWriteTest, WritesEveryRecordG2oExpressesAndReadsItBack) {
  std::istringstream in(kRffd);
  Dataset d;
  std::string error;
  ASSERT_TRUE(ParseDataset(&in, "small.rffd", &d, &error)) << error;
  std::ostringstream out;
  G2oWriteSummary s;
  ASSERT_TRUE(WriteG2o(d, &out, &s, &error)) << error;
  // Poses after landmark 3, dead-reckoned; no vertex for the range.
  EXPECT_EQ(out.str(),
            "# source: test\n"
            "# g2o 2D written by rff_convert; '# t=' after a VERTEX_SE2 is "
            "the pose's time in seconds\n"
            "VERTEX_SE2 4 0 0 0 # t=10\n"
            "VERTEX_SE2 5 1 0 0.5 # t=11\n"
            "VERTEX_XY 3 4 3\n"
            "EDGE_PRIOR_SE2 4 0 0 0 99.99999999999999 0 0 99.99999999999999 0 "
            "10000\n"
            "EDGE_SE2 4 5 1 0 0.5 99.99999999999999 0 0 24.999999999999996 0 "
            "10000\n"
            "EDGE_SE2_XY 5 3 3 0 24.999999999999996 0 11.111111111111109\n"
            "EDGE_BEARING_SE2_XY 5 3 0 99.99999999999999\n");
  EXPECT_EQ(s.pose_vertices, 2u);
  EXPECT_EQ(s.landmark_vertices, 1u);
  EXPECT_EQ(s.ranges_left_out, 1u);
  EXPECT_EQ(s.landmark_priors_left_out, 1u);
  EXPECT_EQ(s.ground_truth_left_out, 2u);

  std::istringstream g2o(out.str());
  Dataset back;
  G2oReadSummary read;
  ASSERT_TRUE(ParseG2o(&g2o, "small.g2o", {}, &back, &read, &error)) << error;
  EXPECT_EQ(read.times, "the '# t=' comments");
  std::ostringstream rffd;
  WriteDataset(back, &rffd);
  EXPECT_EQ(rffd.str(),
            "# source: test\n"
            "# g2o: 'small.g2o' read by rff_convert --format=g2o, times from "
            "the '# t=' comments\n"
            "RFFD 1\n"
            "PRIOR_POSE 10 0 0 0 0.1 0.01\n"
            "ODOM 10 11 1 0 0.5 0.1 0.2 0.01\n"
            "RANGE_BEARING 11 3 3 0 0.2 0.1\n"
            "BEARING 11 3 0 0.1\n");
}

TEST(G2oWriteTest, IdsBeyondG2oIntAreRefused) {
  Dataset d;
  d.pose_priors.push_back({{0, 0, 0, 0}, 0.1, 0.1});
  Observation o;
  o.type = ObservationType::kBearing;
  o.id = 2147483647;
  o.sigma_bearing = 0.1;
  d.observations.push_back(o);
  std::ostringstream out;
  G2oWriteSummary s;
  std::string error;
  EXPECT_FALSE(WriteG2o(d, &out, &s, &error));
  EXPECT_EQ(error,
            "landmark id 2147483647 and 1 poses do not fit g2o's vertex ids "
            "(int)");
  EXPECT_EQ(out.str(), "");
  // The largest id of all, where adding the poses would overflow first.
  d.observations[0].id = std::numeric_limits<LandmarkId>::max();
  EXPECT_FALSE(WriteG2o(d, &out, &s, &error));
  EXPECT_EQ(error,
            "landmark id 9223372036854775807 does not fit g2o's vertex ids "
            "(int)");
  EXPECT_EQ(out.str(), "");
}

}  // namespace
}  // namespace rff
