#include "rff_ceres/io/dataset_io.h"

#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "rff_ceres/io/text_parser.h"
#include "test/test_files.h"

namespace rff {
namespace {

using ::testing::HasSubstr;

constexpr char kValid[] =
    "# source: unit test\n"
    "# license: CC0\n"
    "RFFD 1\n"
    "PRIOR_POSE 0 1 2 0.5 0.1 0.01\n"
    "PRIOR_LANDMARK 7 10 -3 5\n"
    "ODOM 1 2 1.0 0.0 0.1 0.05 0.05 0.01\n"
    "ODOM 0 1 1.0 0.0 0.1 0.05 0.05 0.01\n"
    "RANGE_BEARING 1.5 7 3.0 -0.2 1 0.03\r\n"  // CRLF is fine.
    "RANGE 1 7 2.5 1   # trailing comment\n"
    "\n"
    "BEARING\t0.5\t9\t4.0\t0.1\n"  // Tabs, and landmark 9 has no prior.
    "GT_POSE 1 2 2 0.5\n"
    "GT_POSE 0 1 2 7.0\n"
    "GT_LANDMARK 9 0 0\n"
    "GT_LANDMARK 7 10 -3\n";

bool Parse(const std::string& text, Dataset* dataset, std::string* error) {
  std::istringstream input(text);
  return ParseDataset(&input, "test.rffd", dataset, error);
}

TEST(DatasetIoTest, ParsesEveryRecordAndSortsByTime) {
  Dataset d;
  std::string error;
  ASSERT_TRUE(Parse(kValid, &d, &error)) << error;
  ASSERT_EQ(d.metadata.size(), 2u);
  EXPECT_EQ(d.metadata[0].first, "source");
  EXPECT_EQ(d.metadata[0].second, "unit test");
  ASSERT_EQ(d.pose_priors.size(), 1u);
  EXPECT_DOUBLE_EQ(d.pose_priors[0].pose.theta, 0.5);
  EXPECT_DOUBLE_EQ(d.pose_priors[0].sigma_theta, 0.01);
  ASSERT_EQ(d.landmark_priors.size(), 1u);
  EXPECT_EQ(d.landmark_priors[0].id, 7);
  ASSERT_EQ(d.odometry.size(), 2u);
  EXPECT_DOUBLE_EQ(d.odometry[0].t0, 0.0);  // Sorted by t0.
  ASSERT_EQ(d.observations.size(), 3u);
  EXPECT_EQ(d.observations[0].type, ObservationType::kBearing);
  EXPECT_EQ(d.observations[0].id, 9);
  EXPECT_EQ(d.observations[1].type, ObservationType::kRange);
  EXPECT_DOUBLE_EQ(d.observations[1].range, 2.5);
  EXPECT_EQ(d.observations[2].type, ObservationType::kRangeBearing);
  EXPECT_DOUBLE_EQ(d.observations[2].bearing, -0.2);
  EXPECT_DOUBLE_EQ(d.observations[2].sigma_bearing, 0.03);
  ASSERT_EQ(d.ground_truth.size(), 2u);
  EXPECT_DOUBLE_EQ(d.ground_truth[0].t, 0.0);
  // Headings are wrapped to (-pi, pi].
  EXPECT_NEAR(d.ground_truth[0].theta, 7.0 - 2.0 * M_PI, 1e-12);
  ASSERT_EQ(d.ground_truth_landmarks.size(), 2u);
  EXPECT_EQ(d.ground_truth_landmarks[0].id, 7);  // Sorted by id.
}

TEST(DatasetIoTest, WriteThenReadIsExact) {
  Dataset d;
  std::string error;
  ASSERT_TRUE(Parse(kValid, &d, &error)) << error;
  d.observations[0].bearing = 0.1 + 0.2;  // Not representable in short form.
  d.ground_truth[1].t = 1248444175.103;   // Unix-epoch time.
  std::ostringstream out;
  WriteDataset(d, &out);
  Dataset back;
  ASSERT_TRUE(Parse(out.str(), &back, &error)) << error;
  EXPECT_EQ(back.metadata, d.metadata);
  ASSERT_EQ(back.observations.size(), d.observations.size());
  EXPECT_EQ(back.observations[0].bearing, d.observations[0].bearing);
  EXPECT_EQ(back.ground_truth[1].t, d.ground_truth[1].t);
  EXPECT_EQ(back.odometry[1].sigma_theta, d.odometry[1].sigma_theta);
}

struct BadCase {
  const char* name;
  const char* text;
  const char* message;  // Expected part of the error, with the line number.
};

class DatasetIoErrorTest : public ::testing::TestWithParam<BadCase> {};

TEST_P(DatasetIoErrorTest, NamesFileLineAndProblem) {
  Dataset d;
  std::string error;
  EXPECT_FALSE(Parse(GetParam().text, &d, &error));
  EXPECT_THAT(error, HasSubstr("test.rffd"));
  EXPECT_THAT(error, HasSubstr(GetParam().message));
}

constexpr char kHead[] = "RFFD 1\nPRIOR_POSE 0 0 0 0 1 1\n";

const BadCase kBadCases[] = {
    {"EmptyFile", "", "missing header"},
    {"OnlyComments", "# nothing\n\n", "missing header"},
    {"MissingHeader", "PRIOR_POSE 0 0 0 0 1 1\n", ":1: missing header"},
    {"WrongVersion", "RFFD 2\n", ":1: unsupported RFFD version '2'"},
    {"SecondHeader", "RFFD 1\nRFFD 1\n", ":2: second RFFD header"},
    {"UnknownRecord", "RFFD 1\nPOSE 1 2 3\n", ":2: unknown record 'POSE'"},
    {"TooFewFields", "RFFD 1\nRANGE 1 2 3\n",
     ":2: RANGE needs 4 fields, got 3"},
    {"TooManyFields", "RFFD 1\nGT_LANDMARK 1 2 3 4\n",
     ":2: GT_LANDMARK needs 3 fields, got 4"},
    {"Unparsable", "RFFD 1\nRANGE 1 2 3x 1\n",
     ":2: field 4 '3x' is not a finite number"},
    {"NaN", "RFFD 1\nGT_POSE 0 nan 0 0\n", ":2: field 3 'nan' is not a finite"},
    {"Infinity", "RFFD 1\nGT_POSE 0 0 inf 0\n",
     "field 4 'inf' is not a finite"},
    {"Overflow", "RFFD 1\nGT_POSE 1e999 0 0 0\n", "'1e999' is not a finite"},
    {"ZeroSigma", "RFFD 1\nRANGE 1 2 3 0\n", ":2: sigma_range must be > 0"},
    {"NegativeSigma", "RFFD 1\nPRIOR_LANDMARK 1 0 0 -1\n",
     ":2: sigma must be > 0, got -1"},
    {"NegativeZeroSigma", "RFFD 1\nBEARING 1 2 0.1 -0\n",
     ":2: sigma_bearing must be > 0, got -0"},
    {"SigmaBelowDoubleResolution", "RFFD 1\nRANGE 1 2 3 1e-100\n",
     ":2: sigma_range 1e-100 is finer than double precision resolves its "
     "range; allowed at least 6.661338147750939e-16"},
    {"BearingSigmaBelowDoubleResolution", "RFFD 1\nBEARING 1 2 0.1 1e-300\n",
     ":2: sigma_bearing 1e-300 is finer than double precision resolves its "
     "bearing; allowed at least 2.220446049250313e-16"},
    {"PosePriorSigmaDenormal", "RFFD 1\nPRIOR_POSE 0 0 0 0 1e-320 1\n",
     ":2: sigma_xy 1e-320 is finer than double precision "
     "resolves its position; allowed at least 2.220446049250313e-16"},
    {"LandmarkPriorSigmaTiny", "RFFD 1\nPRIOR_LANDMARK 3 100 0 1e-20\n",
     ":2: sigma 1e-20 is finer than double precision resolves its position; "
     "allowed at least 2.220446049250313e-14"},
    {"OdometryIntervalTooShort", "RFFD 1\nODOM 0 1e-150 0 0 0 1 1 1\n",
     ":2: t1 - t0 = 1e-150 s is finer than double precision resolves its "
     "times; allowed at least 2.220446049250313e-16"},
    {"SpanBeyondDoubleRange",
     "RFFD 1\nPRIOR_POSE -1e308 0 0 0 1 1\nRANGE 1e308 2 3 1\n",
     "test.rffd: the records' times run from -1e+308 to 1e+308 s, a span "
     "beyond double range; allowed times whose differences are finite"},
    {"OdometryBackwards", "RFFD 1\nODOM 2 1 0 0 0 1 1 1\n",
     ":2: ODOM needs t1 > t0"},
    {"OdometryZeroLength", "RFFD 1\nODOM 1 1 0 0 0 1 1 1\n",
     ":2: ODOM needs t1 > t0"},
    {"NegativeId", "RFFD 1\nRANGE 1 -2 3 1\n",
     ":2: landmark id '-2' is not a non-negative"},
    {"FractionalId", "RFFD 1\nRANGE 1 2.5 3 1\n", "landmark id '2.5'"},
    {"OverflowingId", "RFFD 1\nGT_LANDMARK 99999999999999999999 0 0\n",
     ":2: landmark id '99999999999999999999'"},
    {"DuplicateGroundTruthLandmark",
     "RFFD 1\nGT_LANDMARK 3 0 0\nGT_LANDMARK 3 1 1\n",
     ":3: duplicate GT_LANDMARK for landmark 3"},
    {"DuplicateLandmarkPrior",
     "RFFD 1\nPRIOR_LANDMARK 3 0 0 1\nPRIOR_LANDMARK 3 1 1 1\n",
     ":3: duplicate PRIOR_LANDMARK for landmark 3"},
    {"DuplicateGroundTruthTime",
     "RFFD 1\nPRIOR_POSE 0 0 0 0 1 1\nGT_POSE 1 0 0 0\nGT_POSE 1 1 0 0\n",
     "two GT_POSE records at time 1"},
    {"NoPosePrior", "RFFD 1\nRANGE 1 2 3 1\n", "no PRIOR_POSE record"},
};

INSTANTIATE_TEST_SUITE_P(AllErrorClasses, DatasetIoErrorTest,
                         ::testing::ValuesIn(kBadCases),
                         [](const ::testing::TestParamInfo<BadCase>& info) {
                           return std::string(info.param.name);
                         });

TEST(DatasetIoTest, NulByteInsideLineIsAnError) {
  std::string with_nul = std::string(kHead) + "RANGE 1 2";
  with_nul.push_back('\0');
  with_nul += " 3 1\n";
  Dataset d;
  std::string error;
  EXPECT_FALSE(Parse(with_nul, &d, &error));
  EXPECT_THAT(error, HasSubstr("test.rffd:3: NUL byte"));
}

TEST(DatasetIoTest, HugeLineIsRefusedWithoutReadingItWhole) {
  std::string text = std::string(kHead) + "RANGE ";
  text += std::string(10 * 1024 * 1024, '1');
  Dataset d;
  std::string error;
  EXPECT_FALSE(Parse(text, &d, &error));
  EXPECT_THAT(error, HasSubstr("test.rffd:3: line longer than"));
}

TEST(DatasetIoTest, ObservationOfLandmarkWithoutPriorIsFine) {
  Dataset d;
  std::string error;
  EXPECT_TRUE(Parse(std::string(kHead) + "RANGE 1 42 3 1\n", &d, &error))
      << error;
  EXPECT_TRUE(d.landmark_priors.empty());
}

TEST(DatasetIoTest, NegativeNoisyRangeIsData) {
  // Gaussian noise on a short distance can give a negative range.
  Dataset d;
  std::string error;
  ASSERT_TRUE(Parse(std::string(kHead) + "RANGE 1 42 -0.25 1\n", &d, &error))
      << error;
  EXPECT_EQ(d.observations[0].range, -0.25);
}

// The writer never leaves a file its reader refuses: a sigma finer than
// double precision resolves (a simulator's flag set too fine) is an error,
// and nothing is written.
TEST(DatasetIoTest, WriterRefusesWhatTheReaderWould) {
  Dataset d;
  std::string error;
  ASSERT_TRUE(Parse(kValid, &d, &error)) << error;
  for (Observation& o : d.observations) {
    if (o.type == ObservationType::kRangeBearing) o.sigma_range = 1e-300;
  }
  const std::string path = testing::TempDir("DatasetIoTest") + "/fine.rffd";
  EXPECT_FALSE(WriteDataset(d, path, &error));
  EXPECT_EQ(error, path +
                       ": not written: RANGE_BEARING at t = 1.5: "
                       "sigma_range 1e-300 is finer than double precision "
                       "resolves its range; allowed at least "
                       "6.661338147750939e-16 (the reader would refuse the "
                       "file)");
  EXPECT_FALSE(std::filesystem::exists(path));
  // A sigma scaled past the largest double (a converter's per-metre sigma
  // of 1e308) is no number the reader takes.
  ASSERT_TRUE(Parse(kValid, &d, &error)) << error;
  ASSERT_FALSE(d.odometry.empty());
  d.odometry.back().sigma_x = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(WriteDataset(d, path, &error));
  EXPECT_EQ(error, path + ": not written: ODOM at t = " +
                       FormatNumber(d.odometry.back().t0) +
                       " holds a number that is not finite (the reader would "
                       "refuse the file)");
  EXPECT_FALSE(std::filesystem::exists(path));
}

TEST(DatasetIoTest, MissingFileNamesThePath) {
  Dataset d;
  std::string error;
  EXPECT_FALSE(ReadDataset("/nonexistent/x.rffd", &d, &error));
  EXPECT_THAT(error, HasSubstr("/nonexistent/x.rffd: cannot open"));
}

}  // namespace
}  // namespace rff
