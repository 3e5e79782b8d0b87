// Hostile input at the reader and converter level: the cases that the
// per-reader tests (test/io/*_test.cc, test/convert/*_test.cc) do not cover.
// Each case either fails with "source:line: problem" or is accepted with a
// documented meaning (docs: /work/shared/FORMAT.md, the data contract).
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "rff_ceres/convert/mrclam.h"
#include "rff_ceres/convert/plaza.h"
#include "rff_ceres/io/dataset_io.h"
#include "rff_ceres/io/landmarks_io.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/io/tum_io.h"
#include "rff_ceres/slam_solver.h"
#include "test/test_files.h"

namespace rff {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

constexpr char kHead[] = "RFFD 1\nPRIOR_POSE 0 0 0 0 1 1\n";

bool ParseRffd(const std::string& text, Dataset* dataset, std::string* error) {
  std::istringstream input(text);
  return ParseDataset(&input, "h.rffd", dataset, error);
}

// A written dataset that reads back: what every converter output must be.
bool ReadsBack(const Dataset& dataset, std::string* error) {
  std::ostringstream out;
  WriteDataset(dataset, &out);
  Dataset back;
  return ParseRffd(out.str(), &back, error);
}

// ---------------------------------------------------------------------------
// .rffd: rejected inputs, one per case.
struct Rejected {
  const char* name;
  std::string text;
  const char* message;  // Expected part of the error, with the line number.
};
// Test names in ctest say the case, not the bytes of the struct.
void PrintTo(const Rejected& c, std::ostream* out) { *out << c.name; }

class HostileRffdTest : public ::testing::TestWithParam<Rejected> {};

TEST_P(HostileRffdTest, FailsNamingFileLineAndProblem) {
  Dataset d;
  std::string error;
  EXPECT_FALSE(ParseRffd(GetParam().text, &d, &error));
  EXPECT_THAT(error, StartsWith("h.rffd:"));
  EXPECT_THAT(error, HasSubstr(GetParam().message));
}

const Rejected kRejectedRffd[] = {
    // A file cut in the middle of a record (no final newline).
    {"TruncatedMidRecord", std::string(kHead) + "ODOM 0 1 1 0 0 0.1",
     "h.rffd:3: ODOM needs 8 fields, got 6"},
    // Cut inside the last number: "0.5" became "0." = 0, not a sigma.
    {"TruncatedInsideNumber", std::string(kHead) + "RANGE 1 2 3 0.",
     "h.rffd:3: sigma_range must be > 0, got 0"},
    // A PNG signature: binary junk on line 1.
    {"BinaryJunk", std::string("\x89PNG\r\n\x1a\n", 8),
     "h.rffd:1: unknown record '\x89PNG'"},
    {"BinaryJunkAfterHeader", std::string(kHead) + "\xff\xfe\xfd\x01\x02\n",
     "h.rffd:3: unknown record '\xff\xfe\xfd\x01\x02'"},
    // Lone CR (classic Mac) line ends: the whole file is one line.
    {"LoneCarriageReturns", "RFFD 1\rPRIOR_POSE 0 0 0 0 1 1\r",
     "h.rffd:1: RFFD needs 1 fields, got 7"},
    // A CR inside a line is not a blank: it sticks to the number.
    {"CarriageReturnInsideLine", std::string(kHead) + "RANGE 1 2 3\r 1\n",
     "h.rffd:3: field 4 '3\r' is not a finite number"},
    // A no-break space (U+00A0) is not a field separator.
    {"NoBreakSpace",
     std::string(kHead) + "RANGE\xc2\xa0"
                          "1 2 3 1\n",
     "h.rffd:3: unknown record 'RANGE\xc2\xa0"
     "1'"},
    {"LowerCaseRecord", std::string(kHead) + "range 1 2 3 1\n",
     "h.rffd:3: unknown record 'range'"},
    {"NegativeOverflow", std::string(kHead) + "GT_POSE 0 -1e999 0 0\n",
     "h.rffd:3: field 3 '-1e999' is not a finite number"},
    {"CapitalNaN", std::string(kHead) + "GT_POSE 0 0 NaN 0\n",
     "h.rffd:3: field 4 'NaN' is not a finite number"},
    {"NegativeNaN", std::string(kHead) + "RANGE 1 2 -nan 1\n",
     "h.rffd:3: field 4 '-nan' is not a finite number"},
    {"NaNWithPayload", std::string(kHead) + "RANGE nan(0x1) 2 3 1\n",
     "h.rffd:3: field 2 'nan(0x1)' is not a finite number"},
    {"Infinity", std::string(kHead) + "RANGE 1 2 3 Infinity\n",
     "h.rffd:3: field 5 'Infinity' is not a finite number"},
    // Underflow reads as 0, which is not a standard deviation.
    {"SigmaUnderflowsToZero", std::string(kHead) + "RANGE 1 2 3 1e-400\n",
     "h.rffd:3: sigma_range must be > 0, got 0"},
    {"NegativeZeroOdometrySigma",
     std::string(kHead) + "ODOM 0 1 0 0 0 1 -0 1\n",
     "h.rffd:3: sigma_y must be > 0, got -0"},
    // Numbers longer than 64 characters are refused, not truncated.
    {"NumberLongerThan64Chars",
     std::string(kHead) + "RANGE 1 2 3." + std::string(70, '1') + " 1\n",
     "h.rffd:3: field 4 '3.111111111"},
    // INT64_MAX + 1.
    {"IdOneAboveInt64Max",
     std::string(kHead) + "RANGE 1 9223372036854775808 3 1\n",
     "h.rffd:3: landmark id '9223372036854775808' is not a non-negative"},
    {"IdWithPlusSign", std::string(kHead) + "RANGE 1 +5 3 1\n",
     "h.rffd:3: landmark id '+5'"},
    {"HexId", std::string(kHead) + "PRIOR_LANDMARK 0x10 0 0 1\n",
     "h.rffd:3: landmark id '0x10'"},
    {"ExponentId", std::string(kHead) + "GT_LANDMARK 1e3 0 0\n",
     "h.rffd:3: landmark id '1e3'"},
    {"OdometryBackwardsByOneUlpAtEpoch",
     std::string(kHead) +
         "ODOM 1248444175.103 1248444175.1029999 0 0 0 1 1 1\n",
     "h.rffd:3: ODOM needs t1 > t0"},
    {"VersionWithLeadingZero", "RFFD 01\n",
     "h.rffd:1: unsupported RFFD version '01'"},
    {"VersionAsDecimal", "RFFD 1.0\n",
     "h.rffd:1: unsupported RFFD version '1.0'"},
    // One past the longest accepted line (kMaxLineLength bytes).
    {"LineOneByteTooLong",
     std::string(kHead) + "#" + std::string(kMaxLineLength, 'x') + "\n",
     "h.rffd:3: line longer than 65536 bytes"},
    // Angles are judged as written: wrapped, 1e300 rad would pass as some
    // angle in (-pi, pi] that the file never said.
    {"BearingBeyondDoublePrecision",
     std::string(kHead) + "RANGE_BEARING 5 1 10 1e300 1 0.03\n",
     "h.rffd:3: sigma_bearing 0.03 is finer than double precision resolves "
     "its bearing; allowed at least 2.2204460492503132e+284"},
    {"HeadingBeyondDoublePrecision",
     std::string(kHead) + "PRIOR_POSE 1 0 0 1e300 1 0.1\n",
     "h.rffd:3: sigma_theta 0.1 is finer than double precision resolves its "
     "heading"},
    {"OdometryTurnBeyondDoublePrecision",
     std::string(kHead) + "ODOM 0 1 0 0 -1e300 1 1 0.1\n",
     "h.rffd:3: sigma_theta 0.1 is finer than double precision resolves its "
     "dtheta"},
    {"HeaderOnly", "RFFD 1\n", "h.rffd: no PRIOR_POSE record"},
    {"DuplicateGroundTruthTimeOutOfOrder",
     std::string(kHead) + "GT_POSE 2 0 0 0\nGT_POSE 1 0 0 0\nGT_POSE 2 1 0 0\n",
     "h.rffd: two GT_POSE records at time 2"},
};

INSTANTIATE_TEST_SUITE_P(Cases, HostileRffdTest,
                         ::testing::ValuesIn(kRejectedRffd),
                         [](const ::testing::TestParamInfo<Rejected>& info) {
                           return std::string(info.param.name);
                         });

// ---------------------------------------------------------------------------
// .rffd: accepted inputs, each with its documented meaning.

// FORMAT.md: "LF or CRLF line ends". A CRLF file reads exactly as LF.
TEST(HostileRffdAcceptedTest, CrlfFileReadsLikeLf) {
  const std::string lf =
      "# source: crlf\nRFFD 1\nPRIOR_POSE 0 1 2 0.5 0.1 0.01\n"
      "ODOM 0 1 1 0 0.1 0.05 0.05 0.01\nRANGE_BEARING 1 7 3 -0.2 1 0.03\n"
      "GT_POSE 1 2 2 0.5\n";
  std::string crlf;
  for (const char c : lf)
    crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
  Dataset a, b;
  std::string error;
  ASSERT_TRUE(ParseRffd(lf, &a, &error)) << error;
  ASSERT_TRUE(ParseRffd(crlf, &b, &error)) << error;
  EXPECT_EQ(b.metadata, a.metadata);
  ASSERT_EQ(b.observations.size(), 1u);
  EXPECT_EQ(b.observations[0].sigma_bearing, 0.03);
  EXPECT_EQ(b.odometry[0].sigma_theta, 0.01);
  EXPECT_EQ(b.ground_truth[0].theta, 0.5);
}

// A UTF-8 byte order mark before the header is skipped (Windows editors
// write one); anywhere else it is an unknown record.
TEST(HostileRffdAcceptedTest, ByteOrderMarkBeforeHeaderIsSkipped) {
  Dataset d;
  std::string error;
  EXPECT_TRUE(ParseRffd("\xEF\xBB\xBF" + std::string(kHead), &d, &error))
      << error;
  EXPECT_FALSE(ParseRffd(std::string(kHead) + "\xEF\xBB\xBFRANGE 1 2 3 1\n", &d,
                         &error));
  EXPECT_EQ(error, "h.rffd:3: unknown record '\xEF\xBB\xBFRANGE'");
}

TEST(HostileRffdAcceptedTest, FinalLineWithoutNewlineIsRead) {
  Dataset d;
  std::string error;
  ASSERT_TRUE(ParseRffd(std::string(kHead) + "RANGE 1 2 3 0.5", &d, &error))
      << error;
  ASSERT_EQ(d.observations.size(), 1u);
  EXPECT_EQ(d.observations[0].sigma_range, 0.5);
}

// Exactly kMaxLineLength bytes is still a line.
TEST(HostileRffdAcceptedTest, LineOfExactlyMaxLengthIsRead) {
  Dataset d;
  std::string error;
  EXPECT_TRUE(ParseRffd(
      std::string(kHead) + "#" + std::string(kMaxLineLength - 1, 'x') + "\n",
      &d, &error))
      << error;
}

// -0 is a number like any other (equal to 0): a coordinate, a time or an
// angle of -0 is data; only as a sigma is it refused (see the rejected list).
TEST(HostileRffdAcceptedTest, NegativeZeroIsData) {
  Dataset d;
  std::string error;
  ASSERT_TRUE(ParseRffd("RFFD 1\nPRIOR_POSE -0 -0 -0 -0 1 1\n", &d, &error))
      << error;
  EXPECT_EQ(d.pose_priors[0].pose.t, 0.0);
  EXPECT_EQ(d.pose_priors[0].pose.theta, 0.0);
}

// Numbers are read with strtod: a leading '+', hexadecimal floats and
// denormals are valid numbers (the writer never produces them); a sigma
// must still be one double precision resolves (dataset_io_test).
TEST(HostileRffdAcceptedTest, StrtodSyntaxIsAccepted) {
  Dataset d;
  std::string error;
  ASSERT_TRUE(ParseRffd(std::string(kHead) + "RANGE +1 2 4.9e-324 0x1.8p3\n",
                        &d, &error))
      << error;
  EXPECT_EQ(d.observations[0].t, 1.0);
  EXPECT_GT(d.observations[0].range, 0.0);
  EXPECT_LT(d.observations[0].range, 1e-323);
  EXPECT_EQ(d.observations[0].sigma_range, 12.0);
}

// Ids: INT64_MAX is the largest; leading zeros are decimal, not octal.
TEST(HostileRffdAcceptedTest, LargestIdAndLeadingZeros) {
  Dataset d;
  std::string error;
  ASSERT_TRUE(ParseRffd(std::string(kHead) + "RANGE 1 9223372036854775807 3 1\n"
                                             "RANGE 2 007 3 1\n",
                        &d, &error))
      << error;
  EXPECT_EQ(d.observations[0].id, std::numeric_limits<std::int64_t>::max());
  EXPECT_EQ(d.observations[1].id, 7);
}

// Repeated measurements are data: the format forbids duplicates only of
// GT_POSE times, GT_LANDMARK ids and PRIOR_LANDMARK ids. Two equal lines are
// two measurements (the solver weights them twice), kept in file order.
TEST(HostileRffdAcceptedTest, DuplicatedMeasurementsAreKept) {
  Dataset d;
  std::string error;
  ASSERT_TRUE(ParseRffd(std::string(kHead) +
                            "PRIOR_POSE 0 0 0 0 1 1\n"
                            "ODOM 0 1 1 0 0 1 1 1\nODOM 0 1 1 0 0 1 1 1\n"
                            "RANGE 1 2 3 1\nRANGE 1 2 3 1\nRANGE 1 2 4 1\n",
                        &d, &error))
      << error;
  EXPECT_EQ(d.pose_priors.size(), 2u);
  EXPECT_EQ(d.odometry.size(), 2u);
  ASSERT_EQ(d.observations.size(), 3u);
  EXPECT_EQ(d.observations[2].range, 4.0);  // Stable: file order kept.
}

// An odometry sigma whose square overflows is named as too large, not too
// small, before any solve; a valid file (sigmas are only "> 0" there).
TEST(HostileRffdAcceptedTest, OdometrySigmaTooLargeIsNamedSo) {
  Dataset d;
  std::string error;
  ASSERT_TRUE(ParseRffd(std::string(kHead) + "PRIOR_LANDMARK 1 3 0 1\n"
                                             "ODOM 0 1 1 0 0 1e200 0.1 0.01\n"
                                             "RANGE 1 1 2 0.1\n",
                        &d, &error))
      << error;
  SlamResult result;
  for (const char* prior : {"rff", "wnoa"}) {
    SlamOptions options;
    options.prior = prior;
    EXPECT_FALSE(RunSlam(d, options, &result, &error)) << prior;
    EXPECT_EQ(error,
              "odometry from t = 0 to 1: its covariance cannot be inverted "
              "in double precision (sigmas too large)")
        << prior;
  }
}

// A landmark prior exactly where the robot starts, seen from there by a
// bearing: valid data, solved (the start moves off the undefined bearing).
TEST(HostileRffdAcceptedTest, ALandmarkPriorOnTheStartingPoseIsSolved) {
  Dataset d;
  std::string error;
  ASSERT_TRUE(
      ParseRffd("RFFD 1\nPRIOR_POSE 0 0 0 0 0.1 0.1\nPRIOR_LANDMARK 1 0 0 1\n"
                "BEARING 0 1 0 0.01\nBEARING 1 1 1 0.01\n",
                &d, &error))
      << error;
  for (const char* prior : {"rff", "wnoa"}) {
    SlamOptions options;
    options.prior = prior;
    SlamResult result;
    ASSERT_TRUE(RunSlam(d, options, &result, &error)) << prior << ": " << error;
    ASSERT_EQ(result.landmarks.size(), 1u);
    // Ahead of the first pose, along its bearing of 0 (within the heading
    // prior's 0.1 rad), drawn towards the prior's mean.
    const Landmark& l = result.landmarks[0];
    EXPECT_GT(l.x, 0.0) << prior;
    EXPECT_LT(std::abs(std::atan2(l.y, l.x)), 0.1) << prior;
    EXPECT_LT(std::hypot(l.x, l.y), 0.5) << prior;
    EXPECT_EQ(result.quality.verdict, "ok") << prior;
  }
}

// FORMAT.md: "Records may come in any order; readers sort observations by
// time themselves."
TEST(HostileRffdAcceptedTest, TimesOutOfOrderAreSorted) {
  Dataset d;
  std::string error;
  EXPECT_FALSE(
      ParseRffd("RANGE 5 1 1 1\n"
                "# comment lines do not count as records\n"
                "RFFD 1\n",
                &d, &error));
  EXPECT_EQ(error,
            "h.rffd:1: missing header: the first record must be "
            "'RFFD 1', got 'RANGE'");
  ASSERT_TRUE(ParseRffd(std::string(kHead) +
                            "RANGE 5 1 1 1\nODOM 3 4 0 0 0 1 1 1\n"
                            "RANGE -2 1 2 1\nODOM -1 0 0 0 0 1 1 1\n"
                            "GT_POSE 9 0 0 0\nGT_POSE -9 0 0 0\n"
                            "RANGE 0 1 3 1\n",
                        &d, &error))
      << error;
  ASSERT_EQ(d.observations.size(), 3u);
  EXPECT_EQ(d.observations[0].t, -2.0);
  EXPECT_EQ(d.observations[1].t, 0.0);
  EXPECT_EQ(d.observations[2].t, 5.0);
  EXPECT_EQ(d.odometry[0].t0, -1.0);
  EXPECT_EQ(d.ground_truth[0].t, -9.0);
}

// Unix-epoch times keep every bit (millisecond steps stay distinct).
TEST(HostileRffdAcceptedTest, UnixEpochTimesAreExact) {
  Dataset d;
  std::string error;
  ASSERT_TRUE(
      ParseRffd("RFFD 1\nPRIOR_POSE 1248444175.103 0 0 0 1 1\n"
                "ODOM 1248444175.103 1248444175.104 0 0 0 1 1 1\n",
                &d, &error))
      << error;
  EXPECT_EQ(d.odometry[0].t0, 1248444175.103);
  EXPECT_EQ(d.odometry[0].t1, 1248444175.104);
  EXPECT_GT(d.odometry[0].t1, d.odometry[0].t0);
}

// Degenerate but well-formed datasets are the solver's business, not the
// reader's: a single pose, no observations, all observations at one time, a
// landmark seen once without a prior. The reader accepts them as they are.
TEST(HostileRffdAcceptedTest, DegenerateDatasetsAreWellFormed) {
  Dataset d;
  std::string error;
  ASSERT_TRUE(ParseRffd(kHead, &d, &error)) << error;  // A single pose.
  EXPECT_TRUE(d.observations.empty());
  EXPECT_TRUE(d.odometry.empty());
  ASSERT_TRUE(ParseRffd(std::string(kHead) +
                            "RANGE 1 2 3 1\nBEARING 1 3 0.5 0.1\n"
                            "RANGE_BEARING 1 4 2 0.1 1 0.1\n",
                        &d, &error))
      << error;
  EXPECT_EQ(d.observations.size(), 3u);
  for (const Observation& o : d.observations) EXPECT_EQ(o.t, 1.0);
}

// Metadata: only "# key: value" comments before the first record, with a
// key without blanks.
TEST(HostileRffdAcceptedTest, MetadataOnlyBeforeFirstRecord) {
  Dataset d;
  std::string error;
  ASSERT_TRUE(
      ParseRffd("#: no key\n# two words: no\n#k:v # with hash\n"
                "RFFD 1\n# late: ignored\nPRIOR_POSE 0 0 0 0 1 1\n",
                &d, &error))
      << error;
  ASSERT_EQ(d.metadata.size(), 1u);
  EXPECT_EQ(d.metadata[0].first, "k");
  EXPECT_EQ(d.metadata[0].second, "v # with hash");
}

// Found by the fuzzer (corpus/crash-metadata-trailing-cr-*.rffd): a line
// ending in "\r\r\n" left a CR at the end of the metadata value, which a
// write and re-read lost. Metadata values are trimmed of CR as of blanks.
TEST(HostileRffdAcceptedTest, MetadataValueLosesTrailingCarriageReturns) {
  Dataset d;
  std::string error;
  ASSERT_TRUE(ParseRffd(
      "# source: a\rb\r\r\n# \rkey\r: v\r\n" + std::string(kHead), &d, &error))
      << error;
  ASSERT_EQ(d.metadata.size(), 2u);
  EXPECT_EQ(d.metadata[0].second, "a\rb");
  EXPECT_EQ(d.metadata[1].first, "key");
  EXPECT_EQ(d.metadata[1].second, "v");
  std::ostringstream out;
  WriteDataset(d, &out);
  Dataset back;
  ASSERT_TRUE(ParseRffd(out.str(), &back, &error)) << error;
  EXPECT_EQ(back.metadata, d.metadata);
}

// ---------------------------------------------------------------------------
// TUM trajectories.
bool ParseTumText(const std::string& text, std::vector<TimedPose>* poses,
                  std::string* error) {
  std::istringstream input(text);
  return ParseTum(&input, "h.tum", poses, error);
}

class HostileTumTest : public ::testing::TestWithParam<Rejected> {};

TEST_P(HostileTumTest, FailsNamingFileLineAndProblem) {
  std::vector<TimedPose> poses;
  std::string error;
  EXPECT_FALSE(ParseTumText(GetParam().text, &poses, &error));
  EXPECT_THAT(error, StartsWith("h.tum"));
  EXPECT_THAT(error, HasSubstr(GetParam().message));
}

const Rejected kRejectedTum[] = {
    {"Truncated", "0 0 0 0 0 0 0 1\n1 0 0 0 0 0",
     "h.tum:2: a TUM pose needs 8 "
     "fields (t x y z qx qy qz "
     "qw), got 6"},
    {"BinaryJunk",
     std::string("\x7f"
                 "ELF\x02\x01\x01\n",
                 8),
     "h.tum:1: a TUM pose needs 8 fields"},
    {"TimeOverflow", "1e999 0 0 0 0 0 0 1\n",
     "h.tum:1: field 1 '1e999' is not a finite number"},
    {"TimesOutOfOrder", "1 0 0 0 0 0 0 1\n0.5 0 0 0 0 0 0 1\n",
     "h.tum:2: time 0.5 does not increase (previous 1)"},
    // 0 == -0: not an increase.
    {"ZeroAfterNegativeZero", "-0 0 0 0 0 0 0 1\n0 0 0 0 0 0 0 1\n",
     "h.tum:2: time 0 does not increase (previous -0)"},
    {"TinyQuaternion", "0 0 0 0 1e-7 0 0 1e-7\n",
     "h.tum:1: quaternion has zero norm"},
    {"HugeLine", std::string(kMaxLineLength + 10, '1'),
     "h.tum:1: line longer than 65536 bytes"},
    {"OnlyComments", "# t x y z qx qy qz qw\n\n", "h.tum: no poses"},
};

INSTANTIATE_TEST_SUITE_P(Cases, HostileTumTest,
                         ::testing::ValuesIn(kRejectedTum),
                         [](const ::testing::TestParamInfo<Rejected>& info) {
                           return std::string(info.param.name);
                         });

TEST(HostileTumAcceptedTest, CrlfAndEpochTimes) {
  std::vector<TimedPose> poses;
  std::string error;
  ASSERT_TRUE(
      ParseTumText("1248444175.103 1 2 0 0 0 0 1\r\n"
                   "1248444175.104 1 2 0 0 0 1 0\r\n",
                   &poses, &error))
      << error;
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_EQ(poses[1].t, 1248444175.104);
  EXPECT_NEAR(poses[1].theta, M_PI, 1e-15);
}

// Components above 1e154 overflow when squared; the heading must still be
// the yaw of the direction (here 90 degrees), never NaN.
TEST(HostileTumAcceptedTest, HugeQuaternionGivesFiniteYaw) {
  std::vector<TimedPose> poses;
  std::string error;
  ASSERT_TRUE(ParseTumText(
      "0 0 0 0 0 0 1e200 1e200\n1 0 0 0 0 0 -1e300 1e300\n", &poses, &error))
      << error;
  EXPECT_NEAR(poses[0].theta, M_PI / 2, 1e-15);
  EXPECT_NEAR(poses[1].theta, -M_PI / 2, 1e-15);
}

// ---------------------------------------------------------------------------
// Landmark files.
bool ParseLandmarkText(const std::string& text, std::vector<Landmark>* out,
                       std::string* error) {
  std::istringstream input(text);
  return ParseLandmarks(&input, "h.landmarks", out, error);
}

class HostileLandmarksTest : public ::testing::TestWithParam<Rejected> {};

TEST_P(HostileLandmarksTest, FailsNamingFileLineAndProblem) {
  std::vector<Landmark> landmarks;
  std::string error;
  EXPECT_FALSE(ParseLandmarkText(GetParam().text, &landmarks, &error));
  EXPECT_THAT(error, StartsWith("h.landmarks"));
  EXPECT_THAT(error, HasSubstr(GetParam().message));
}

const Rejected kRejectedLandmarks[] = {
    {"Truncated", "1 0 0\n2 0", "h.landmarks:2: a landmark needs 3 fields"},
    {"IdOverflow", "9223372036854775808 0 0\n",
     "h.landmarks:1: landmark id '9223372036854775808'"},
    {"NaNCovariance", "1 0 0 1 nan 1\n", "h.landmarks:1: field 5 'nan'"},
    // sxy^2 = 2.25e400 > sxx syy = 1e400: both products overflow to inf,
    // and inf > inf is false; the check must not pass it.
    {"HugeNonPsdCovariance", "1 0 0 1e200 1.5e200 1e200\n",
     "h.landmarks:1: covariance is not positive semi-definite"},
    {"NegativeVariance", "1 0 0 -1e-300 0 1\n",
     "h.landmarks:1: covariance is not positive semi-definite"},
    {"BinaryJunk", std::string("1 0 0\n\x01\x02\x03\x04\n"),
     "h.landmarks:2: a landmark needs 3 fields"},
};

INSTANTIATE_TEST_SUITE_P(Cases, HostileLandmarksTest,
                         ::testing::ValuesIn(kRejectedLandmarks),
                         [](const ::testing::TestParamInfo<Rejected>& info) {
                           return std::string(info.param.name);
                         });

// An empty landmark file is a map without landmarks (a localisation run);
// rows may mix the 3- and 6-column forms; a singular PSD covariance at the
// overflow edge (sxy^2 == sxx syy) is accepted.
TEST(HostileLandmarksAcceptedTest, EmptyMixedAndSingular) {
  std::vector<Landmark> landmarks;
  std::string error;
  ASSERT_TRUE(ParseLandmarkText("", &landmarks, &error)) << error;
  EXPECT_TRUE(landmarks.empty());
  ASSERT_TRUE(ParseLandmarkText("2 0 0\r\n1 5 6 1e200 1e200 1e200\r\n",
                                &landmarks, &error))
      << error;
  ASSERT_EQ(landmarks.size(), 2u);
  EXPECT_TRUE(landmarks[0].has_covariance);
  EXPECT_FALSE(landmarks[1].has_covariance);
}

// ---------------------------------------------------------------------------
// Converters. The raw layouts of test/convert/*_test.cc, made hostile one
// file at a time. A converter either fails naming the file (and the line
// where there is one) or writes a dataset that reads back.
using testing::WriteFile;

void WriteTinyPlaza(const std::string& dir) {
  WriteFile(dir + "/Tiny_GT.txt", "0 0 0 0\n1 1 0 0\n2 2 0 0\n3 3 0 0\n");
  WriteFile(dir + "/Tiny_DR.txt", "1 1 0\n2 1 0\n3 1 0\n");
  WriteFile(dir + "/Tiny_TL.txt", "3 0 10\n8 20 0\n");
  WriteFile(dir + "/Tiny_TD.txt",
            "0.5 2 3 10.1\n1.0 2 8 19.0\n1.5 2 3 10.2\n2.0 2 8 18.1\n"
            "2.5 2 3 10.3\n");
}

PlazaOptions TinyPlaza() {
  PlazaOptions options;
  options.name = "Tiny";
  return options;
}

std::string PlazaError(const std::string& dir, const PlazaOptions& options) {
  Dataset d;
  PlazaSummary s;
  std::string error;
  if (ConvertPlaza(dir, options, &d, &s, &error)) {
    std::string reread;
    EXPECT_TRUE(ReadsBack(d, &reread)) << reread;
    return "converted";
  }
  return error;
}

TEST(HostilePlazaTest, TinyInputConverts) {
  const std::string dir = testing::TempDir("hostile_input_test");
  WriteTinyPlaza(dir);
  EXPECT_EQ(PlazaError(dir, TinyPlaza()), "converted");
}

struct RawCase {
  const char* name;
  const char* file;
  std::string text;
  const char* message;  // After "DIR/".
};
// Test names in ctest say the case, not the bytes of the struct.
void PrintTo(const RawCase& c, std::ostream* out) { *out << c.name; }

class HostilePlazaFileTest : public ::testing::TestWithParam<RawCase> {};

TEST_P(HostilePlazaFileTest, FailsNamingFileAndLine) {
  const std::string dir = testing::TempDir("hostile_input_test");
  WriteTinyPlaza(dir);
  WriteFile(dir + "/" + GetParam().file, GetParam().text);
  EXPECT_EQ(PlazaError(dir, TinyPlaza()), dir + "/" + GetParam().message);
}

const RawCase kPlazaCases[] = {
    {"EmptyGroundTruth", "Tiny_GT.txt", "", "Tiny_GT.txt: no data rows"},
    {"SingleGroundTruthRow", "Tiny_GT.txt", "0 0 0 0\n",
     "Tiny_GT.txt: needs at least 2 rows"},
    {"TruncatedGroundTruth", "Tiny_GT.txt", "0 0 0 0\n1 1 0",
     "Tiny_GT.txt:2: expected 4 fields, got 3"},
    {"BinaryRanges", "Tiny_TD.txt", "\x89PNG\r\n",
     "Tiny_TD.txt:1: expected 4 fields, got 1"},
    {"NaNRange", "Tiny_TD.txt", "0.5 2 3 nan\n",
     "Tiny_TD.txt:1: field 4 'nan' is not a finite number"},
    {"OverflowingTime", "Tiny_DR.txt", "1e999 1 0\n",
     "Tiny_DR.txt:1: field 1 '1e999' is not a finite number"},
    {"OverflowingBeaconId", "Tiny_TD.txt", "0.5 2 99999999999999999999 1\n",
     "Tiny_TD.txt:1: field 3 '99999999999999999999' is not a non-negative "
     "integer"},
    {"TooFewRangesToCalibrate", "Tiny_TD.txt", "0.5 2 3 10\n1.5 2 3 10\n",
     "Tiny_TD.txt: range calibration needs at least 3 ranges, got 2"},
    // Every range at one time and one beacon: the fit is undetermined.
    {"AllRangesAtOneTime", "Tiny_TD.txt", "1 2 3 10\n1 2 3 10\n1 2 3 10\n",
     "Tiny_TD.txt: range calibration: all measured ranges are equal"},
    {"HugeLine", "Tiny_TL.txt", std::string(kMaxLineLength + 1, '7'),
     "Tiny_TL.txt:1: line longer than 65536 bytes (binary or broken "
     "file?)"},
};

INSTANTIATE_TEST_SUITE_P(Cases, HostilePlazaFileTest,
                         ::testing::ValuesIn(kPlazaCases),
                         [](const ::testing::TestParamInfo<RawCase>& info) {
                           return std::string(info.param.name);
                         });

// Raw files with CRLF line ends convert exactly as with LF.
TEST(HostilePlazaTest, CrlfRawFilesConvertLikeLf) {
  const std::string dir = testing::TempDir("hostile_input_test");
  WriteTinyPlaza(dir);
  Dataset lf, crlf;
  PlazaSummary s;
  std::string error;
  ASSERT_TRUE(ConvertPlaza(dir, TinyPlaza(), &lf, &s, &error)) << error;
  for (const char* name : {"GT", "DR", "TL", "TD"}) {
    const std::string path = dir + "/Tiny_" + name + ".txt";
    std::string text;
    for (const char c : testing::ReadFile(path)) {
      text += c == '\n' ? std::string("\r\n") : std::string(1, c);
    }
    WriteFile(path, text);
  }
  ASSERT_TRUE(ConvertPlaza(dir, TinyPlaza(), &crlf, &s, &error)) << error;
  std::ostringstream a, b;
  WriteDataset(lf, &a);
  WriteDataset(crlf, &b);
  EXPECT_EQ(a.str(), b.str());
}

// Coordinates near the largest double: the interpolated truth and the fit
// overflow, so no range is an inlier of the calibration fit. The converter
// fails naming the range file instead of writing inf or NaN.
TEST(HostilePlazaTest, HugeCoordinatesDoNotGiveNonFiniteOutput) {
  const std::string dir = testing::TempDir("hostile_input_test");
  WriteTinyPlaza(dir);
  WriteFile(dir + "/Tiny_TL.txt", "3 1e308 -1e308\n8 -1e308 1e308\n");
  WriteFile(dir + "/Tiny_TD.txt",
            "0.5 2 3 1e308\n1.0 2 8 1.7e308\n1.5 2 3 1e300\n2.0 2 8 5\n");
  PlazaOptions options = TinyPlaza();
  for (const PlazaCalibration c :
       {PlazaCalibration::kLinear, PlazaCalibration::kNone}) {
    options.calibration = c;
    EXPECT_EQ(PlazaError(dir, options),
              dir +
                  "/Tiny_TD.txt: range calibration needs at least 3 ranges, "
                  "got 0 (inliers: |residual| <= 2 m)");
  }
}

void WriteTinyMrclam(const std::string& dir) {
  WriteFile(dir + "/Barcodes.dat", "1 5\n6 63\n7 81\n");
  WriteFile(dir + "/Landmark_Groundtruth.dat", "6 3 4 0 0\n7 -2 1 0 0\n");
  WriteFile(dir + "/Robot1_Odometry.dat", "0 1 0\n1 1 0.5\n2 0 0\n10 0 0\n");
  WriteFile(dir + "/Robot1_Groundtruth.dat",
            "0 0 0 0\n1 1 0 0\n2 1.9 0.4 0.5\n10 1.9 0.4 0.5\n");
  WriteFile(dir + "/Robot1_Measurement.dat",
            "0.5 63 5 0.9\n1.5 81 3 2.5\n2.5 63 3.6 0.8\n");
}

std::string MrclamError(const std::string& dir, const MrclamOptions& options) {
  Dataset d;
  MrclamSummary s;
  std::string error;
  if (ConvertMrclam(dir, options, &d, &s, &error)) {
    std::string reread;
    EXPECT_TRUE(ReadsBack(d, &reread)) << reread;
    return "converted";
  }
  return error;
}

TEST(HostileMrclamTest, TinyInputConverts) {
  const std::string dir = testing::TempDir("hostile_input_test");
  WriteTinyMrclam(dir);
  EXPECT_EQ(MrclamError(dir, MrclamOptions()), "converted");
}

class HostileMrclamFileTest : public ::testing::TestWithParam<RawCase> {};

TEST_P(HostileMrclamFileTest, FailsNamingFileAndLine) {
  const std::string dir = testing::TempDir("hostile_input_test");
  WriteTinyMrclam(dir);
  WriteFile(dir + "/" + GetParam().file, GetParam().text);
  EXPECT_EQ(MrclamError(dir, MrclamOptions()), dir + "/" + GetParam().message);
}

const RawCase kMrclamCases[] = {
    {"EmptyMeasurements", "Robot1_Measurement.dat", "",
     "Robot1_Measurement.dat: no data rows"},
    {"TruncatedOdometry", "Robot1_Odometry.dat", "0 1 0\n1 1",
     "Robot1_Odometry.dat:2: expected 3 fields, got 2"},
    {"BinaryBarcodes", "Barcodes.dat", std::string("\x01\x02 \x03\n"),
     "Barcodes.dat:1: field 1 '\x01\x02' is not a non-negative integer"},
    {"InfiniteVelocity", "Robot1_Odometry.dat", "0 inf 0\n",
     "Robot1_Odometry.dat:1: field 2 'inf' is not a finite number"},
    {"OverflowingBarcode", "Robot1_Measurement.dat",
     "0.5 99999999999999999999 5 0\n",
     "Robot1_Measurement.dat:1: field 2 '99999999999999999999' is not a "
     "non-negative integer"},
    {"SingleGroundTruthRow", "Robot1_Groundtruth.dat", "0 0 0 0\n",
     "Robot1_Groundtruth.dat: needs at least 2 rows"},
    {"GroundTruthTimesOutOfOrder", "Robot1_Groundtruth.dat",
     "0 0 0 0\n2 0 0 0\n1 0 0 0\n",
     "Robot1_Groundtruth.dat:3: time 1 does not increase (previous row 2)"},
};

INSTANTIATE_TEST_SUITE_P(Cases, HostileMrclamFileTest,
                         ::testing::ValuesIn(kMrclamCases),
                         [](const ::testing::TestParamInfo<RawCase>& info) {
                           return std::string(info.param.name);
                         });

// Unix-epoch times (as in the real data) convert with exact times.
TEST(HostileMrclamTest, UnixEpochTimes) {
  const std::string dir = testing::TempDir("hostile_input_test");
  WriteTinyMrclam(dir);
  WriteFile(dir + "/Robot1_Odometry.dat",
            "1248444189 1 0\n1248444191 0 0\n1248444199 0 0\n");
  WriteFile(dir + "/Robot1_Groundtruth.dat",
            "1248444189 0 0 0\n1248444199 2 0 0\n");
  WriteFile(dir + "/Robot1_Measurement.dat",
            "1248444189.599 63 5 0.9\n1248444189.828 81 3 2.5\n");
  Dataset d;
  MrclamSummary s;
  std::string error;
  ASSERT_TRUE(ConvertMrclam(dir, MrclamOptions(), &d, &s, &error)) << error;
  ASSERT_EQ(d.odometry.size(), 1u);
  EXPECT_EQ(d.odometry[0].t0, 1248444189.599);
  EXPECT_EQ(d.odometry[0].t1, 1248444189.828);
  EXPECT_NEAR(d.odometry[0].dx, 0.229, 1e-6);
}

// A velocity near the largest double over 3 s integrates to inf: an error
// naming the odometry file, not an ODOM record with inf.
TEST(HostileMrclamTest, HugeVelocityDoesNotGiveNonFiniteOdometry) {
  const std::string dir = testing::TempDir("hostile_input_test");
  WriteTinyMrclam(dir);
  WriteFile(dir + "/Robot1_Odometry.dat", "0 1e308 0\n10 0 0\n");
  WriteFile(dir + "/Robot1_Measurement.dat", "0.5 63 5 0.9\n3.5 81 3 2.5\n");
  const std::string result = MrclamError(dir, MrclamOptions());
  EXPECT_THAT(result, StartsWith(dir + "/Robot1_Odometry.dat"));
}

// A time span of 1e9 s split into 0.01 s steps would be 1e11 poses (and an
// int overflow in the step count): refused with a clear error.
TEST(HostileMrclamTest, OdometryIntervalOverHugeGapIsRefused) {
  const std::string dir = testing::TempDir("hostile_input_test");
  WriteTinyMrclam(dir);
  WriteFile(dir + "/Robot1_Odometry.dat", "0 0 0\n1e9 0 0\n");
  WriteFile(dir + "/Robot1_Groundtruth.dat", "0 0 0 0\n1e9 0 0 0\n");
  WriteFile(dir + "/Robot1_Measurement.dat", "0.5 63 5 0.9\n9e8 81 3 2.5\n");
  MrclamOptions options;
  options.odometry_interval = 0.01;
  EXPECT_EQ(MrclamError(dir, options),
            "--mrclam_odometry_interval=0.01: gives more than 1e+07 poses "
            "over the measurement times 0.5 to 9e+08 of " +
                dir +
                "/Robot1_Measurement.dat; allowed 0 or a longer interval");
}

}  // namespace
}  // namespace rff
