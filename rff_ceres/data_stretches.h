// The stretches of time a dataset's data cover: the trajectory's feature
// segments are laid over these only, so that an empty stretch of time (two
// observations 9e5 s apart, a stray ground-truth pose) costs no weights.
#ifndef RFF_CERES_DATA_STRETCHES_H_
#define RFF_CERES_DATA_STRETCHES_H_

#include <vector>

#include "rff_ceres/types.h"

namespace rff {

// A closed interval of time, seconds.
struct TimeInterval {
  double begin = 0.0;
  double end = 0.0;
};

// The times a solve asks the trajectory about.
struct DataTimes {
  // What constrains it: observations and pose priors (begin == end) and
  // odometry intervals.
  std::vector<TimeInterval> constraints;
  // Where it is only evaluated: ground-truth poses.
  std::vector<double> queries;
};

DataTimes DataTimesOf(const Dataset& dataset);

// The constraints merged across gaps of at most `max_gap`, in time order and
// disjoint, each widened to the queries within `max_gap` of it. A query
// farther from every constraint is in none (nothing there for weights to
// fit). Without constraints the queries are merged the same way.
std::vector<TimeInterval> DataStretches(const DataTimes& times, double max_gap);

}  // namespace rff

#endif  // RFF_CERES_DATA_STRETCHES_H_
