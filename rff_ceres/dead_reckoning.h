// Dead reckoning: the trajectory obtained by chaining the ODOM records from
// the dataset's PRIOR_POSE, the baseline every solver has to beat.
#ifndef RFF_CERES_DEAD_RECKONING_H_
#define RFF_CERES_DEAD_RECKONING_H_

#include <string>
#include <vector>

#include "rff_ceres/types.h"

namespace rff {

struct DeadReckoningOptions {
  // An interval that no ODOM record covers is an error by default (the motion
  // there is unknown). When set, the pose is held constant across it instead
  // and the gap is reported.
  bool hold_through_gaps = false;
};

// A time interval (begin, end) that no ODOM record covers.
struct OdometryGap {
  double begin = 0.0;
  double end = 0.0;
};

// Chains `odometry` (any order; sorted here by t0) through `start`. Returns
// the pose at every record endpoint in `nodes` (strictly increasing times).
// `start.t` may be any time inside the chain's span (within
// kTimeToleranceSeconds): the chain is integrated forward and backward from
// it, and inside a record the pose moves linearly as in Interpolate().
// Consecutive records must meet (t1 of one == t0 of the next, within the
// tolerance). Fails when records overlap, when `start.t` is outside the span,
// and on a gap unless options.hold_through_gaps; gaps held are listed in
// `gaps`.
bool IntegrateOdometry(const TimedPose& start, std::vector<Odometry> odometry,
                       const DeadReckoningOptions& options,
                       std::vector<TimedPose>* nodes,
                       std::vector<OdometryGap>* gaps, std::string* error);

struct DeadReckoningResult {
  TimedPose start;  // The earliest PRIOR_POSE, where integration starts.
  std::vector<OdometryGap> gaps;
  int odometry_records = 0;
  double span_begin = 0.0;  // Time span covered by the odometry chain.
  double span_end = 0.0;
  // Poses at every ODOM endpoint and at every observation, GT_POSE and
  // PRIOR_POSE time inside the span (interpolated), sorted, times distinct.
  std::vector<TimedPose> poses;
  // Observation and GT_POSE times outside the span: no pose is written for
  // them (nothing is extrapolated).
  int times_outside_span = 0;
};

// Dead reckoning of `dataset` from its earliest PRIOR_POSE. Fails when the
// dataset has no ODOM or no PRIOR_POSE record, and as IntegrateOdometry.
bool DeadReckon(const Dataset& dataset, const DeadReckoningOptions& options,
                DeadReckoningResult* result, std::string* error);

}  // namespace rff

#endif  // RFF_CERES_DEAD_RECKONING_H_
