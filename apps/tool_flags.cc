#include "tool_flags.h"

#include <csignal>
#include <vector>

#include "gflags/gflags.h"
#include "rff_ceres/io/flagfile_check.h"

namespace rff {

FlagKind ToolFlagKind(const std::string& name) {
  gflags::CommandLineFlagInfo info;
  if (gflags::GetCommandLineFlagInfo(name.c_str(), &info)) {
    return info.type == "bool" ? FlagKind::kBoolean : FlagKind::kValued;
  }
  return name.rfind("no", 0) == 0 &&
                 gflags::GetCommandLineFlagInfo(name.substr(2).c_str(),
                                                &info) &&
                 info.type == "bool"
             ? FlagKind::kBoolean
             : FlagKind::kUnknown;
}

namespace {
std::vector<std::string>& FlagfilesRead() {
  static std::vector<std::string> read;
  return read;
}
}  // namespace

std::vector<NamedPath> WithFlagfiles(std::vector<NamedPath> inputs) {
  for (const std::string& path : FlagfilesRead()) {
    inputs.push_back({"--flagfile", path});
  }
  return inputs;
}

bool ParseToolFlags(int* argc, char*** argv, std::string* error) {
  std::signal(SIGXFSZ, SIG_IGN);
  const std::vector<std::string> args(*argv + 1, *argv + *argc);
  if (!CheckFlagfiles(args, ToolFlagKind, error, nullptr, &FlagfilesRead())) {
    return false;
  }
  gflags::ParseCommandLineFlags(argc, argv, true);
  if (*argc > 1) {
    *error = std::string("unexpected argument '") + (*argv)[1] + "'";
    return false;
  }
  return true;
}

}  // namespace rff
