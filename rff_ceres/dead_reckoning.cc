#include "rff_ceres/dead_reckoning.h"

#include <algorithm>
#include <cmath>

#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/metrics.h"
#include "rff_ceres/se2.h"

namespace rff {
namespace {

std::string Interval(double begin, double end) {
  return "[" + FormatNumber(begin) + ", " + FormatNumber(end) + "]";
}

std::string GapText(const OdometryGap& gap) {
  return "(" + FormatNumber(gap.begin) + ", " + FormatNumber(gap.end) + ")";
}

}  // namespace

bool IntegrateOdometry(const TimedPose& start, std::vector<Odometry> odometry,
                       const DeadReckoningOptions& options,
                       std::vector<TimedPose>* nodes,
                       std::vector<OdometryGap>* gaps, std::string* error) {
  nodes->clear();
  gaps->clear();
  if (odometry.empty()) {
    *error = "no ODOM records to integrate";
    return false;
  }
  std::stable_sort(odometry.begin(), odometry.end(),
                   [](const Odometry& a, const Odometry& b) {
                     return a.t0 < b.t0 || (a.t0 == b.t0 && a.t1 < b.t1);
                   });
  // The chain as node times and the motion from each node to the next.
  std::vector<double> times = {odometry.front().t0};
  std::vector<Pose2> motions;
  const Odometry* previous = nullptr;
  for (const Odometry& record : odometry) {
    if (!(record.t1 > record.t0)) {
      *error = "ODOM record " + Interval(record.t0, record.t1) +
               " does not have t1 > t0";
      return false;
    }
    if (previous != nullptr) {
      const double last = times.back();
      if (record.t0 < last - kTimeToleranceSeconds || !(record.t1 > last)) {
        *error = "ODOM records " + Interval(previous->t0, previous->t1) +
                 " and " + Interval(record.t0, record.t1) +
                 " overlap (the motion in between would be counted twice)";
        return false;
      }
      if (record.t0 > last + kTimeToleranceSeconds) {
        gaps->push_back({last, record.t0});
        times.push_back(record.t0);
        motions.push_back(Pose2{});  // Held: no motion across the gap.
      }
    }
    times.push_back(record.t1);
    motions.push_back({record.dx, record.dy, WrapAngle(record.dtheta)});
    previous = &record;
  }
  if (!gaps->empty() && !options.hold_through_gaps) {
    double total = 0.0;
    for (const OdometryGap& gap : *gaps) total += gap.end - gap.begin;
    *error = "odometry gap: no ODOM record covers " + GapText(gaps->front()) +
             " (" + std::to_string(gaps->size()) + " gap(s), " +
             FormatNumber(total) +
             " s in all); use hold_through_gaps (--hold_through_gaps) to "
             "hold the pose through gaps";
    gaps->clear();
    return false;
  }

  const double begin = times.front();
  const double end = times.back();
  if (start.t < begin - kTimeToleranceSeconds ||
      start.t > end + kTimeToleranceSeconds) {
    *error = "the start pose time " + FormatNumber(start.t) +
             " lies outside the odometry span " + Interval(begin, end);
    return false;
  }
  const double t = std::clamp(start.t, begin, end);
  // Anchor node: the last node at or before t, and the start's position
  // inside the motion that follows it.
  std::size_t anchor = static_cast<std::size_t>(
      std::upper_bound(times.begin(), times.end(), t) - times.begin() - 1);
  std::vector<Pose2> poses(times.size());
  const Pose2 start_pose = ToPose2(start);
  if (anchor + 1 == times.size() || t - times[anchor] <= 0.0) {
    poses[anchor] = start_pose;
  } else {
    // Invert Interpolate(p, Compose(p, d), alpha) == start for p.
    const Pose2& d = motions[anchor];
    const double alpha =
        (t - times[anchor]) / (times[anchor + 1] - times[anchor]);
    const double theta = WrapAngle(start_pose.theta - alpha * d.theta);
    const double c = std::cos(theta), s = std::sin(theta);
    poses[anchor] = {start_pose.x - alpha * (c * d.x - s * d.y),
                     start_pose.y - alpha * (s * d.x + c * d.y), theta};
  }
  for (std::size_t k = anchor; k + 1 < poses.size(); ++k) {
    poses[k + 1] = Compose(poses[k], motions[k]);
  }
  for (std::size_t k = anchor; k > 0; --k) {
    poses[k - 1] = Compose(poses[k], Inverse(motions[k - 1]));
  }
  nodes->reserve(times.size());
  for (std::size_t k = 0; k < times.size(); ++k) {
    nodes->push_back(ToTimedPose(times[k], poses[k]));
  }
  return true;
}

bool DeadReckon(const Dataset& dataset, const DeadReckoningOptions& options,
                DeadReckoningResult* result, std::string* error) {
  *result = DeadReckoningResult();
  if (dataset.odometry.empty()) {
    *error =
        "the dataset has no ODOM records: dead reckoning integrates odometry";
    return false;
  }
  if (dataset.pose_priors.empty()) {
    *error = "the dataset has no PRIOR_POSE record to start from";
    return false;
  }
  result->start = EarliestPosePrior(dataset).pose;
  std::vector<TimedPose> nodes;
  if (!IntegrateOdometry(result->start, dataset.odometry, options, &nodes,
                         &result->gaps, error)) {
    // Name the start pose as the user knows it.
    const std::string generic = "the start pose";
    if (error->rfind(generic, 0) == 0) {
      error->replace(0, generic.size(), "the earliest PRIOR_POSE");
    }
    return false;
  }
  result->odometry_records = static_cast<int>(dataset.odometry.size());
  result->span_begin = nodes.front().t;
  result->span_end = nodes.back().t;

  std::vector<double> times;
  for (const TimedPose& node : nodes) times.push_back(node.t);
  times.push_back(result->start.t);
  auto add_if_inside = [&](double t) {
    if (t < result->span_begin - kTimeToleranceSeconds ||
        t > result->span_end + kTimeToleranceSeconds) {
      ++result->times_outside_span;
    } else {
      times.push_back(t);
    }
  };
  for (const Observation& o : dataset.observations) add_if_inside(o.t);
  for (const TimedPose& p : dataset.ground_truth) add_if_inside(p.t);
  std::sort(times.begin(), times.end());
  times.erase(std::unique(times.begin(), times.end()), times.end());
  if (!InterpolateTrajectory(nodes, times, &result->poses, error)) {
    return false;
  }
  for (const TimedPose& p : result->poses) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.theta)) {
      *error = "the integrated pose at t = " + FormatNumber(p.t) +
               " overflows double precision (the ODOM motions sum beyond "
               "1e308 m)";
      return false;
    }
  }
  return true;
}

}  // namespace rff
