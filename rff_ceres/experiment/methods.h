// The methods axis of the experiment grid: solver configurations named on
// the command line, each with the flagfile pattern its options come from.
#ifndef RFF_CERES_EXPERIMENT_METHODS_H_
#define RFF_CERES_EXPERIMENT_METHODS_H_

#include <string>
#include <vector>

namespace rff {

// A solver configuration under comparison. `flagfile_pattern` tells the app
// where the method's options live: "{configs}" and "{family}" in it are
// replaced by the configs directory and the dataset family.
struct Method {
  std::string name;
  std::string flagfile_pattern;
};

// Parses a comma list of methods: "rff" ({configs}/{family}.flags), "wnoa"
// ({configs}/{family}_wnoa.flags) or "name=pattern" for any other. Fails on
// an empty list, an empty name or pattern, an unknown bare name or a name
// given twice.
bool ParseMethods(const std::string& list, std::vector<Method>* methods,
                  std::string* error);

// The flagfile of `method` for `family`: its pattern with {configs} and
// {family} substituted.
std::string MethodFlagfile(const Method& method, const std::string& family,
                           const std::string& configs_dir);

// "rff, wnoa": the method names, for the tables' descriptions.
std::string MethodNames(const std::vector<Method>& methods);

}  // namespace rff

#endif  // RFF_CERES_EXPERIMENT_METHODS_H_
