#include "rff_ceres/io/landmarks_io.h"

#include <sstream>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace rff {
namespace {

using ::testing::HasSubstr;

TEST(LandmarksIoTest, WritesSortedByIdAndReadsBack) {
  Landmark a;
  a.id = 9;
  a.x = 1.5;
  a.y = -2.0;
  Landmark b;
  b.id = 2;
  b.x = 0.1 + 0.2;
  std::ostringstream out;
  WriteLandmarks({a, b}, &out);
  EXPECT_EQ(out.str(), "2 0.30000000000000004 0\n9 1.5 -2\n");
  std::istringstream in(out.str());
  std::vector<Landmark> back;
  std::string error;
  ASSERT_TRUE(ParseLandmarks(&in, "l.landmarks", &back, &error)) << error;
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[0].id, 2);
  EXPECT_EQ(back[0].x, 0.1 + 0.2);
  EXPECT_FALSE(back[0].has_covariance);
}

TEST(LandmarksIoTest, ReadsCovarianceColumns) {
  std::istringstream in("4 1 2 0.5 0.1 0.25\n");
  std::vector<Landmark> landmarks;
  std::string error;
  ASSERT_TRUE(ParseLandmarks(&in, "l", &landmarks, &error)) << error;
  ASSERT_TRUE(landmarks[0].has_covariance);
  EXPECT_EQ(landmarks[0].sxy, 0.1);
  EXPECT_EQ(landmarks[0].syy, 0.25);
}

struct BadLandmarks {
  const char* text;
  const char* message;
};

class LandmarksIoErrorTest : public ::testing::TestWithParam<BadLandmarks> {};

TEST_P(LandmarksIoErrorTest, NamesFileLineAndProblem) {
  std::istringstream in(GetParam().text);
  std::vector<Landmark> landmarks;
  std::string error;
  EXPECT_FALSE(ParseLandmarks(&in, "l.landmarks", &landmarks, &error));
  EXPECT_THAT(error, HasSubstr(GetParam().message));
}

INSTANTIATE_TEST_SUITE_P(
    Errors, LandmarksIoErrorTest,
    ::testing::Values(
        BadLandmarks{"1 2\n", "l.landmarks:1: a landmark needs 3 fields"},
        BadLandmarks{"1 2 3 4\n", "l.landmarks:1: a landmark needs 3 fields"},
        BadLandmarks{"x 2 3\n", "l.landmarks:1: landmark id 'x'"},
        BadLandmarks{"1 2 inf\n", "l.landmarks:1: field 3 'inf'"},
        BadLandmarks{"1 0 0\n1 2 3\n",
                     "l.landmarks:2: duplicate landmark id 1"},
        BadLandmarks{"1 0 0 1 2 1\n",
                     "l.landmarks:1: covariance is not positive"}),
    [](const ::testing::TestParamInfo<BadLandmarks>& info) {
      return "Case" + std::to_string(info.index);
    });

}  // namespace
}  // namespace rff
