#include "rff_ceres/io/tum_io.h"

#include <cmath>
#include <sstream>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace rff {
namespace {

using ::testing::HasSubstr;

TEST(TumIoTest, WritesPlanarQuaternionAndReadsItBack) {
  const std::vector<TimedPose> poses = {{1248444175.103, 1.0, -2.0, 3.0},
                                        {1248444175.2, 0.5, 0.25, -M_PI / 2}};
  std::ostringstream out;
  WriteTum(poses, &out);
  const std::string text = out.str();
  // theta = -pi/2: qz = sin(-pi/4), qw = cos(-pi/4).
  EXPECT_THAT(text, HasSubstr("1248444175.2 0.5 0.25 0 0 0 -0.7071067811865"));
  std::istringstream in(text);
  std::vector<TimedPose> back;
  std::string error;
  ASSERT_TRUE(ParseTum(&in, "t.tum", &back, &error)) << error;
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[0].t, poses[0].t);
  EXPECT_EQ(back[0].x, 1.0);
  EXPECT_NEAR(back[0].theta, 3.0, 1e-12);
  EXPECT_NEAR(back[1].theta, -M_PI / 2, 1e-12);
}

TEST(TumIoTest, ReadsYawOfUnnormalisedQuaternion) {
  // 2 * (qw, qz) of yaw 0.3.
  std::ostringstream text;
  text.precision(17);
  text << "0 0 0 0 0 0 " << 2 * std::sin(0.15) << " " << 2 * std::cos(0.15)
       << "\n";
  std::istringstream in(text.str());
  std::vector<TimedPose> poses;
  std::string error;
  ASSERT_TRUE(ParseTum(&in, "t.tum", &poses, &error)) << error;
  EXPECT_NEAR(poses[0].theta, 0.3, 1e-12);
}

struct BadTum {
  const char* text;
  const char* message;
};

class TumIoErrorTest : public ::testing::TestWithParam<BadTum> {};

TEST_P(TumIoErrorTest, NamesFileLineAndProblem) {
  std::istringstream in(GetParam().text);
  std::vector<TimedPose> poses;
  std::string error;
  EXPECT_FALSE(ParseTum(&in, "t.tum", &poses, &error));
  EXPECT_THAT(error, HasSubstr(GetParam().message));
}

INSTANTIATE_TEST_SUITE_P(
    Errors, TumIoErrorTest,
    ::testing::Values(
        BadTum{"", "t.tum: no poses"},
        BadTum{"0 0 0 0 0 0 0\n", "t.tum:1: a TUM pose needs 8 fields"},
        BadTum{"0 0 0 0 0 0 0 nan\n", "t.tum:1: field 8 'nan'"},
        BadTum{"0 0 0 0 0 0 0 0\n", "t.tum:1: quaternion has zero norm"},
        BadTum{"1 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n",
               "t.tum:2: time 1 does not increase"},
        BadTum{"0 0 0 0.5 0 0 0 1\n",
               "t.tum:1: not a planar pose (z = 0.5 m, tilt 0 rad; at most "
               "1e-06): the tools compare planar trajectories, z = 0 and qx = "
               "qy = 0"},
        BadTum{"0 0 0 0 0.1 0 0 1\n",
               "t.tum:1: not a planar pose (z = 0 m, "
               "tilt 0.199"}),
    [](const ::testing::TestParamInfo<BadTum>& info) {
      return "Case" + std::to_string(info.index);
    });

}  // namespace
}  // namespace rff
