// The solver flags of rff_slam, defined once and shared with rff_experiment
// (which reads one flagfile per method): the flag names, defaults and help
// texts are the same in every tool.
#ifndef RFF_APPS_SLAM_FLAGS_H_
#define RFF_APPS_SLAM_FLAGS_H_

#include <string>

#include "rff_ceres/options.h"

namespace rff {

// SlamOptions from the current values of the solver flags.
SlamOptions SlamOptionsFromFlags();

// Whether `name` is one of the solver flags defined here, not a tool's own
// flag nor one of gflags or glog: the options the Python module's solve()
// takes.
bool IsSlamFlag(const std::string& name);

}  // namespace rff

#endif  // RFF_APPS_SLAM_FLAGS_H_
