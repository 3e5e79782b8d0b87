#include "rff_ceres/data_stretches.h"

#include <vector>

#include "gtest/gtest.h"

namespace rff {
namespace {

// The stretches as (begin, end) pairs, for exact comparison.
std::vector<std::pair<double, double>> Pairs(
    const std::vector<TimeInterval>& stretches) {
  std::vector<std::pair<double, double>> pairs;
  for (const TimeInterval& s : stretches) pairs.emplace_back(s.begin, s.end);
  return pairs;
}

using Intervals = std::vector<std::pair<double, double>>;

// Constraints (observations, an odometry interval) join across gaps of at
// most max_gap, and only those.
TEST(DataStretchesTest, ConstraintsSplitAtGapsLongerThanTheLongestBridged) {
  DataTimes times;
  times.constraints = {{900000.0, 900000.0}, {0.0, 0.0}, {2.0, 5.0},
                       {107.0, 107.0},       {6.0, 6.0}, {900100.0, 900100.0}};
  EXPECT_EQ(Pairs(DataStretches(times, 100.0)),
            (Intervals{{0.0, 6.0}, {107.0, 107.0}, {900000.0, 900100.0}}));
}

// A query (a ground-truth time) widens the stretch it is near, the nearer of
// two; one farther than max_gap from every constraint is left out.
TEST(DataStretchesTest, QueriesWidenTheNearestStretchOrAreLeftOut) {
  DataTimes times;
  times.constraints = {{0.0, 10.0}, {1000.0, 1010.0}};
  times.queries = {-50.0, 5.0, 400.0, 1100.0, 1e6};
  EXPECT_EQ(Pairs(DataStretches(times, 100.0)),
            (Intervals{{-50.0, 10.0}, {1000.0, 1100.0}}));
  times.queries = {60.0, 950.0};
  EXPECT_EQ(Pairs(DataStretches(times, 100.0)),
            (Intervals{{0.0, 60.0}, {950.0, 1010.0}}));
}

// Widened stretches that come within max_gap of each other are one.
TEST(DataStretchesTest, WidenedStretchesCloseTogetherJoin) {
  DataTimes times;
  times.constraints = {{0.0, 0.0}, {250.0, 250.0}};
  times.queries = {90.0, 160.0};
  EXPECT_EQ(Pairs(DataStretches(times, 100.0)), (Intervals{{0.0, 250.0}}));
}

// Without constraints the queries alone make the stretches.
TEST(DataStretchesTest, QueriesAloneMakeTheStretches) {
  DataTimes times;
  times.queries = {3.0, 1.0, 500.0};
  EXPECT_EQ(Pairs(DataStretches(times, 100.0)),
            (Intervals{{1.0, 3.0}, {500.0, 500.0}}));
}

TEST(DataStretchesTest, DataTimesOfADataset) {
  Dataset dataset;
  dataset.pose_priors.push_back({{0.0, 0.0, 0.0, 0.0}, 0.1, 0.01});
  Odometry odometry;
  odometry.t0 = 1.0;
  odometry.t1 = 2.0;
  dataset.odometry.push_back(odometry);
  Observation observation;
  observation.t = 3.0;
  dataset.observations.push_back(observation);
  dataset.ground_truth.push_back({4.0, 0.0, 0.0, 0.0});
  const DataTimes times = DataTimesOf(dataset);
  EXPECT_EQ(Pairs(times.constraints),
            (Intervals{{3.0, 3.0}, {1.0, 2.0}, {0.0, 0.0}}));
  EXPECT_EQ(times.queries, std::vector<double>{4.0});
}

}  // namespace
}  // namespace rff
