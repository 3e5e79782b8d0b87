#include "rff_ceres/data_stretches.h"

#include <algorithm>
#include <limits>

namespace rff {

namespace {

// Sorted intervals joined wherever the gap between them is at most max_gap.
std::vector<TimeInterval> Merge(std::vector<TimeInterval> intervals,
                                double max_gap) {
  std::sort(intervals.begin(), intervals.end(),
            [](const TimeInterval& a, const TimeInterval& b) {
              return a.begin < b.begin;
            });
  std::vector<TimeInterval> merged;
  for (const TimeInterval& interval : intervals) {
    if (!merged.empty() && interval.begin - merged.back().end <= max_gap) {
      merged.back().end = std::max(merged.back().end, interval.end);
    } else {
      merged.push_back(interval);
    }
  }
  return merged;
}

}  // namespace

DataTimes DataTimesOf(const Dataset& dataset) {
  DataTimes times;
  for (const Observation& o : dataset.observations) {
    times.constraints.push_back({o.t, o.t});
  }
  for (const Odometry& o : dataset.odometry) {
    times.constraints.push_back({o.t0, o.t1});
  }
  for (const PosePrior& p : dataset.pose_priors) {
    times.constraints.push_back({p.pose.t, p.pose.t});
  }
  for (const TimedPose& p : dataset.ground_truth) times.queries.push_back(p.t);
  return times;
}

std::vector<TimeInterval> DataStretches(const DataTimes& times,
                                        double max_gap) {
  if (times.constraints.empty()) {
    std::vector<TimeInterval> points;
    for (const double t : times.queries) points.push_back({t, t});
    return Merge(std::move(points), max_gap);
  }
  std::vector<TimeInterval> stretches = Merge(times.constraints, max_gap);
  // Each query widens the nearest stretch of constraints (they stay
  // disjoint: a query between two goes to the nearer).
  std::vector<TimeInterval> widened = stretches;
  for (const double t : times.queries) {
    // The first stretch that begins after t, and the one before it.
    const auto after = std::upper_bound(
        stretches.begin(), stretches.end(), t,
        [](double time, const TimeInterval& s) { return time < s.begin; });
    int nearest = -1;
    double distance = std::numeric_limits<double>::infinity();
    if (after != stretches.begin()) {
      nearest = static_cast<int>(after - stretches.begin()) - 1;
      distance = std::max(t - stretches[nearest].end, 0.0);
    }
    if (after != stretches.end() && after->begin - t < distance) {
      nearest = static_cast<int>(after - stretches.begin());
      distance = after->begin - t;
    }
    if (!(distance <= max_gap)) continue;
    widened[nearest].begin = std::min(widened[nearest].begin, t);
    widened[nearest].end = std::max(widened[nearest].end, t);
  }
  // Widened stretches less than max_gap apart are one.
  return Merge(std::move(widened), max_gap);
}

}  // namespace rff
