#include "rff_ceres/io/pose_covariance_io.h"

#include <sstream>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "test/test_files.h"

namespace rff {
namespace {

using ::testing::HasSubstr;

Eigen::Matrix3d Symmetric(double xx, double xy, double xt, double yy, double yt,
                          double tt) {
  Eigen::Matrix3d c;
  c << xx, xy, xt, xy, yy, yt, xt, yt, tt;
  return c;
}

TEST(PoseCovarianceIoTest, WritesTheUpperTriangle) {
  std::ostringstream out;
  WritePoseCovariances({{1.5, Symmetric(4, 0.5, -0.25, 2, 0, 0.01)}}, &out);
  EXPECT_EQ(out.str(), "1.5 4 0.5 -0.25 2 0 0.01\n");
}

TEST(PoseCovarianceIoTest, RoundTripIsExact) {
  const std::vector<PoseCovariance> written = {
      {0.1 + 0.2, Symmetric(1.0 / 3.0, 1e-300, -1e-2 / 7.0, 2.0 / 3.0,
                            1.0 / 110.0, 0.1 / 3.0)},
      {1234567890.123, Symmetric(0, 0, 0, 0, 0, 0)},
      {1234567890.2, Symmetric(25, 24.999999, 0, 25, 0, 3)}};
  const std::string path =
      rff::testing::TempDir("PoseCovarianceIoTest") + "/c.txt";
  std::string error;
  ASSERT_TRUE(WritePoseCovariances(written, path, &error)) << error;
  std::vector<PoseCovariance> read;
  ASSERT_TRUE(ReadPoseCovariances(path, &read, &error)) << error;
  ASSERT_EQ(read.size(), written.size());
  for (std::size_t k = 0; k < read.size(); ++k) {
    EXPECT_EQ(read[k].t, written[k].t);
    EXPECT_EQ(read[k].covariance, written[k].covariance) << k;
  }
}

TEST(PoseCovarianceIoTest, WritesTheTimesOfTheTrajectory) {
  std::ostringstream out;
  std::string error;
  ASSERT_TRUE(WritePoseCovariances(
      std::vector<TimedPose>{{2.0, 9, 9, 9}, {3.5, 9, 9, 9}},
      {Symmetric(1, 0, 0, 1, 0, 1), Symmetric(2, 1, 0, 3, 0, 0.5)}, &out,
      &error))
      << error;
  EXPECT_EQ(out.str(), "2 1 0 0 1 0 1\n3.5 2 1 0 3 0 0.5\n");
}

TEST(PoseCovarianceIoTest, RefusesMismatchedLengths) {
  std::string error;
  std::ostringstream out;
  EXPECT_FALSE(WritePoseCovariances(std::vector<TimedPose>{{2.0, 0, 0, 0}},
                                    std::vector<Eigen::Matrix3d>{}, &out,
                                    &error));
  EXPECT_EQ(error, "0 covariances for 1 poses");
}

TEST(PoseCovarianceIoTest, MissingFileIsAnError) {
  std::vector<PoseCovariance> read;
  std::string error;
  EXPECT_FALSE(ReadPoseCovariances("/nonexistent/c.txt", &read, &error));
  EXPECT_THAT(error, HasSubstr("/nonexistent/c.txt"));
}

TEST(PoseCovarianceIoTest, SkipsCommentsAndBlankLines) {
  std::istringstream in(
      "# t sxx sxy sxtheta syy sytheta sthetatheta\n\n"
      "1 1 0 0 1 0 1  # first\n");
  std::vector<PoseCovariance> read;
  std::string error;
  ASSERT_TRUE(ParsePoseCovariances(&in, "c", &read, &error)) << error;
  ASSERT_EQ(read.size(), 1u);
  EXPECT_EQ(read[0].covariance, Eigen::Matrix3d::Identity());
}

struct BadCovariances {
  const char* text;
  const char* message;
};

class PoseCovarianceIoErrorTest
    : public ::testing::TestWithParam<BadCovariances> {};

TEST_P(PoseCovarianceIoErrorTest, NamesFileLineAndProblem) {
  std::istringstream in(GetParam().text);
  std::vector<PoseCovariance> read;
  std::string error;
  EXPECT_FALSE(ParsePoseCovariances(&in, "c.txt", &read, &error));
  EXPECT_THAT(error, HasSubstr(GetParam().message));
}

INSTANTIATE_TEST_SUITE_P(
    Errors, PoseCovarianceIoErrorTest,
    ::testing::Values(
        BadCovariances{"1 1 0 0 1 0\n",
                       "c.txt:1: a pose covariance needs 7 fields (t sxx sxy "
                       "sxtheta syy sytheta sthetatheta), got 6"},
        BadCovariances{"1 1 0 0 1 0 1 0\n",
                       "c.txt:1: a pose covariance needs 7 fields"},
        BadCovariances{"1 1 0 0 1 0 1\n2 1 nan 0 1 0 1\n",
                       "c.txt:2: field 3 'nan'"},
        BadCovariances{"1 1 0 0 1 0 inf\n", "c.txt:1: field 7 'inf'"},
        BadCovariances{"1 1 0 0 1 0 1\n2 -1 0 0 1 0 1\n",
                       "c.txt:2: negative variance sxx = -1"},
        BadCovariances{"1 1 0 0 1 0 -0.5\n",
                       "c.txt:1: negative variance sthetatheta = -0.5"},
        BadCovariances{"1 1 1.5 0 1 0 1\n",
                       "c.txt:1: covariance is not positive semi-definite: "
                       "|sxy| > sqrt(sxx syy)"},
        BadCovariances{"1 1 0 0 0 0.1 1\n",
                       "c.txt:1: covariance is not positive semi-definite: "
                       "|sytheta| > sqrt(syy sthetatheta)"},
        // Every pair is a valid 2x2 covariance, the triple is not.
        BadCovariances{"1 4 1.8 -0.9 1 0.45 0.25\n",
                       "c.txt:1: covariance is not positive semi-definite "
                       "(smallest eigenvalue of the correlation matrix -"},
        BadCovariances{"2 1 0 0 1 0 1\n1 1 0 0 1 0 1\n",
                       "c.txt:2: time 1 does not increase (previous 2)"},
        BadCovariances{"2 1 0 0 1 0 1\n2 1 0 0 1 0 1\n",
                       "c.txt:2: time 2 does not increase (previous 2)"}),
    [](const ::testing::TestParamInfo<BadCovariances>& info) {
      return "Case" + std::to_string(info.index);
    });

}  // namespace
}  // namespace rff
