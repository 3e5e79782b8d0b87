// The options of rffslam.solve(): rff_slam's solver flags by name, turned
// into SlamOptions by rff_slam's own code (the flagfile check,
// SlamOptionsFromFlags), so that a name and a value mean the same in both.
#ifndef RFF_PYTHON_SOLVE_OPTIONS_H_
#define RFF_PYTHON_SOLVE_OPTIONS_H_

#include <string>
#include <utility>
#include <vector>

#include "rff_ceres/options.h"

namespace rff {

// One option as rff_slam reads it: {"prior", "wnoa"} is --prior=wnoa.
using Setting = std::pair<std::string, std::string>;

// Whether `name` is an option: a solver flag (IsSlamFlag) or "flagfile".
// False with "unknown option 'name'" and the nearest option names.
bool CheckOptionName(const std::string& name, std::string* error);

// The SlamOptions of `rff_slam --flagfile=F --name=value ...`: the
// "flagfile" settings first, checked as the tools check flagfiles (but
// holding solver flags only), then the others in order; gflags parses every
// value. The flags are as they were afterwards. False with `error` naming
// the option, or the flagfile and line, that is unknown or has a bad value.
// The options are not validated (ValidateSlamOptions).
bool SlamOptionsFromSettings(const std::vector<Setting>& settings,
                             SlamOptions* options, std::string* error);

}  // namespace rff

#endif  // RFF_PYTHON_SOLVE_OPTIONS_H_
