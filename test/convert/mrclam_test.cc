#include "rff_ceres/convert/mrclam.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "rff_ceres/io/dataset_io.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/se2.h"
#include "test/test_files.h"

namespace rff {
namespace {

using ::testing::HasSubstr;

// The turning radius of the hand-made run: v = 1 m/s, omega = pi/2 rad/s.
const double kRadius = 2.0 / M_PI;

std::string TempDir() { return testing::TempDir("mrclam_test"); }
using testing::ReadFile;
using testing::WriteFile;

std::string N(double v) { return FormatNumber(v); }

// "t barcode range bearing" for a measurement of landmark (lx, ly) from the
// pose, with `range_offset` added to the true range.
std::string Measurement(double t, int barcode, const TimedPose& pose, double lx,
                        double ly, double range_offset) {
  const double range = std::hypot(lx - pose.x, ly - pose.y) + range_offset;
  const double bearing =
      WrapAngle(std::atan2(ly - pose.y, lx - pose.x) - pose.theta);
  return N(t) + " " + std::to_string(barcode) + " " + N(range) + " " +
         N(bearing) + "\n";
}

// Robot 1 drives 1 s straight at 1 m/s, then 1 s on a quarter circle
// (omega = pi/2), then stands. Ground truth at 0, 1, 2 and 10 s lies on that
// path. Landmark 6 (barcode 63) at (3, 4), landmark 7 (barcode 81) at
// (-2, 1); barcode 5 is robot 1, 70 is subject 9 without landmark truth,
// 99 is unknown. Measurements are out of time order.
void WriteSmallMrclam(const std::string& dir) {
  WriteFile(dir + "/Barcodes.dat",
            "# Subject #    Barcode #\n  1 \t 5\n  2 \t 14\n  6 \t 63\n"
            "  7 \t 81\n  9 \t 70\n");
  WriteFile(dir + "/Landmark_Groundtruth.dat",
            "# subject x y sx sy\n6 3 4 0.0001 0.0001\n"
            "7 -2 1 0.0001 0.0001\n");
  WriteFile(dir + "/Robot1_Odometry.dat",
            "# Time v omega\n0 1 0\n1 1 " + N(M_PI / 2) + "\n2 0 0\n10 0 0\n");
  WriteFile(dir + "/Robot1_Groundtruth.dat",
            "0 0 0 0\n1 1 0 0\n2 " + N(1 + kRadius) + " " + N(kRadius) + " " +
                N(M_PI / 2) + "\n10 " + N(1 + kRadius) + " " + N(kRadius) +
                " " + N(M_PI / 2) + "\n");
  // Poses that the converter interpolates from the ground truth.
  const TimedPose at_half{0.5, 0.5, 0.0, 0.0};
  const TimedPose at_1_2{1.2, 1 + 0.2 * (kRadius), 0.2 * kRadius,
                         0.2 * M_PI / 2};
  const TimedPose at_2{2.0, 1 + kRadius, kRadius, M_PI / 2};
  WriteFile(dir + "/Robot1_Measurement.dat",
            "# Time Subject range bearing\n" +
                Measurement(0.5, 63, at_half, 3, 4, 0.1) +
                Measurement(0.5, 81, at_half, -2, 1, 0.2) +
                Measurement(2.0, 63, at_2, 3, 4, 0.4) + "1.5 5 1 0\n" +
                "1.7 99 1 0\n1.8 70 1 0\n20 63 1 0\n" +
                Measurement(1.2, 81, at_1_2, -2, 1, 0.3));
}

void ExpectOdometry(const Odometry& o, double t0, double t1, double dx,
                    double dy, double dtheta) {
  EXPECT_EQ(o.t0, t0);
  EXPECT_EQ(o.t1, t1);
  EXPECT_NEAR(o.dx, dx, 1e-12);
  EXPECT_NEAR(o.dy, dy, 1e-12);
  EXPECT_NEAR(o.dtheta, dtheta, 1e-12);
}

TEST(IntegrateUnicycleTest, QuarterCircleAndStraightLine) {
  double x = 0, y = 0, theta = 0;
  IntegrateUnicycle(1.0, M_PI / 2, 1.0, &x, &y, &theta);
  EXPECT_NEAR(x, kRadius, 1e-15);
  EXPECT_NEAR(y, kRadius, 1e-15);
  EXPECT_NEAR(theta, M_PI / 2, 1e-15);
  // Straight on from there, heading +y.
  IntegrateUnicycle(2.0, 0.0, 0.5, &x, &y, &theta);
  EXPECT_NEAR(x, kRadius, 1e-15);
  EXPECT_NEAR(y, kRadius + 1.0, 1e-15);
  // Backwards on a clockwise arc: v < 0, omega < 0, a half circle.
  x = y = theta = 0;
  IntegrateUnicycle(-1.0, -1.0, M_PI, &x, &y, &theta);
  EXPECT_NEAR(x, 0.0, 1e-15);
  EXPECT_NEAR(y, 2.0, 1e-15);  // R = v / omega = 1, centre at (0, 1).
  EXPECT_NEAR(theta, -M_PI, 1e-15);
}

TEST(IntegrateUnicycleTest, TinyTurnRateMatchesTheArc) {
  double x = 0, y = 0, theta = 0;
  const double omega = 1e-5;
  IntegrateUnicycle(1.0, omega, 1.0, &x, &y, &theta);
  EXPECT_NEAR(x, 1.0 - omega * omega / 6.0, 1e-15);
  EXPECT_NEAR(y, omega / 2.0, 1e-15);
}

TEST(MrclamConvertTest, SmallInputAtMeasurementTimes) {
  const std::string dir = TempDir();
  WriteSmallMrclam(dir);
  MrclamOptions options;
  Dataset d;
  MrclamSummary s;
  std::string error;
  ASSERT_TRUE(ConvertMrclam(dir, options, &d, &s, &error)) << error;

  EXPECT_EQ(s.odometry_rows, 4u);
  EXPECT_EQ(s.ground_truth_rows, 4u);
  EXPECT_EQ(s.measurement_rows, 8u);
  EXPECT_EQ(s.dropped_robot, 1u);
  EXPECT_EQ(s.dropped_unknown, 2u);  // Barcode 99 and subject 9.
  EXPECT_EQ(s.dropped_outside_span, 1u);
  EXPECT_EQ(s.measurements_kept, 4u);
  EXPECT_EQ(s.trajectory_times, 3u);  // 0.5 (twice), 1.2, 2.

  ASSERT_EQ(d.observations.size(), 4u);
  EXPECT_EQ(d.observations[0].t, 0.5);
  EXPECT_EQ(d.observations[0].id, 6);
  EXPECT_EQ(d.observations[0].type, ObservationType::kRangeBearing);
  EXPECT_NEAR(d.observations[0].range, std::hypot(2.5, 4.0) + 0.1, 1e-15);
  EXPECT_NEAR(d.observations[0].bearing, std::atan2(4.0, 2.5), 1e-15);
  EXPECT_EQ(d.observations[0].sigma_range, 0.1);
  EXPECT_EQ(d.observations[0].sigma_bearing, 0.02);
  EXPECT_EQ(d.observations[1].id, 7);
  EXPECT_EQ(d.observations[2].t, 1.2);
  EXPECT_EQ(d.observations[3].t, 2.0);

  // 0.5 m straight, then 0.2 s of the arc (pi / 10); then 0.8 s of it.
  ASSERT_EQ(d.odometry.size(), 2u);
  const double a1 = M_PI / 10, a2 = 0.4 * M_PI;
  ExpectOdometry(d.odometry[0], 0.5, 1.2, 0.5 + kRadius * std::sin(a1),
                 kRadius * (1 - std::cos(a1)), a1);
  ExpectOdometry(d.odometry[1], 1.2, 2.0, kRadius * std::sin(a2),
                 kRadius * (1 - std::cos(a2)), a2);
  // Path lengths 0.7 m and 0.8 m at 0.1 per metre; theta 0.05 per second.
  EXPECT_NEAR(d.odometry[0].sigma_x, 0.07, 1e-15);
  EXPECT_EQ(d.odometry[0].sigma_y, d.odometry[0].sigma_x);
  EXPECT_NEAR(d.odometry[0].sigma_theta, 0.035, 1e-15);
  EXPECT_NEAR(d.odometry[1].sigma_x, 0.08, 1e-15);

  ASSERT_EQ(d.pose_priors.size(), 1u);
  EXPECT_EQ(d.pose_priors[0].pose.t, 0.5);
  EXPECT_EQ(d.pose_priors[0].pose.x, 0.5);
  EXPECT_EQ(d.pose_priors[0].pose.y, 0.0);
  EXPECT_EQ(d.pose_priors[0].pose.theta, 0.0);
  EXPECT_EQ(d.pose_priors[0].sigma_xy, 0.01);

  ASSERT_EQ(d.landmark_priors.size(), 2u);
  EXPECT_EQ(d.landmark_priors[0].id, 6);
  EXPECT_EQ(d.landmark_priors[0].x, 3.0);
  EXPECT_EQ(d.landmark_priors[0].sigma, 0.1);
  ASSERT_EQ(d.ground_truth_landmarks.size(), 2u);
  EXPECT_EQ(d.ground_truth_landmarks[1].x, -2.0);

  // GT rows inside [0.5, 2]: t = 1 and t = 2.
  ASSERT_EQ(d.ground_truth.size(), 2u);
  EXPECT_EQ(d.ground_truth[0].t, 1.0);
  EXPECT_EQ(d.ground_truth[1].t, 2.0);

  // Range offsets 0.1..0.4 m, bearings exact.
  EXPECT_EQ(s.agreement.count, 4u);
  EXPECT_NEAR(s.agreement.range_median, 0.25, 1e-12);
  EXPECT_NEAR(s.agreement.range_mad, 0.1, 1e-12);
  EXPECT_NEAR(s.agreement.bearing_median, 0.0, 1e-12);
  EXPECT_NEAR(s.agreement.bearing_mad, 0.0, 1e-12);

  std::ostringstream out;
  WriteDataset(d, &out);
  EXPECT_THAT(out.str(), HasSubstr("# source: UTIAS MRCLAM, directory "
                                   "'SmallInputAtMeasurementTimes', robot 1 "));
  EXPECT_THAT(out.str(),
              HasSubstr("# measurements: 8 rows, kept 4, dropped 1 of robots, "
                        "2 of unknown barcodes, 1 outside the "
                        "odometry/ground-truth times\n"));
  std::istringstream in(out.str());
  Dataset back;
  ASSERT_TRUE(ParseDataset(&in, "small.rffd", &back, &error)) << error;
  EXPECT_EQ(back.odometry.size(), 2u);
}

TEST(MrclamConvertTest, SmallInputWithRegularOdometryInterval) {
  const std::string dir = TempDir();
  WriteSmallMrclam(dir);
  MrclamOptions options;
  options.odometry_interval = 0.5;
  options.gt_rate_hz = 0.75;  // At least 1.33 s between GT_POSE rows.
  options.landmark_prior_sigma = 0.0;
  Dataset d;
  MrclamSummary s;
  std::string error;
  ASSERT_TRUE(ConvertMrclam(dir, options, &d, &s, &error)) << error;
  // Gaps 0.7 s and 0.8 s are each split in two.
  ASSERT_EQ(d.odometry.size(), 4u);
  EXPECT_EQ(d.odometry[0].t1, 0.85);
  EXPECT_EQ(d.odometry[2].t1, 1.6);
  const double a = 0.2 * M_PI;  // 0.4 s at pi / 2 rad/s.
  ExpectOdometry(d.odometry[2], 1.2, 1.6, kRadius * std::sin(a),
                 kRadius * (1 - std::cos(a)), a);
  ExpectOdometry(d.odometry[0], 0.5, 0.85, 0.35, 0.0, 0.0);
  // Composing the four steps lands on the ground truth at t = 2.
  TimedPose pose = d.pose_priors[0].pose;
  for (const Odometry& o : d.odometry) {
    const double c = std::cos(pose.theta), sn = std::sin(pose.theta);
    pose.x += c * o.dx - sn * o.dy;
    pose.y += sn * o.dx + c * o.dy;
    pose.theta += o.dtheta;
  }
  EXPECT_NEAR(pose.x, 1 + kRadius, 1e-12);
  EXPECT_NEAR(pose.y, kRadius, 1e-12);
  EXPECT_NEAR(pose.theta, M_PI / 2, 1e-12);
  EXPECT_TRUE(d.landmark_priors.empty());
  ASSERT_EQ(d.ground_truth.size(), 1u);
  EXPECT_EQ(d.ground_truth[0].t, 1.0);
}

// Runs the converter on the small input after replacing one file.
std::string ErrorWith(const std::string& dir, const std::string& file,
                      const std::string& text) {
  WriteSmallMrclam(dir);
  WriteFile(dir + "/" + file, text);
  Dataset d;
  MrclamSummary s;
  std::string error;
  EXPECT_FALSE(ConvertMrclam(dir, MrclamOptions(), &d, &s, &error));
  return error;
}

TEST(MrclamConvertTest, RawFileErrorsNameFileAndLine) {
  const std::string dir = TempDir();
  EXPECT_EQ(ErrorWith(dir, "Robot1_Odometry.dat", "# t v w\n0 1 0\n1 abc 0\n"),
            dir +
                "/Robot1_Odometry.dat:3: field 2 'abc' is not a finite "
                "number");
  EXPECT_EQ(ErrorWith(dir, "Robot1_Odometry.dat", "0 1 0\n1 1 0\n0.5 1 0\n"),
            dir +
                "/Robot1_Odometry.dat:3: time 0.5 decreases (previous "
                "row 1)");
  EXPECT_EQ(ErrorWith(dir, "Robot1_Groundtruth.dat", "0 0 0 0\n0 1 0 0\n"),
            dir +
                "/Robot1_Groundtruth.dat:2: time 0 does not increase "
                "(previous row 0)");
  EXPECT_EQ(ErrorWith(dir, "Robot1_Measurement.dat", "0.5 63 1\n"),
            dir + "/Robot1_Measurement.dat:1: expected 4 fields, got 3");
  EXPECT_EQ(ErrorWith(dir, "Robot1_Measurement.dat", "0.5 63 -1 0\n"),
            dir + "/Robot1_Measurement.dat:1: range must be >= 0, got -1");
  EXPECT_EQ(ErrorWith(dir, "Robot1_Measurement.dat", "0.5 6.3 1 0\n"),
            dir +
                "/Robot1_Measurement.dat:1: field 2 '6.3' is not a "
                "non-negative integer");
  EXPECT_EQ(ErrorWith(dir, "Barcodes.dat", "1 5\n2 5\n"),
            dir + "/Barcodes.dat:2: duplicate barcode 5");
  EXPECT_EQ(
      ErrorWith(dir, "Landmark_Groundtruth.dat", "6 3 4 0 0\n3 1 1 0 0\n"),
      dir +
          "/Landmark_Groundtruth.dat:2: subject 3 is a robot (1-5), "
          "not a landmark");
  EXPECT_EQ(ErrorWith(dir, "Robot1_Measurement.dat", "20 63 1 0\n"),
            dir +
                "/Robot1_Measurement.dat: no landmark measurement inside "
                "the odometry and ground-truth times");
}

TEST(MrclamConvertTest, MissingFileAndBadOptions) {
  const std::string dir = TempDir();
  WriteSmallMrclam(dir);
  MrclamOptions options;
  options.robot = 2;
  Dataset d;
  MrclamSummary s;
  std::string error;
  EXPECT_FALSE(ConvertMrclam(dir, options, &d, &s, &error));
  EXPECT_EQ(error, dir +
                       "/Robot2_Odometry.dat: cannot open for reading: No "
                       "such file or directory");
  options.robot = 6;
  EXPECT_FALSE(ConvertMrclam(dir, options, &d, &s, &error));
  EXPECT_EQ(error, "--mrclam_robot=6: allowed 1 to 5");
  options.robot = 1;
  options.odometry_interval = 0.005;
  EXPECT_FALSE(ConvertMrclam(dir, options, &d, &s, &error));
  EXPECT_EQ(error,
            "--mrclam_odometry_interval=0.005: allowed 0 (poses at "
            "measurement times only) or 0.01 s or more");
  options.odometry_interval = 0.0;
  options.bearing_sigma = -1.0;
  EXPECT_FALSE(ConvertMrclam(dir, options, &d, &s, &error));
  EXPECT_EQ(error, "--mrclam_bearing_sigma=-1: allowed more than 0");
}

// GT_POSE pose at time t by linear interpolation (t inside the rows).
TimedPose InterpolateTruth(const std::vector<TimedPose>& gt, double t) {
  auto upper = std::upper_bound(
      gt.begin(), gt.end(), t,
      [](double time, const TimedPose& p) { return time < p.t; });
  if (upper == gt.end()) return gt.back();
  if (upper == gt.begin()) return gt.front();
  const TimedPose& p0 = *(upper - 1);
  const double s = (t - p0.t) / (upper->t - p0.t);
  return {t, p0.x + s * (upper->x - p0.x), p0.y + s * (upper->y - p0.y), 0.0};
}

TEST(MrclamBundledTest, CountsFirstRecordsAndDeadReckoning) {
  const std::string path =
      std::string(RFF_SOURCE_DIR) + "/data/mrclam6_robot1.rffd";
  Dataset d;
  std::string error;
  ASSERT_TRUE(ReadDataset(path, &d, &error)) << error;
  EXPECT_EQ(d.pose_priors.size(), 1u);
  EXPECT_EQ(d.landmark_priors.size(), 15u);
  EXPECT_EQ(d.odometry.size(), 1393u);
  EXPECT_EQ(d.observations.size(), 1534u);
  EXPECT_EQ(d.ground_truth.size(), 6692u);
  EXPECT_EQ(d.ground_truth_landmarks.size(), 15u);
  bool found = false;
  for (const auto& [key, value] : d.metadata) {
    if (key != "measurements") continue;
    found = true;
    EXPECT_EQ(value,
              "1942 rows, kept 1534, dropped 407 of robots, 1 of unknown "
              "barcodes, 0 outside the odometry/ground-truth times");
  }
  EXPECT_TRUE(found);

  // Raw row 2 of Robot1_Measurement.dat: barcode 90 = subject 15.
  EXPECT_EQ(d.pose_priors[0].pose.t, 1248444189.599);
  const Observation& first = d.observations[0];
  EXPECT_EQ(first.type, ObservationType::kRangeBearing);
  EXPECT_EQ(first.t, 1248444189.599);
  EXPECT_EQ(first.id, 15);
  EXPECT_EQ(first.range, 6.758);
  EXPECT_EQ(first.bearing, -0.005);
  EXPECT_EQ(d.landmark_priors[0].id, 6);
  EXPECT_EQ(d.landmark_priors[0].x, 0.58831396);
  EXPECT_EQ(d.landmark_priors[0].sigma, 0.1);

  // The ODOM chain is contiguous with steps of at most 1 s.
  EXPECT_EQ(d.odometry.front().t0, d.pose_priors[0].pose.t);
  for (std::size_t k = 0; k + 1 < d.odometry.size(); ++k) {
    ASSERT_EQ(d.odometry[k].t1, d.odometry[k + 1].t0);
    ASSERT_LE(d.odometry[k].t1 - d.odometry[k].t0, 1.0 + 1e-6);
  }
  EXPECT_EQ(d.odometry.back().t1, 1248444927.166);

  // Dead reckoning on the commanded velocities ends metres off.
  TimedPose pose = d.pose_priors[0].pose;
  double sum_squares = 0.0, error_m = 0.0;
  for (const Odometry& o : d.odometry) {
    const double c = std::cos(pose.theta), sn = std::sin(pose.theta);
    pose.x += c * o.dx - sn * o.dy;
    pose.y += sn * o.dx + c * o.dy;
    pose.theta += o.dtheta;
    const TimedPose truth = InterpolateTruth(d.ground_truth, o.t1);
    error_m = std::hypot(pose.x - truth.x, pose.y - truth.y);
    sum_squares += error_m * error_m;
  }
  const double rms = std::sqrt(sum_squares / d.odometry.size());
  EXPECT_NEAR(rms, 2.65, 0.05);
  EXPECT_NEAR(error_m, 7.56, 0.05);
}

TEST(MrclamSharedTest, RawDataConvertsToTheBundledFile) {
  const std::string raw = std::string(RFF_SHARED_DIR) + "/data/mrclam6";
  if (!std::filesystem::exists(raw + "/Robot1_Odometry.dat")) {
    GTEST_SKIP() << "no raw MRCLAM data in " << raw;
  }
  MrclamOptions options;
  options.odometry_interval = 1.0;  // As bundled (docs/converters.md).
  Dataset d;
  MrclamSummary s;
  std::string error;
  ASSERT_TRUE(ConvertMrclam(raw, options, &d, &s, &error)) << error;
  EXPECT_EQ(s.odometry_rows, 61785u);
  EXPECT_EQ(s.ground_truth_rows, 49241u);
  EXPECT_EQ(s.measurement_rows, 1942u);
  EXPECT_EQ(s.dropped_robot, 407u);
  EXPECT_EQ(s.dropped_unknown, 1u);
  // Agreement with Vicon (SOURCES.md: ~0.05 m range MAD).
  EXPECT_NEAR(s.agreement.range_mad, 0.053, 0.001);
  EXPECT_NEAR(s.agreement.range_median, 0.038, 0.001);
  EXPECT_NEAR(s.agreement.bearing_mad, 0.0074, 0.0002);
  std::ostringstream out;
  WriteDataset(d, &out);
  EXPECT_TRUE(out.str() == ReadFile(std::string(RFF_SOURCE_DIR) +
                                    "/data/mrclam6_robot1.rffd"))
      << "data/mrclam6_robot1.rffd is stale: regenerate it "
         "(docs/converters.md)";
}

}  // namespace
}  // namespace rff
