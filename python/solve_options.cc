#include "python/solve_options.h"

#include <algorithm>

#include "apps/slam_flags.h"
#include "apps/tool_flags.h"
#include "gflags/gflags.h"
#include "rff_ceres/io/flagfile_check.h"
#include "rff_ceres/option_error.h"

namespace rff {
namespace {

// Levenshtein distance, for the nearest names of an unknown option.
std::size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1,
                         diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

// A boolean solver flag's negation ("noestimate_range_calibration"), which
// flagfiles may hold as the command line may.
bool IsNegatedSlamFlag(const std::string& name) {
  gflags::CommandLineFlagInfo info;
  return name.rfind("no", 0) == 0 && IsSlamFlag(name.substr(2)) &&
         gflags::GetCommandLineFlagInfo(name.substr(2).c_str(), &info) &&
         info.type == "bool";
}

}  // namespace

bool CheckOptionName(const std::string& name, std::string* error) {
  if (name == "flagfile" || IsSlamFlag(name)) return true;
  std::vector<std::pair<std::size_t, std::string>> nearest;
  std::vector<gflags::CommandLineFlagInfo> flags;
  gflags::GetAllFlags(&flags);
  for (const gflags::CommandLineFlagInfo& flag : flags) {
    if (!IsSlamFlag(flag.name)) continue;
    const std::size_t distance = EditDistance(name, flag.name);
    if (distance <= std::max<std::size_t>(2, name.size() / 4)) {
      nearest.emplace_back(distance, flag.name);
    }
  }
  std::sort(nearest.begin(), nearest.end());
  *error = "unknown option '" + name + "'";
  for (std::size_t i = 0; i < nearest.size() && i < 3; ++i) {
    *error += (i == 0 ? " (did you mean '" : " or '") + nearest[i].second + "'";
  }
  *error += nearest.empty() ? "" : ")";
  *error += "; rffslam.options() lists them";
  return false;
}

bool SlamOptionsFromSettings(const std::vector<Setting>& settings,
                             SlamOptions* options, std::string* error) {
  // Every call starts from the flags as they are (their defaults) and leaves
  // them so.
  gflags::FlagSaver saver;
  // The solver's flags only, each as the tools tell its kind.
  const FlagKindOf kind_of = [](const std::string& name) {
    return IsSlamFlag(name) || IsNegatedSlamFlag(name) ? ToolFlagKind(name)
                                                       : FlagKind::kUnknown;
  };
  // gflags parses each line as it would in the file, alone so that a bad
  // value is named with its line.
  const FlagLineVisitor apply = [](const std::string& where,
                                   const std::string& line,
                                   std::string* error) {
    if (gflags::ReadFlagsFromString(line, "rffslam", false)) return true;
    *error = where + "illegal value in '" + line + "'";
    return false;
  };
  for (const auto& [name, value] : settings) {
    if (name != "flagfile") continue;
    if (!CheckFlagfiles({"--flagfile=" + value}, kind_of, error, apply)) {
      return false;
    }
  }
  for (const auto& [name, value] : settings) {
    if (name == "flagfile") continue;
    if (!CheckOptionName(name, error)) return false;
    if (gflags::SetCommandLineOption(name.c_str(), value.c_str()).empty()) {
      gflags::CommandLineFlagInfo info;
      gflags::GetCommandLineFlagInfo(name.c_str(), &info);
      *error = OptionError(name, value, "not a valid " + info.type + " value");
      return false;
    }
  }
  *options = SlamOptionsFromFlags();
  return true;
}

}  // namespace rff
