// The flagfiles of a command line, checked before gflags reads them: gflags
// follows a flagfile that includes itself until the stack overflows, and
// ignores an unknown flag inside a flagfile that it would reject on the
// command line.
#ifndef RFF_CERES_IO_FLAGFILE_CHECK_H_
#define RFF_CERES_IO_FLAGFILE_CHECK_H_

#include <functional>
#include <string>
#include <vector>

namespace rff {

// Whether a flag of this name (without dashes) exists; for a boolean flag
// "name" both "name" and "noname" are known.
using FlagIsKnown = std::function<bool(const std::string& name)>;

// Checks every flagfile named in `args` (--flagfile=A,B or --flagfile A)
// and in the flagfiles they name: each can be read, none includes itself
// directly or through others, and every line is blank, a '#' comment or
// --name[=value] with a known name. `error` names the file and line.
bool CheckFlagfiles(const std::vector<std::string>& args,
                    const FlagIsKnown& is_known, std::string* error);

}  // namespace rff

#endif  // RFF_CERES_IO_FLAGFILE_CHECK_H_
