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

// What a flag of this name (without dashes) is: none, a boolean (for a
// boolean "name" both "name" and "noname"), or one that needs a value.
enum class FlagKind { kUnknown, kBoolean, kValued };
using FlagKindOf = std::function<FlagKind(const std::string& name)>;

// Given each flag line that passed the check, in the order gflags applies
// them (a nested flagfile's lines where it is named): `where` is
// "path:line: ", `line` the line as written, for gflags to parse. Returning
// false stops the check with the error it set.
using FlagLineVisitor = std::function<bool(
    const std::string& where, const std::string& line, std::string* error)>;

// Checks every flagfile named in `args` (--flagfile=A,B or --flagfile A)
// and in the flagfiles they name: each can be read, none includes itself
// directly or through others, and every line is blank, a '#' comment,
// --name=value with a known name or --name of a boolean (gflags would drop
// a valued flag's line without its value). `error` names the file and line.
// `on_flag`, when given, sees every flag line as it is checked; `read`, when
// given, gains the path of every flagfile read (inputs no output may
// overwrite).
bool CheckFlagfiles(const std::vector<std::string>& args,
                    const FlagKindOf& kind_of, std::string* error,
                    const FlagLineVisitor& on_flag = nullptr,
                    std::vector<std::string>* read = nullptr);

}  // namespace rff

#endif  // RFF_CERES_IO_FLAGFILE_CHECK_H_
