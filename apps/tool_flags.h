// Command-line parsing shared by every tool: the flagfiles are checked
// before gflags reads them (rff_ceres/io/flagfile_check.h), a leftover
// argument is an error, and a write past the file-size limit fails with an
// error instead of killing the process (SIGXFSZ).
#ifndef RFF_APPS_TOOL_FLAGS_H_
#define RFF_APPS_TOOL_FLAGS_H_

#include <string>
#include <vector>

#include "rff_ceres/io/flagfile_check.h"
#include "rff_ceres/io/output_file.h"

namespace rff {

// Parses the flags and removes them from argv; false with `error` set when
// a flagfile is bad or an argument is left over. gflags itself exits on an
// unknown or malformed flag.
bool ParseToolFlags(int* argc, char*** argv, std::string* error);

// `inputs` and every flagfile ParseToolFlags read, for CheckOutputPaths: an
// output never overwrites the flags it was given by.
std::vector<NamedPath> WithFlagfiles(std::vector<NamedPath> inputs);

// What the tool's flag of this name is ("noname" for a boolean's negation).
FlagKind ToolFlagKind(const std::string& name);

}  // namespace rff

#endif  // RFF_APPS_TOOL_FLAGS_H_
