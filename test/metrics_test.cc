#include "rff_ceres/metrics.h"

#include <cmath>
#include <sstream>

#include "ceres/jet.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "rff_ceres/io/text_parser.h"

namespace rff {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

constexpr double kDeg = 180.0 / M_PI;

// Ground truth of the hand-computed cases: along x, then a left turn.
std::vector<TimedPose> ThreePoses() {
  return {
      {0.0, 0.0, 0.0, 0.0}, {1.0, 1.0, 0.0, 0.0}, {2.0, 1.0, 1.0, M_PI / 2}};
}

void ExpectSummary(const ErrorSummary& s, double rms, double mean,
                   double median, double max, int count) {
  ASSERT_TRUE(s.available) << s.reason;
  EXPECT_NEAR(s.rms, rms, 1e-12);
  EXPECT_NEAR(s.mean, mean, 1e-12);
  EXPECT_NEAR(s.median, median, 1e-12);
  EXPECT_NEAR(s.max, max, 1e-12);
  EXPECT_EQ(s.count, count);
}

// Every estimated pose is the true one shifted by (0.3, -0.4) in the world
// and turned by +0.1 rad.
// APE: E_i = P_i^-1 Phat_i has translation R(-theta_i) (0.3, -0.4), norm 0.5,
// and angle 0.1, for every i.
// RPE 0->1: true motion (1, 0, 0); estimated R(-0.1) (1, 0) = (cos .1,
// -sin .1); E = (cos .1 - 1, -sin .1, 0), norm sqrt(2 - 2 cos .1) =
// 2 sin 0.05 = 0.0999583385413567. RPE 1->2: true (0, 1, pi/2); estimated
// (sin .1, cos .1, pi/2); E = R(-pi/2) (sin .1, cos .1 - 1) = (cos .1 - 1,
// -sin .1), the same norm; angles 0.
TEST(MetricsTest, RigidOffsetByHand) {
  std::vector<TimedPose> estimate = ThreePoses();
  for (TimedPose& p : estimate) {
    p.x += 0.3;
    p.y -= 0.4;
    p.theta += 0.1;
  }
  Evaluation e;
  std::string error;
  ASSERT_TRUE(Evaluate(ThreePoses(), {}, estimate, nullptr, {}, &e, &error))
      << error;
  ExpectSummary(e.ape_translation, 0.5, 0.5, 0.5, 0.5, 3);
  ExpectSummary(e.ape_rotation, 0.1, 0.1, 0.1, 0.1, 3);
  ExpectSummary(e.rpe_translation, 0.0999583385413567, 0.0999583385413567,
                0.0999583385413567, 0.0999583385413567, 2);
  ExpectSummary(e.rpe_rotation, 0.0, 0.0, 0.0, 0.0, 2);
  EXPECT_FALSE(e.aligned);
  EXPECT_FALSE(e.landmarks.evaluated);
}

// Only the middle pose is wrong: (1, 0.2, 0.3) instead of (1, 0, 0).
// APE translations {0, 0.2, 0}: RMS 0.2 / sqrt(3) = 0.115470053837925,
// mean 0.0666..., median 0, max 0.2; angles {0, 0.3, 0}: RMS 0.3 / sqrt(3).
// RPE 0->1: E = (0, 0.2, 0.3): 0.2 m, 0.3 rad. RPE 1->2: estimated motion
// R(-0.3) (0, 0.8) = 0.8 (sin .3, cos .3), angle pi/2 - 0.3; E = R(-pi/2)
// (0.8 sin .3, 0.8 cos .3 - 1) = (0.8 cos .3 - 1, -0.8 sin .3), angle -0.3,
// norm sqrt(1.64 - 1.6 cos .3) = 0.333858678783449.
// RPE translation RMS sqrt((0.04 + 1.64 - 1.6 cos .3) / 2) = 0.275192312210053.
TEST(MetricsTest, SinglePerturbedPoseByHand) {
  std::vector<TimedPose> estimate = ThreePoses();
  estimate[1] = {1.0, 1.0, 0.2, 0.3};
  Evaluation e;
  std::string error;
  ASSERT_TRUE(Evaluate(ThreePoses(), {}, estimate, nullptr, {}, &e, &error))
      << error;
  ExpectSummary(e.ape_translation, 0.115470053837925, 0.2 / 3, 0.0, 0.2, 3);
  ExpectSummary(e.ape_rotation, 0.173205080756888, 0.1, 0.0, 0.3, 3);
  ExpectSummary(e.rpe_translation, 0.275192312210053,
                0.5 * (0.2 + 0.333858678783449),
                0.5 * (0.2 + 0.333858678783449), 0.333858678783449, 2);
  ExpectSummary(e.rpe_rotation, 0.3, 0.3, 0.3, 0.3, 2);
}

TEST(Se2Test, ComposeInverseBetweenAndGenericWrap) {
  const Pose2 a{1.0, 2.0, 3.0};
  const Pose2 b{-0.5, 4.0, -2.5};
  // a * (a^-1 b) == b.
  const Pose2 ab = Compose(a, Between(a, b));
  EXPECT_NEAR(ab.x, b.x, 1e-12);
  EXPECT_NEAR(ab.y, b.y, 1e-12);
  EXPECT_NEAR(ab.theta, b.theta, 1e-12);
  const Pose2 identity = Compose(a, Inverse(a));
  EXPECT_NEAR(identity.x, 0.0, 1e-12);
  EXPECT_NEAR(identity.y, 0.0, 1e-12);
  EXPECT_EQ(identity.theta, 0.0);
  // (1, 0) seen from a pose at the origin turned by pi/2 lies at (0, -1).
  const Pose2 seen = Between(Pose2{0.0, 0.0, M_PI / 2}, Pose2{1.0, 0.0, 0.0});
  EXPECT_NEAR(seen.x, 0.0, 1e-12);
  EXPECT_NEAR(seen.y, -1.0, 1e-12);
  EXPECT_NEAR(seen.theta, -M_PI / 2, 1e-12);
  // The generic (Jet-capable) wrap agrees with WrapAngle: (-pi, pi].
  EXPECT_NEAR(WrapAngle<double>(3.0 * M_PI), M_PI, 1e-12);
  EXPECT_NEAR(WrapAngle<double>(-M_PI), M_PI, 1e-12);
  EXPECT_NEAR(WrapAngle<double>(-3.5), 2.0 * M_PI - 3.5, 1e-12);
  using Jet = ceres::Jet<double, 1>;
  const Pose2T<Jet> p{Jet(0.0), Jet(0.0), Jet(3.0, 0)};
  const Pose2T<Jet> q{Jet(1.0), Jet(0.0), Jet(0.5)};
  const Pose2T<Jet> pq = Compose(p, q);  // Heading 3.5 wraps to 3.5 - 2 pi.
  EXPECT_NEAR(pq.theta.a, 3.5 - 2.0 * M_PI, 1e-12);
  EXPECT_NEAR(pq.theta.v[0], 1.0, 1e-12);  // d theta / d p.theta.
  EXPECT_NEAR(pq.y.v[0], std::cos(3.0), 1e-12);
}

TEST(MetricsTest, SummarizeMedianOfOddAndEvenCounts) {
  ExpectSummary(Summarize({4.0, 1.0, 3.0}, ""), std::sqrt(26.0 / 3.0),
                8.0 / 3.0, 3.0, 4.0, 3);
  ExpectSummary(Summarize({4.0, 1.0, 3.0, 2.0}, ""), std::sqrt(30.0 / 4.0), 2.5,
                2.5, 4.0, 4);
  const ErrorSummary empty = Summarize({}, "why not");
  EXPECT_FALSE(empty.available);
  EXPECT_EQ(empty.reason, "why not");
}

TEST(MetricsTest, InterpolatesMidpointsAndHeadingAcrossPi) {
  // Heading from 3.0 to -3.0 runs the short way, through pi (0.2832 rad),
  // not back through 0.
  const std::vector<TimedPose> trajectory = {{0.0, 0.0, 0.0, 3.0},
                                             {2.0, 2.0, 4.0, -3.0}};
  std::vector<TimedPose> poses;
  std::string error;
  ASSERT_TRUE(InterpolateTrajectory(trajectory, {0.0, 0.5, 1.0, 1.5, 2.0},
                                    &poses, &error))
      << error;
  ASSERT_EQ(poses.size(), 5u);
  const double arc = 2.0 * M_PI - 6.0;  // 0.28318530717958623
  EXPECT_EQ(poses[0].theta, 3.0);       // Sample times are exact.
  EXPECT_EQ(poses[4].theta, -3.0);
  EXPECT_EQ(poses[4].x, 2.0);
  EXPECT_DOUBLE_EQ(poses[1].t, 0.5);
  EXPECT_NEAR(poses[1].x, 0.5, 1e-15);
  EXPECT_NEAR(poses[1].y, 1.0, 1e-15);
  EXPECT_NEAR(poses[1].theta, 3.0 + 0.25 * arc, 1e-12);  // 3.0708
  EXPECT_NEAR(poses[2].x, 1.0, 1e-15);
  EXPECT_NEAR(poses[2].y, 2.0, 1e-15);
  EXPECT_NEAR(poses[2].theta, M_PI, 1e-12);  // Wrapped to +pi, not -pi.
  EXPECT_NEAR(poses[3].theta, -3.0 - 0.25 * arc, 1e-12);  // Past pi: wrapped.
}

TEST(MetricsTest, TimesWithinToleranceGetTheEndPose) {
  const std::vector<TimedPose> trajectory = {{0.0, 0.0, 0.0, 0.0},
                                             {2.0, 2.0, 4.0, 1.0}};
  std::vector<TimedPose> poses;
  std::string error;
  ASSERT_TRUE(
      InterpolateTrajectory(trajectory, {-5e-7, 2.0 + 5e-7}, &poses, &error))
      << error;
  EXPECT_EQ(poses[0].x, 0.0);
  EXPECT_EQ(poses[1].x, 2.0);
  EXPECT_EQ(poses[1].theta, 1.0);
}

TEST(MetricsTest, OutOfSpanIsAnErrorNotAnExtrapolation) {
  const std::vector<TimedPose> trajectory = {{0.0, 0.0, 0.0, 0.0},
                                             {2.0, 2.0, 4.0, 1.0}};
  std::vector<TimedPose> poses;
  std::string error;
  EXPECT_FALSE(
      InterpolateTrajectory(trajectory, {-1.0, 0.5, 3.0, 4.0}, &poses, &error));
  EXPECT_EQ(error,
            "3 of 4 query times (span [-1, 4]) lie outside the trajectory's "
            "time span [0, 2] (1 before, 2 after, tolerance 1e-06 s); poses "
            "are not extrapolated");

  // Through Evaluate: the estimate stops before the last ground-truth time.
  std::vector<TimedPose> estimate = ThreePoses();
  estimate.back().t = 1.5;
  Evaluation e;
  EXPECT_FALSE(Evaluate(ThreePoses(), {}, estimate, nullptr, {}, &e, &error));
  EXPECT_EQ(error,
            "the estimated trajectory does not cover the ground truth: 1 of 3 "
            "ground-truth times (span [0, 2]) lie outside the trajectory's "
            "time span [0, 1.5] (0 before, 1 after, tolerance 1e-06 s); poses "
            "are not extrapolated");
}

TEST(MetricsTest, EstimateIsInterpolatedAtGroundTruthTimes) {
  // The estimate has poses at 0 and 2 only; at t = 1 it gives (0.5, 0.5,
  // pi/4), 0.5 m and pi/4 away from the true (1, 0, 0).
  const std::vector<TimedPose> estimate = {{0.0, 0.0, 0.0, 0.0},
                                           {2.0, 1.0, 1.0, M_PI / 2}};
  Evaluation e;
  std::string error;
  ASSERT_TRUE(Evaluate(ThreePoses(), {}, estimate, nullptr, {}, &e, &error))
      << error;
  EXPECT_NEAR(e.ape_translation.max, std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(e.ape_rotation.max, M_PI / 4, 1e-12);
  EXPECT_NEAR(e.ape_translation.rms, std::sqrt(0.5 / 3.0), 1e-12);
}

TEST(MetricsTest, AlignmentRecoversAKnownRigidTransform) {
  const std::vector<TimedPose> truth = {{0.0, 0.0, 0.0, 0.0},
                                        {1.0, 2.0, 0.5, 0.4},
                                        {2.0, 3.0, 2.5, 1.9},
                                        {3.0, 1.0, 4.0, -3.0},
                                        {4.0, -1.0, 2.0, -2.2}};
  const Pose2 transform{5.0, -7.0, 2.5};
  // The estimate lives in a frame moved by transform^-1.
  std::vector<TimedPose> estimate;
  std::vector<Pose2> source, target;
  for (const TimedPose& p : truth) {
    const Pose2 moved = Compose(Inverse(transform), ToPose2(p));
    estimate.push_back(ToTimedPose(p.t, moved));
    source.push_back(moved);
    target.push_back(ToPose2(p));
  }
  Pose2 found;
  std::string error;
  ASSERT_TRUE(AlignPositions(source, target, &found, &error)) << error;
  EXPECT_NEAR(found.x, 5.0, 1e-12);
  EXPECT_NEAR(found.y, -7.0, 1e-12);
  EXPECT_NEAR(found.theta, 2.5, 1e-12);

  const std::vector<Landmark> true_landmarks = {{3, 10.0, -4.0},
                                                {8, -2.0, 6.0}};
  std::vector<Landmark> estimated_landmarks = true_landmarks;
  for (Landmark& l : estimated_landmarks) {
    const Pose2 moved = Compose(Inverse(transform), Pose2{l.x, l.y, 0.0});
    l.x = moved.x;
    l.y = moved.y;
  }
  Evaluation e;
  ASSERT_TRUE(Evaluate(truth, true_landmarks, estimate, &estimated_landmarks,
                       {}, &e, &error))
      << error;
  EXPECT_GT(e.ape_translation.rms, 1.0);  // Unaligned: far off.
  EXPECT_NEAR(e.ape_rotation.rms, 2.5, 1e-12);

  EvaluationOptions align;
  align.align = true;
  ASSERT_TRUE(Evaluate(truth, true_landmarks, estimate, &estimated_landmarks,
                       align, &e, &error))
      << error;
  EXPECT_TRUE(e.aligned);
  EXPECT_NEAR(e.alignment.theta, 2.5, 1e-12);
  EXPECT_NEAR(e.alignment.x, 5.0, 1e-12);
  EXPECT_NEAR(e.ape_translation.max, 0.0, 1e-12);
  EXPECT_NEAR(e.ape_rotation.max, 0.0, 1e-12);
  EXPECT_NEAR(e.rpe_translation.max, 0.0, 1e-12);
  EXPECT_NEAR(e.landmarks.distance.max, 0.0, 1e-12);
  EXPECT_EQ(e.landmarks.matched, 2);
}

TEST(MetricsTest, AlignmentOfCoincidentPositionsIsAnError) {
  const std::vector<TimedPose> truth = {{0.0, 0.0, 0.0, 0.0},
                                        {1.0, 1.0, 0.0, 0.0}};
  const std::vector<TimedPose> estimate = {{0.0, 3.0, 3.0, 0.0},
                                           {1.0, 3.0, 3.0, 1.0}};
  EvaluationOptions align;
  align.align = true;
  Evaluation e;
  std::string error;
  EXPECT_FALSE(Evaluate(truth, {}, estimate, nullptr, align, &e, &error));
  EXPECT_EQ(error,
            "cannot align the estimate (source) onto the ground truth "
            "(target): alignment is undetermined: the source positions are "
            "all equal (need at least 2 distinct positions)");
}

// Distances: id 1 (3, 4) vs (0, 0): 5; id 2 (10, 1) vs (10, 0): 1. RMS
// sqrt((25 + 1) / 2) = sqrt(13); id 5 has no estimate, id 9 no ground truth.
TEST(MetricsTest, LandmarkErrorByHand) {
  const std::vector<Landmark> truth = {
      {1, 0.0, 0.0}, {2, 10.0, 0.0}, {5, 3.0, 3.0}};
  const std::vector<Landmark> estimate = {
      {1, 3.0, 4.0}, {2, 10.0, 1.0}, {9, 0.0, 0.0}};
  Evaluation e;
  std::string error;
  ASSERT_TRUE(
      Evaluate(ThreePoses(), truth, ThreePoses(), &estimate, {}, &e, &error))
      << error;
  const LandmarkEvaluation& l = e.landmarks;
  EXPECT_TRUE(l.evaluated);
  EXPECT_EQ(l.ground_truth_count, 3);
  EXPECT_EQ(l.estimate_count, 3);
  EXPECT_EQ(l.matched, 2);
  EXPECT_EQ(l.missing_ids, std::vector<LandmarkId>{5});
  EXPECT_EQ(l.unmatched_estimates, 1);
  ExpectSummary(l.distance, 3.605551275463989, 3.0, 3.0, 5.0, 2);
  EXPECT_EQ(e.ape_translation.rms, 0.0);  // Perfect trajectory.
}

TEST(MetricsTest, LandmarksWithoutMatchesOrGroundTruthAreNull) {
  const std::vector<Landmark> estimate = {{4, 1.0, 1.0}};
  Evaluation e;
  std::string error;
  ASSERT_TRUE(
      Evaluate(ThreePoses(), {}, ThreePoses(), &estimate, {}, &e, &error));
  EXPECT_FALSE(e.landmarks.distance.available);
  EXPECT_EQ(e.landmarks.distance.reason,
            "the dataset has no GT_LANDMARK record");
  ASSERT_TRUE(Evaluate(ThreePoses(), {{7, 0.0, 0.0}}, ThreePoses(), &estimate,
                       {}, &e, &error));
  EXPECT_EQ(e.landmarks.distance.reason,
            "no estimated landmark id matches a ground-truth id");
  EXPECT_EQ(e.landmarks.missing_ids, std::vector<LandmarkId>{7});
}

TEST(MetricsTest, RejectsMissingGroundTruthAndDuplicateLandmarks) {
  Evaluation e;
  std::string error;
  EXPECT_FALSE(Evaluate({}, {}, ThreePoses(), nullptr, {}, &e, &error));
  EXPECT_EQ(error, "no ground-truth poses (the dataset has no GT_POSE record)");
  const std::vector<Landmark> duplicates = {{4, 1.0, 1.0}, {4, 2.0, 1.0}};
  EXPECT_FALSE(
      Evaluate(ThreePoses(), {}, ThreePoses(), &duplicates, {}, &e, &error));
  EXPECT_EQ(error, "duplicate estimated landmark id 4");
}

TEST(MetricsTest, JsonHasNumbersAndNullsWithReasons) {
  // One ground-truth pose: APE works, RPE cannot.
  const std::vector<TimedPose> truth = {{1.0, 0.0, 0.0, 0.0}};
  const std::vector<TimedPose> estimate = {{0.0, 0.0, 0.0, 0.0},
                                           {2.0, 0.0, 2.0, 0.2}};
  Evaluation e;
  std::string error;
  ASSERT_TRUE(Evaluate(truth, {}, estimate, nullptr, {}, &e, &error)) << error;
  EXPECT_FALSE(e.rpe_translation.available);
  std::ostringstream json;
  WriteEvaluationJson(e, {{"trajectory", "a \"b\".tum"}}, &json);
  const std::string text = json.str();
  EXPECT_THAT(text, HasSubstr("\"trajectory\": \"a \\\"b\\\".tum\",\n"));
  EXPECT_THAT(text, HasSubstr("\"ground_truth_poses\": 1,\n"));
  EXPECT_THAT(text, HasSubstr("\"aligned\": false,\n  \"alignment\": null,\n"));
  // At t = 1 the estimate is (0, 1, 0.1): 1 m and 0.1 rad off.
  EXPECT_THAT(text, HasSubstr("\"ape_trans_m\": {\"rms\": 1, \"mean\": 1, "
                              "\"median\": 1, \"max\": 1, \"count\": 1},\n"));
  EXPECT_THAT(text, HasSubstr("\"ape_rot_deg\": {\"rms\": " +
                              FormatNumber(0.1 * kDeg)));
  EXPECT_THAT(text, HasSubstr("\"rpe_trans_m\": null,\n  "
                              "\"rpe_trans_m_reason\": \"RPE needs at least 2 "
                              "ground-truth poses, got 1\",\n"));
  EXPECT_THAT(text, HasSubstr("\"rpe_rot_deg\": null,\n"));
  EXPECT_THAT(text, HasSubstr("\"landmark_error_m\": null,\n  "
                              "\"landmark_error_m_reason\": \"no estimated "
                              "landmarks given\""));
  EXPECT_THAT(text, Not(HasSubstr("nan")));
  EXPECT_EQ(text.front(), '{');
  EXPECT_EQ(text.substr(text.size() - 2), "}\n");
}

// The text table of three estimated poses shifted by `dx` in x.
std::string TableOfShift(double dx) {
  std::vector<TimedPose> estimate = ThreePoses();
  for (TimedPose& p : estimate) p.x += dx;
  Evaluation e;
  std::string error;
  EXPECT_TRUE(Evaluate(ThreePoses(), {}, estimate, nullptr, {}, &e, &error))
      << error;
  std::ostringstream table;
  PrintEvaluation(e, &table);
  return table.str();
}

TEST(MetricsTest, TableShowsEveryMetric) {
  const std::string table = TableOfShift(0.5);
  EXPECT_THAT(table,
              HasSubstr("APE translation [m]      0.500000     0.500000     "
                        "0.500000     0.500000       3\n"));
  EXPECT_THAT(table, HasSubstr("RPE rotation [deg]"));
  EXPECT_THAT(table, HasSubstr("landmarks [m]         n/a (no estimated "
                               "landmarks given)\n"));
}

// Errors too large for a fixed-point cell keep the table's columns.
TEST(MetricsTest, TableShowsHugeErrorsInExponentForm) {
  EXPECT_THAT(TableOfShift(1e200),
              HasSubstr("APE translation [m]        1e+200       1e+200       "
                        "1e+200       1e+200       3\n"));
  EXPECT_THAT(TableOfShift(123456.5),
              HasSubstr("APE translation [m]        123456       123456       "
                        "123456       123456       3\n"));
}

}  // namespace
}  // namespace rff
