#include "rff_ceres/convert/plaza.h"

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
#include "test/test_files.h"

namespace rff {
namespace {

using ::testing::HasSubstr;

std::string TempDir() { return testing::TempDir("plaza_test"); }
using testing::ReadFile;
using testing::WriteFile;

// Composes the ODOM increments from the PRIOR_POSE (dead reckoning) and
// returns the RMS translation error against GT_POSE at the ODOM end times,
// which are GT times on Plaza.
double DeadReckoningRms(const Dataset& d) {
  TimedPose pose = d.pose_priors.at(0).pose;
  double sum_squares = 0.0;
  std::size_t gt_index = 1;
  for (const Odometry& o : d.odometry) {
    const double c = std::cos(pose.theta), s = std::sin(pose.theta);
    pose.x += c * o.dx - s * o.dy;
    pose.y += s * o.dx + c * o.dy;
    pose.theta += o.dtheta;
    const TimedPose& truth = d.ground_truth.at(gt_index++);
    EXPECT_EQ(truth.t, o.t1);
    sum_squares +=
        std::pow(pose.x - truth.x, 2) + std::pow(pose.y - truth.y, 2);
  }
  return std::sqrt(sum_squares / d.odometry.size());
}

// The robot drives along x at 1 m/s (heading 0, written unwrapped as 2 pi);
// beacon 3 sits at (0, 10), beacon 8 at (20, 0). The raw ranges are
// (r_true - 0.5) / 0.9, so the fit must give a = 0.9, b = 0.5 exactly, except
// one outlier 30 m long. TD is out of time order.
constexpr double kA = 0.9;
constexpr double kB = 0.5;

double RawRange(double t, double bx, double by) {
  return (std::hypot(bx - t, by) - kB) / kA;
}

void WriteSmallPlaza(const std::string& dir) {
  const double two_pi = 2.0 * M_PI;
  std::ostringstream gt;
  gt << "# time x y heading\n";
  for (int k = 0; k <= 4; ++k) {
    gt << k << " " << k << " 0 " << FormatNumber(two_pi) << "\n";
  }
  WriteFile(dir + "/Tiny_GT.txt", gt.str());
  WriteFile(dir + "/Tiny_DR.txt",
            "# time d dtheta\n1 1 0\n2 1 0.05\n3 1 -0.1\n4 1 6.4\n");
  WriteFile(dir + "/Tiny_TL.txt", "3 0 10\n8 20 0\n");
  std::ostringstream td;
  const double times[] = {0.5, 1.5, 2.5, 3.5, 1.0, 2.0, 3.0, 0.25};
  for (const double t : times) {
    td << FormatNumber(t) << " 2 3 " << FormatNumber(RawRange(t, 0, 10))
       << "\n";
    td << FormatNumber(t) << " 2 8 " << FormatNumber(RawRange(t, 20, 0))
       << "\n";
  }
  td << "3.75 2 8 " << FormatNumber(RawRange(3.75, 20, 0) + 30.0) << "\n";
  td << "5 2 8 10\n";  // After the last GT time: outside the trajectory.
  WriteFile(dir + "/Tiny_TD.txt", td.str());
}

TEST(FitLinearRangeCalibrationTest, RecoversLineAndRejectsOutlier) {
  // truth = 2 * measured + 1 except the last pair.
  const std::vector<double> measured = {1, 2, 3, 4, 5, 6, 7, 8, 3};
  const std::vector<double> truth = {3, 5, 7, 9, 11, 13, 15, 17, 20};
  LinearRangeFit fit;
  std::string error;
  ASSERT_TRUE(FitLinearRangeCalibration(measured, truth, 2.0, &fit, &error))
      << error;
  EXPECT_NEAR(fit.a, 2.0, 1e-12);
  EXPECT_NEAR(fit.b, 1.0, 1e-12);
  EXPECT_NEAR(fit.inlier_sigma, 0.0, 1e-12);
  EXPECT_EQ(fit.num_inliers, 8u);
  EXPECT_EQ(fit.inlier, std::vector<bool>({true, true, true, true, true, true,
                                           true, true, false}));
}

TEST(FitLinearRangeCalibrationTest, InlierSigmaUsesTwoDegreesOfFreedomLess) {
  // Residuals +-0.1 about truth = measured: sigma = sqrt(4 * 0.01 / 2).
  const std::vector<double> measured = {0, 1, 2, 3};
  const std::vector<double> truth = {0.1, 0.9, 1.9, 3.1};
  LinearRangeFit fit;
  std::string error;
  ASSERT_TRUE(FitLinearRangeCalibration(measured, truth, 2.0, &fit, &error));
  EXPECT_NEAR(fit.a, 1.0, 1e-12);
  EXPECT_NEAR(fit.b, 0.0, 1e-12);
  EXPECT_NEAR(fit.inlier_sigma, std::sqrt(0.04 / 2.0), 1e-12);
}

TEST(FitLinearRangeCalibrationTest, RejectsANonPositiveScale) {
  // Ranges that grow as the true distance shrinks (ground truth run
  // backwards against them): no sensor does that.
  const std::vector<double> measured = {10, 20, 30, 40, 50};
  const std::vector<double> truth = {48, 38.5, 29, 19.5, 10};
  LinearRangeFit fit;
  std::string error;
  EXPECT_FALSE(FitLinearRangeCalibration(measured, truth, 2.0, &fit, &error));
  EXPECT_EQ(error,
            "range calibration: the fitted scale a = -0.95 (b = 57.5 m) is "
            "not positive, which no range sensor produces: the ranges do not "
            "match the ground truth");
}

TEST(FitLinearRangeCalibrationTest, RejectsDegenerateInput) {
  LinearRangeFit fit;
  std::string error;
  EXPECT_FALSE(FitLinearRangeCalibration({1, 2}, {1, 2}, 2.0, &fit, &error));
  EXPECT_EQ(error, "range calibration needs at least 3 ranges, got 2");
  EXPECT_FALSE(
      FitLinearRangeCalibration({4, 4, 4}, {1, 2, 3}, 2.0, &fit, &error));
  EXPECT_EQ(error, "range calibration: all measured ranges are equal");
}

TEST(PlazaConvertTest, SmallInputLinearCalibration) {
  const std::string dir = TempDir();
  WriteSmallPlaza(dir);
  PlazaOptions options;
  options.name = "Tiny";
  Dataset d;
  PlazaSummary s;
  std::string error;
  ASSERT_TRUE(ConvertPlaza(dir, options, &d, &s, &error)) << error;

  EXPECT_EQ(s.ground_truth_rows, 5u);
  EXPECT_EQ(s.odometry_rows, 4u);
  EXPECT_EQ(s.range_rows, 18u);
  EXPECT_EQ(s.ranges_out_of_order, 8u);  // 1.0, 2.0, 3.0, 0.25 (2 each).
  EXPECT_EQ(s.ranges_outside_span, 1u);
  EXPECT_EQ(s.ranges_rejected, 1u);
  EXPECT_EQ(s.ranges_kept, 16u);
  EXPECT_NEAR(s.fit.a, kA, 1e-12);
  EXPECT_NEAR(s.fit.b, kB, 1e-11);
  EXPECT_DOUBLE_EQ(s.range_sigma, 0.1);  // Perfect fit: the 0.1 m floor.

  ASSERT_EQ(d.pose_priors.size(), 1u);
  EXPECT_EQ(d.pose_priors[0].pose.t, 0.0);
  EXPECT_NEAR(d.pose_priors[0].pose.theta, 0.0, 1e-15);  // 2 pi wrapped.
  EXPECT_EQ(d.pose_priors[0].sigma_xy, 0.02);
  EXPECT_EQ(d.pose_priors[0].sigma_theta, 0.01);

  ASSERT_EQ(d.odometry.size(), 4u);
  EXPECT_EQ(d.odometry[1].t0, 1.0);
  EXPECT_EQ(d.odometry[1].t1, 2.0);
  EXPECT_EQ(d.odometry[1].dx, 1.0);
  EXPECT_EQ(d.odometry[1].dy, 0.0);
  EXPECT_EQ(d.odometry[1].dtheta, 0.05);
  EXPECT_EQ(d.odometry[1].sigma_x, 0.05);  // 0.05 per metre over 1 m.
  EXPECT_EQ(d.odometry[1].sigma_y, 0.05);
  EXPECT_EQ(d.odometry[1].sigma_theta, 0.005);  // Floor (0.05 * 0.05).
  EXPECT_NEAR(d.odometry[3].dtheta, 6.4 - 2.0 * M_PI, 1e-12);
  EXPECT_EQ(d.odometry[3].sigma_theta, 0.05 * WrapAngle(6.4));

  // Sorted by time, corrected, the outlier and the late range gone.
  ASSERT_EQ(d.observations.size(), 16u);
  EXPECT_EQ(d.observations[0].t, 0.25);
  EXPECT_EQ(d.observations[0].id, 3);
  EXPECT_NEAR(d.observations[0].range, std::hypot(0.25, 10.0), 1e-10);
  EXPECT_EQ(d.observations[1].id, 8);
  EXPECT_NEAR(d.observations[1].range, std::hypot(19.75, 0.0), 1e-10);
  EXPECT_EQ(d.observations.back().t, 3.5);
  for (const Observation& o : d.observations) {
    EXPECT_EQ(o.type, ObservationType::kRange);
    EXPECT_EQ(o.sigma_range, 0.1);
  }

  ASSERT_EQ(d.ground_truth.size(), 5u);
  EXPECT_NEAR(d.ground_truth[4].theta, 0.0, 1e-15);
  ASSERT_EQ(d.landmark_priors.size(), 2u);
  EXPECT_EQ(d.landmark_priors[1].id, 8);
  EXPECT_EQ(d.landmark_priors[1].x, 20.0);
  EXPECT_EQ(d.landmark_priors[1].sigma, 1.0);
  ASSERT_EQ(d.ground_truth_landmarks.size(), 2u);
  EXPECT_EQ(d.ground_truth_landmarks[0].y, 10.0);

  // The written file reads back through the strict reader.
  std::ostringstream out;
  WriteDataset(d, &out);
  std::istringstream in(out.str());
  Dataset back;
  ASSERT_TRUE(ParseDataset(&in, "tiny.rffd", &back, &error)) << error;
  EXPECT_EQ(back.observations.size(), 16u);
  EXPECT_THAT(out.str(), HasSubstr("# calibration: range = a * raw + b"));
  EXPECT_THAT(out.str(), HasSubstr("kept 16 of 18"));
}

TEST(PlazaConvertTest, SmallInputWithoutCalibrationKeepsRawRanges) {
  const std::string dir = TempDir();
  WriteSmallPlaza(dir);
  PlazaOptions options;
  options.name = "Tiny";
  options.calibration = PlazaCalibration::kNone;
  options.range_sigma = 2.5;
  options.landmark_prior_sigma = 0.0;
  Dataset d;
  PlazaSummary s;
  std::string error;
  ASSERT_TRUE(ConvertPlaza(dir, options, &d, &s, &error)) << error;
  EXPECT_EQ(s.ranges_rejected, 0u);
  EXPECT_EQ(s.ranges_kept, 17u);  // The outlier stays; the late one not.
  ASSERT_EQ(d.observations.size(), 17u);
  EXPECT_EQ(d.observations[0].range, RawRange(0.25, 0, 10));
  EXPECT_EQ(d.observations[0].sigma_range, 2.5);
  EXPECT_TRUE(d.landmark_priors.empty());
  EXPECT_EQ(d.ground_truth_landmarks.size(), 2u);
}

TEST(PlazaConvertTest, ParsesCalibrationName) {
  PlazaCalibration c;
  std::string error;
  ASSERT_TRUE(ParsePlazaCalibration("none", &c, &error));
  EXPECT_EQ(c, PlazaCalibration::kNone);
  ASSERT_TRUE(ParsePlazaCalibration("linear", &c, &error));
  EXPECT_EQ(c, PlazaCalibration::kLinear);
  EXPECT_FALSE(ParsePlazaCalibration("robust", &c, &error));
  EXPECT_EQ(error,
            "--plaza_calibration=robust: unknown calibration; allowed linear "
            "or none");
}

// Runs the converter on the small input after replacing one file.
std::string ErrorWith(const std::string& dir, const std::string& file,
                      const std::string& text) {
  WriteSmallPlaza(dir);
  WriteFile(dir + "/" + file, text);
  PlazaOptions options;
  options.name = "Tiny";
  Dataset d;
  PlazaSummary s;
  std::string error;
  EXPECT_FALSE(ConvertPlaza(dir, options, &d, &s, &error));
  return error;
}

TEST(PlazaConvertTest, RawFileErrorsNameFileAndLine) {
  const std::string dir = TempDir();
  EXPECT_EQ(ErrorWith(dir, "Tiny_GT.txt", "# header\n0 0 0 0\n1 1 zero 0\n"),
            dir + "/Tiny_GT.txt:3: field 3 'zero' is not a finite number");
  EXPECT_EQ(ErrorWith(dir, "Tiny_GT.txt", "0 0 0 0\n1 1 0\n"),
            dir + "/Tiny_GT.txt:2: expected 4 fields, got 3");
  EXPECT_EQ(ErrorWith(dir, "Tiny_GT.txt", "0 0 0 0\n1 1 0 0\n1 2 0 0\n"),
            dir + "/Tiny_GT.txt:3: time 1 does not increase (previous row 1)");
  EXPECT_EQ(ErrorWith(dir, "Tiny_DR.txt", "1 1 0\n2.5 1 0\n"),
            dir +
                "/Tiny_DR.txt:2: time 2.5 does not match ground-truth row "
                "3 time 2 (DR row k moves GT pose k to k + 1)");
  EXPECT_EQ(ErrorWith(dir, "Tiny_DR.txt", "1 1 0\n2 1 0\n"),
            dir +
                "/Tiny_DR.txt: 2 rows, expected 4 (one per ground-truth "
                "row after the first)");
  EXPECT_EQ(ErrorWith(dir, "Tiny_TD.txt", "0.5 2 3 10\n0.7 2 4 10\n"),
            dir +
                "/Tiny_TD.txt:2: beacon 4 is not in the beacon list (TL "
                "file)");
  EXPECT_EQ(ErrorWith(dir, "Tiny_TD.txt", "0.5 2 3 -1\n"),
            dir + "/Tiny_TD.txt:1: range must be >= 0, got -1");
  EXPECT_EQ(ErrorWith(dir, "Tiny_TD.txt", "0.5 2 -3 1\n"),
            dir +
                "/Tiny_TD.txt:1: field 3 '-3' is not a non-negative "
                "integer");
  EXPECT_EQ(ErrorWith(dir, "Tiny_TL.txt", "3 0 10\n3 1 1\n"),
            dir + "/Tiny_TL.txt:2: duplicate beacon 3");
  EXPECT_EQ(ErrorWith(dir, "Tiny_TL.txt", "# nothing\n"),
            dir + "/Tiny_TL.txt: no data rows");
}

TEST(PlazaConvertTest, MissingFileIsAClearError) {
  const std::string dir = TempDir();
  WriteSmallPlaza(dir);
  std::filesystem::remove(dir + "/Tiny_TD.txt");
  PlazaOptions options;
  options.name = "Tiny";
  Dataset d;
  PlazaSummary s;
  std::string error;
  EXPECT_FALSE(ConvertPlaza(dir, options, &d, &s, &error));
  EXPECT_EQ(error, dir +
                       "/Tiny_TD.txt: cannot open for reading: No such file "
                       "or directory");
}

TEST(PlazaConvertTest, RejectsBadOptions) {
  PlazaOptions options;
  options.odometry_sigma_xy_floor = 0.0;
  Dataset d;
  PlazaSummary s;
  std::string error;
  EXPECT_FALSE(ConvertPlaza("/nonexistent", options, &d, &s, &error));
  EXPECT_EQ(error, "--plaza_odom_sigma_xy_floor=0: allowed more than 0");
  options = PlazaOptions();
  options.name = "";
  EXPECT_FALSE(ConvertPlaza("/nonexistent", options, &d, &s, &error));
  EXPECT_EQ(error,
            "--plaza_name=: empty; allowed a file prefix such as Plaza1");
  // A path would read files the output check does not see.
  options.name = "../other/Plaza1";
  EXPECT_FALSE(ConvertPlaza("/nonexistent", options, &d, &s, &error));
  EXPECT_EQ(error,
            "--plaza_name=../other/Plaza1: holds a '/'; allowed a file prefix "
            "such as Plaza1 (the directory goes in --input)");
}

// A raw Plaza recording whose odometry frame is the GT heading frame turned
// by `offset`: the robot drives a weaving path (with two reversing steps) of
// DR increments Pose2(d, 0, dtheta) in its odometry frame, and GT_k carries
// the odometry heading minus `offset`, as gpslam's init_heading_offset
// defines. `header` is written at the top of GT and DR (empty: none).
struct RotatedPlaza {
  std::vector<double> distance, turn;  // DR rows.
  std::vector<TimedPose> truth;        // GT rows, headings unwrapped.
};

RotatedPlaza WriteRotatedPlaza(const std::string& dir, double offset,
                               const std::string& header) {
  RotatedPlaza raw;
  double x = 3.0, y = -2.0, heading = 0.7;  // Odometry frame.
  raw.truth.push_back({0.0, x, y, heading - offset});
  for (int k = 0; k < 60; ++k) {
    const double d = (k == 10 || k == 11) ? -0.4 : 0.5;
    const double turn = 0.3 * std::sin(k / 5.0);
    x += d * std::cos(heading);
    y += d * std::sin(heading);
    heading += turn;
    raw.distance.push_back(d);
    raw.turn.push_back(turn);
    raw.truth.push_back({k + 1.0, x, y, heading - offset});
  }
  std::ostringstream gt, dr, td;
  gt << header;
  dr << header;
  for (std::size_t k = 0; k < raw.truth.size(); ++k) {
    const TimedPose& p = raw.truth[k];
    gt << FormatNumber(p.t) << " " << FormatNumber(p.x) << " "
       << FormatNumber(p.y) << " " << FormatNumber(p.theta) << "\n";
    if (k > 0) {
      dr << FormatNumber(p.t) << " " << FormatNumber(raw.distance[k - 1]) << " "
         << FormatNumber(raw.turn[k - 1]) << "\n";
    }
    // Beacon 3 at (0, 10), raw ranges as in WriteSmallPlaza.
    td << FormatNumber(p.t) << " 2 3 "
       << FormatNumber((std::hypot(p.x, p.y - 10.0) - kB) / kA) << "\n";
  }
  WriteFile(dir + "/Rot_GT.txt", gt.str());
  WriteFile(dir + "/Rot_DR.txt", dr.str());
  WriteFile(dir + "/Rot_TL.txt", "3 0 10\n");
  WriteFile(dir + "/Rot_TD.txt", td.str());
  return raw;
}

std::string OffsetHeader(double offset) {
  return "# Rot: time d dtheta\n# init_heading_offset[rad] = " +
         FormatNumber(offset) +
         " (add to GT heading to get the heading frame of DR)\n";
}

// Composes the ODOM records from the PRIOR_POSE and returns the largest
// position and heading gap to `truth` at the ODOM end times.
void DeadReckoningGap(const Dataset& d, const std::vector<TimedPose>& truth,
                      double* position_gap, double* heading_gap) {
  *position_gap = *heading_gap = 0.0;
  TimedPose pose = d.pose_priors.at(0).pose;
  ASSERT_EQ(d.odometry.size() + 1, truth.size());
  for (std::size_t k = 0; k < d.odometry.size(); ++k) {
    const Odometry& o = d.odometry[k];
    ASSERT_EQ(o.t0, pose.t);
    const double c = std::cos(pose.theta), s = std::sin(pose.theta);
    pose = {o.t1, pose.x + c * o.dx - s * o.dy, pose.y + s * o.dx + c * o.dy,
            pose.theta + o.dtheta};
    const TimedPose& t = truth[k + 1];
    ASSERT_EQ(pose.t, t.t);
    *position_gap =
        std::max(*position_gap, std::hypot(pose.x - t.x, pose.y - t.y));
    *heading_gap =
        std::max(*heading_gap, std::abs(WrapAngle(pose.theta - t.theta)));
  }
}

bool ConvertRotated(const std::string& dir, const PlazaOptions& base,
                    Dataset* d, PlazaSummary* s, std::string* error) {
  PlazaOptions options = base;
  options.name = "Rot";
  return ConvertPlaza(dir, options, d, s, error);
}

TEST(PlazaHeadingOffsetTest, OdometryComposesToTheTruthInAnyFrame) {
  const double offsets[] = {0.0, M_PI_2, M_PI, -M_PI_2, 0.3, -2.5};
  for (const double offset : offsets) {
    for (const bool declared : {true, false}) {
      // Undeclared offsets are rounded to a multiple of pi/2.
      if (!declared && (offset == 0.3 || offset == -2.5)) continue;
      SCOPED_TRACE("offset " + FormatNumber(offset) +
                   (declared ? " declared" : " measured"));
      const std::string dir = TempDir();
      const RotatedPlaza raw =
          WriteRotatedPlaza(dir, offset, declared ? OffsetHeader(offset) : "");
      Dataset d;
      PlazaSummary s;
      std::string error;
      ASSERT_TRUE(ConvertRotated(dir, PlazaOptions(), &d, &s, &error)) << error;
      EXPECT_NEAR(WrapAngle(s.heading_offset - offset), 0.0, 1e-15);
      EXPECT_NEAR(WrapAngle(s.measured_heading_offset - offset), 0.0, 1e-12);
      EXPECT_EQ(s.heading_offset_source,
                declared ? "declared in Rot_GT.txt and Rot_DR.txt"
                         : "measured, not declared (nearest multiple of "
                           "pi/2)");

      // The prior is GT row 0, heading included, never the odometry heading.
      ASSERT_EQ(d.pose_priors.size(), 1u);
      EXPECT_EQ(d.pose_priors[0].pose.t, raw.truth[0].t);
      EXPECT_EQ(d.pose_priors[0].pose.x, raw.truth[0].x);
      EXPECT_EQ(d.pose_priors[0].pose.y, raw.truth[0].y);
      EXPECT_EQ(d.pose_priors[0].pose.theta, WrapAngle(raw.truth[0].theta));
      // GT_POSE is the GT as given.
      ASSERT_EQ(d.ground_truth.size(), raw.truth.size());
      EXPECT_EQ(d.ground_truth[5].theta, WrapAngle(raw.truth[5].theta));

      double position_gap, heading_gap;
      DeadReckoningGap(d, raw.truth, &position_gap, &heading_gap);
      EXPECT_LT(position_gap, 1e-12);
      EXPECT_LT(heading_gap, 1e-12);

      // The increments are the DR ones turned into the GT pose frame: the
      // length and the heading change do not depend on the frame.
      for (std::size_t k = 0; k < d.odometry.size(); ++k) {
        EXPECT_NEAR(std::hypot(d.odometry[k].dx, d.odometry[k].dy),
                    std::abs(raw.distance[k]), 1e-15);
        EXPECT_EQ(d.odometry[k].dtheta, raw.turn[k]);
      }
    }
  }
}

TEST(PlazaHeadingOffsetTest, AxisAlignedOffsetsGiveExactIncrements) {
  const std::string dir = TempDir();
  const RotatedPlaza raw = WriteRotatedPlaza(dir, M_PI, OffsetHeader(M_PI));
  Dataset d;
  PlazaSummary s;
  std::string error;
  ASSERT_TRUE(ConvertRotated(dir, PlazaOptions(), &d, &s, &error)) << error;
  EXPECT_EQ(d.odometry[0].dx, -0.5);
  EXPECT_EQ(d.odometry[0].dy, 0.0);
  EXPECT_FALSE(std::signbit(d.odometry[0].dy));  // Written "0", not "-0".
  EXPECT_EQ(d.odometry[10].dx, 0.4);             // A reversing step.
  std::ostringstream out;
  WriteDataset(d, &out);
  EXPECT_THAT(out.str(),
              HasSubstr("# heading_offset: odometry frame = GT heading + "
                        "3.1416 rad (declared in Rot_GT.txt and Rot_DR.txt; "
                        "measured from the GT displacements: 3.1416 rad)"));
  EXPECT_THAT(out.str(), HasSubstr("--plaza_heading_offset=auto"));
}

TEST(PlazaHeadingOffsetTest, TheOldReadingDrivesAwayFromTheTruth) {
  // What the converter did before it knew the offset: Pose2(d, 0, dtheta) in
  // the GT frame. With the frame pi off, dead reckoning runs backwards.
  const std::string dir = TempDir();
  const RotatedPlaza raw = WriteRotatedPlaza(dir, M_PI, OffsetHeader(M_PI));
  PlazaOptions forced;
  forced.heading_offset = 0.0;
  forced.heading_offset_tolerance = 4.0;  // Let the wrong frame through.
  Dataset d;
  PlazaSummary s;
  std::string error;
  ASSERT_TRUE(ConvertRotated(dir, forced, &d, &s, &error)) << error;
  double position_gap, heading_gap;
  DeadReckoningGap(d, raw.truth, &position_gap, &heading_gap);
  EXPECT_GT(position_gap, 10.0);
}

TEST(PlazaHeadingOffsetTest, OptionOverridesTheHeader) {
  const std::string dir = TempDir();
  // The header says 0 but the data are pi off: the option fixes it.
  const RotatedPlaza raw = WriteRotatedPlaza(dir, M_PI, OffsetHeader(0.0));
  PlazaOptions options;
  options.heading_offset = -M_PI;
  Dataset d;
  PlazaSummary s;
  std::string error;
  ASSERT_TRUE(ConvertRotated(dir, options, &d, &s, &error)) << error;
  EXPECT_EQ(s.heading_offset_source, "option");
  double position_gap, heading_gap;
  DeadReckoningGap(d, raw.truth, &position_gap, &heading_gap);
  EXPECT_LT(position_gap, 1e-12);
  std::ostringstream out;
  WriteDataset(d, &out);
  EXPECT_THAT(out.str(), HasSubstr("--plaza_heading_offset=-3.14159265358979"));
}

// Converts the rotated recording after replacing one file, expecting an
// error.
std::string RotatedError(const std::string& dir, double offset,
                         const std::string& header, const std::string& file,
                         const std::string& text,
                         const PlazaOptions& options = PlazaOptions()) {
  WriteRotatedPlaza(dir, offset, header);
  if (!file.empty()) WriteFile(dir + "/" + file, text);
  Dataset d;
  PlazaSummary s;
  std::string error;
  EXPECT_FALSE(ConvertRotated(dir, options, &d, &s, &error));
  return error;
}

TEST(PlazaHeadingOffsetTest, RejectsAnOffsetTheDataContradict) {
  const std::string dir = TempDir();
  // Declared 0, data pi off: the reported bug, now an error.
  EXPECT_EQ(RotatedError(dir, M_PI, OffsetHeader(0.0), "", ""),
            dir +
                "/Rot_DR.txt: the odometry moves the robot along the "
                "ground-truth heading + 3.1416 rad (measured from the GT "
                "displacements), but the heading offset is 0 rad (declared "
                "in Rot_GT.txt and Rot_DR.txt); set --plaza_heading_offset "
                "(or widen --plaza_heading_offset_tolerance, now 0.1 rad)");
  // Undeclared and not a multiple of pi/2.
  EXPECT_THAT(RotatedError(dir, 0.3, "", "", ""),
              HasSubstr("ground-truth heading + 0.3 rad (measured from the "
                        "GT displacements), but the heading offset is 0 rad "
                        "(measured, not declared (nearest multiple of "
                        "pi/2))"));
  // A wrong option is checked too.
  PlazaOptions wrong;
  wrong.heading_offset = 0.0;
  EXPECT_THAT(RotatedError(dir, M_PI_2, "", "", "", wrong),
              HasSubstr("but the heading offset is 0 rad (option)"));
}

// A robot that stands still neither declares its heading offset nor lets
// it be measured: the converter asks for it instead of assuming 0.
TEST(PlazaHeadingOffsetTest, AnOffsetNeitherDeclaredNorMeasurableIsAnError) {
  const std::string dir = TempDir();
  std::ostringstream gt, dr, td;
  for (int k = 0; k < 10; ++k) {
    gt << k << " 3 -2 0.7\n";
    if (k > 0) dr << k << " 0 0\n";
    // Beacons 3 at (0, 10) and 4 at (10, 0) in turn: two distances to fit.
    const double range =
        k % 2 ? std::hypot(-7.0, -2.0) : std::hypot(3.0, -12.0);
    td << k << " 2 " << 3 + k % 2 << " " << FormatNumber((range - kB) / kA)
       << "\n";
  }
  WriteFile(dir + "/Rot_GT.txt", gt.str());
  WriteFile(dir + "/Rot_DR.txt", dr.str());
  WriteFile(dir + "/Rot_TL.txt", "3 0 10\n4 10 0\n");
  WriteFile(dir + "/Rot_TD.txt", td.str());
  Dataset d;
  PlazaSummary s;
  std::string error;
  EXPECT_FALSE(ConvertRotated(dir, PlazaOptions(), &d, &s, &error));
  EXPECT_EQ(error, dir +
                       "/Rot_DR.txt: no init_heading_offset declared in the "
                       "headers, and the ground truth moves too little to "
                       "measure one; set --plaza_heading_offset");
  PlazaOptions given;
  given.heading_offset = 0.0;
  EXPECT_TRUE(ConvertRotated(dir, given, &d, &s, &error)) << error;
}

TEST(PlazaHeadingOffsetTest, RejectsBadDeclarations) {
  const std::string dir = TempDir();
  EXPECT_EQ(
      RotatedError(dir, 0.0, "# init_heading_offset[deg] = 180\n", "", ""),
      dir +
          "/Rot_GT.txt: header '# init_heading_offset[deg] = 180': the "
          "heading offset must be given in [rad]");
  EXPECT_EQ(RotatedError(dir, 0.0, "# init_heading_offset = pi\n", "", ""),
            dir +
                "/Rot_GT.txt: header '# init_heading_offset = pi': 'pi' is "
                "not a finite number");
  EXPECT_EQ(RotatedError(dir, 0.0, "# init_heading_offset 0\n", "", ""),
            dir +
                "/Rot_GT.txt: header '# init_heading_offset 0': expected '=' "
                "after init_heading_offset");
  // GT and DR must agree.
  WriteRotatedPlaza(dir, M_PI, OffsetHeader(M_PI));
  std::string dr = ReadFile(dir + "/Rot_DR.txt");
  dr.replace(dr.find("3.141592653589793"), 17, "3.1416");
  WriteFile(dir + "/Rot_DR.txt", dr);
  Dataset d;
  PlazaSummary s;
  std::string error;
  EXPECT_FALSE(ConvertRotated(dir, PlazaOptions(), &d, &s, &error));
  EXPECT_EQ(error, dir +
                       "/Rot_{GT,DR}.txt: the headers declare different "
                       "init_heading_offset (3.141592653589793 and 3.1416)");
}

TEST(PlazaHeadingOffsetTest, RejectsDrColumnsInAnotherConvention) {
  const std::string dir = TempDir();
  const RotatedPlaza raw = WriteRotatedPlaza(dir, 0.0, "");
  auto dr_with = [&](auto column) {
    std::ostringstream dr;
    for (std::size_t k = 0; k < raw.distance.size(); ++k) {
      double d = raw.distance[k], dtheta = raw.turn[k];
      column(k, &d, &dtheta);
      dr << FormatNumber(raw.truth[k + 1].t) << " " << FormatNumber(d) << " "
         << FormatNumber(dtheta) << "\n";
    }
    return dr.str();
  };
  const std::string heading_problem =
      "/Rot_DR.txt: the DR heading column does not follow the ground-truth "
      "heading";
  // Clockwise heading changes.
  EXPECT_THAT(RotatedError(dir, 0.0, "", "Rot_DR.txt",
                           dr_with([](std::size_t, double*, double* dtheta) {
                             *dtheta = -*dtheta;
                           })),
              HasSubstr(heading_problem + " (correlation of the increments "
                                          "-1, expected about 1)"));
  // Absolute odometry headings instead of increments.
  EXPECT_THAT(RotatedError(dir, 0.0, "", "Rot_DR.txt",
                           dr_with([&](std::size_t k, double*, double* dtheta) {
                             *dtheta = raw.truth[k + 1].theta;
                           })),
              HasSubstr(heading_problem));
  // Distances in feet.
  EXPECT_THAT(RotatedError(dir, 0.0, "", "Rot_DR.txt",
                           dr_with([](std::size_t, double* d, double*) {
                             *d /= 0.3048;
                           })),
              HasSubstr("/Rot_DR.txt: the DR distances do not match the "
                        "ground truth (GT moves 0.3048 m per DR metre)"));
  // A distance whose square overflows: nothing could be compared.
  EXPECT_EQ(RotatedError(dir, 0.0, "", "Rot_DR.txt",
                         dr_with([](std::size_t k, double* d, double*) {
                           if (k == 3) *d = 1e308;
                         })),
            dir +
                "/Rot_{GT,DR}.txt: the DR distances and the ground-truth "
                "displacements overflow double precision when compared: "
                "distances or coordinates no recording has");
}

TEST(PlazaBundledTest, CountsFirstRecordsAndDeadReckoning) {
  const std::string path = std::string(RFF_SOURCE_DIR) + "/data/plaza1.rffd";
  Dataset d;
  std::string error;
  ASSERT_TRUE(ReadDataset(path, &d, &error)) << error;
  EXPECT_EQ(d.pose_priors.size(), 1u);
  EXPECT_EQ(d.landmark_priors.size(), 4u);
  EXPECT_EQ(d.odometry.size(), 9657u);
  EXPECT_EQ(d.observations.size(), 3529u);
  EXPECT_EQ(d.ground_truth.size(), 9658u);
  EXPECT_EQ(d.ground_truth_landmarks.size(), 4u);

  // First records, as in the raw files (GT row 0, DR row 0, beacon 0).
  EXPECT_EQ(d.pose_priors[0].pose.t, 3856.857346);
  EXPECT_EQ(d.pose_priors[0].pose.x, 0.0);
  EXPECT_NEAR(d.pose_priors[0].pose.theta, 4.222432 - 2.0 * M_PI, 1e-15);
  EXPECT_EQ(d.odometry[0].t0, 3856.857346);
  EXPECT_EQ(d.odometry[0].t1, 3857.053202);
  EXPECT_EQ(d.odometry[0].dx, 0.0002348385815);
  EXPECT_EQ(d.odometry[0].dy, 0.0);
  EXPECT_EQ(d.odometry[0].dtheta, -5.2e-05);
  EXPECT_EQ(d.landmark_priors[0].id, 0);
  EXPECT_EQ(d.landmark_priors[0].x, -46.623234);
  EXPECT_EQ(d.landmark_priors[0].sigma, 1.0);

  // Calibration: the published a ~ 0.934, b ~ 0.02 m, sigma ~ 0.5 m; the
  // first range (TD row 1: beacon 5, 65.46600784 m) corrected with it.
  double a = 0.0, b = 0.0;
  for (const auto& [key, value] : d.metadata) {
    if (key != "calibration") continue;
    EXPECT_THAT(value, HasSubstr("kept 3529 of 3529"));
    const std::size_t at_a = value.find("a=");
    const std::size_t at_b = value.find("b=");
    ASSERT_NE(at_a, std::string::npos);
    ASSERT_NE(at_b, std::string::npos);
    a = std::stod(value.substr(at_a + 2));
    b = std::stod(value.substr(at_b + 2));
  }
  EXPECT_NEAR(a, 0.934, 0.001);
  EXPECT_NEAR(b, 0.02, 0.005);
  EXPECT_EQ(d.observations[0].t, 3858.062);
  EXPECT_EQ(d.observations[0].id, 5);
  EXPECT_NEAR(d.observations[0].range, a * 65.46600784 + b, 1e-9);
  EXPECT_EQ(d.observations[0].sigma_range, 0.5);

  // Plaza 1 declares no heading offset, and its data agree.
  bool has_heading_offset = false;
  for (const auto& [key, value] : d.metadata) {
    if (key != "heading_offset") continue;
    has_heading_offset = true;
    EXPECT_THAT(value, HasSubstr("GT heading + 0 rad (declared in "
                                 "Plaza1_GT.txt and Plaza1_DR.txt; measured "
                                 "from the GT displacements: -0.018 rad)"));
  }
  EXPECT_TRUE(has_heading_offset);

  // Dead reckoning from the prior ends up ~2 m RMS from the truth.
  const double rms = DeadReckoningRms(d);
  EXPECT_NEAR(rms, 1.97, 0.01);
}

TEST(PlazaSharedTest, RawDataConvertsToTheBundledFile) {
  const std::string raw = std::string(RFF_SHARED_DIR) + "/data/plaza1";
  if (!std::filesystem::exists(raw + "/Plaza1_GT.txt")) {
    GTEST_SKIP() << "no raw Plaza1 data in " << raw;
  }
  Dataset d;
  PlazaSummary s;
  std::string error;
  ASSERT_TRUE(ConvertPlaza(raw, PlazaOptions(), &d, &s, &error)) << error;
  EXPECT_EQ(s.range_rows, 3529u);
  EXPECT_EQ(s.ranges_out_of_order, 217u);
  EXPECT_EQ(s.ranges_outside_span, 0u);
  EXPECT_NEAR(s.fit.a, 0.934, 0.001);
  EXPECT_NEAR(s.fit.b, 0.018, 0.001);
  EXPECT_NEAR(s.fit.inlier_sigma, 0.505, 0.001);
  EXPECT_EQ(s.range_sigma, 0.5);
  EXPECT_EQ(s.heading_offset, 0.0);
  EXPECT_NEAR(s.measured_heading_offset, -0.018, 0.001);
  std::ostringstream out;
  WriteDataset(d, &out);
  EXPECT_TRUE(out.str() ==
              ReadFile(std::string(RFF_SOURCE_DIR) + "/data/plaza1.rffd"))
      << "data/plaza1.rffd is stale: regenerate it (docs/converters.md)";

  // A tighter threshold does reject ranges (gpslam's 2 m keeps them all).
  PlazaOptions tight;
  tight.outlier_threshold = 1.0;
  ASSERT_TRUE(ConvertPlaza(raw, tight, &d, &s, &error)) << error;
  EXPECT_EQ(s.ranges_rejected, 184u);
  EXPECT_EQ(s.ranges_kept, 3345u);
  EXPECT_NEAR(s.fit.a, 0.934, 0.001);
  EXPECT_NEAR(s.fit.inlier_sigma, 0.437, 0.001);
}

}  // namespace
}  // namespace rff
