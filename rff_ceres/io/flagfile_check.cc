#include "rff_ceres/io/flagfile_check.h"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "rff_ceres/option_error.h"

namespace rff {
namespace {

// Flagfiles deeper than this are an error even without a cycle.
constexpr int kMaxFlagfileDepth = 32;

// "--name=value" or "-name": the name; empty when `arg` is not a flag.
std::string FlagName(const std::string& arg) {
  std::size_t begin = 0;
  while (begin < arg.size() && begin < 2 && arg[begin] == '-') ++begin;
  if (begin == 0) return "";
  const std::size_t equals = arg.find('=');
  return arg.substr(begin,
                    equals == std::string::npos ? equals : equals - begin);
}

std::string FlagValue(const std::string& arg) {
  const std::size_t equals = arg.find('=');
  return equals == std::string::npos ? "" : arg.substr(equals + 1);
}

std::vector<std::string> SplitCommas(const std::string& list) {
  std::vector<std::string> items;
  std::stringstream in(list);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (!item.empty()) items.push_back(item);
  }
  return items;
}

// Whether a --flagfile list names a file in each entry; an empty name
// gflags skips, and the file the user meant would be lost.
bool NamesEveryFile(const std::string& list, std::string* error) {
  if (SplitCommas(list).empty() || list.find(",,") != std::string::npos ||
      list.front() == ',' || list.back() == ',') {
    *error = OptionError("flagfile", list, "an empty file name",
                         "comma-separated file paths");
    return false;
  }
  return true;
}

std::string Trim(const std::string& text) {
  const char* blanks = " \t\r\n";
  const std::size_t begin = text.find_first_not_of(blanks);
  if (begin == std::string::npos) return "";
  return text.substr(begin, text.find_last_not_of(blanks) - begin + 1);
}

// gflags's --fromenv and --tryfromenv read the flags they name from
// FLAGS_<name> environment variables; a flagfile read that way, or another
// --fromenv naming one, would pass every check here unseen.
bool CheckFromEnvironment(const std::string& name, const std::string& value,
                          std::string* error) {
  if (name != "fromenv" && name != "tryfromenv") return true;
  for (const std::string& flag : SplitCommas(value)) {
    if (flag == "flagfile" || flag == "fromenv" || flag == "tryfromenv") {
      *error = OptionError(name, value,
                           "a flagfile read from the environment (directly or "
                           "through another --fromenv) is not checked",
                           "--flagfile=PATH instead");
      return false;
    }
  }
  return true;
}

bool CheckFlagfile(const std::string& path, const FlagKindOf& kind_of,
                   const FlagLineVisitor& on_flag,
                   std::vector<std::string>* open,
                   std::vector<std::string>* read, std::string* error) {
  std::error_code ec;
  const std::string canonical =
      std::filesystem::weakly_canonical(path, ec).string();
  for (const std::string& ancestor : *open) {
    if (ancestor == canonical) {
      *error = OptionError("flagfile", path,
                           open->size() > 1
                               ? "includes itself through other flagfiles"
                               : "includes itself");
      return false;
    }
  }
  if (static_cast<int>(open->size()) >= kMaxFlagfileDepth) {
    *error = OptionError("flagfile", path,
                         "flagfiles nested more than " +
                             std::to_string(kMaxFlagfileDepth) + " deep");
    return false;
  }
  if (std::filesystem::is_directory(path, ec)) {
    *error = OptionError("flagfile", path, "a directory", "a file path");
    return false;
  }
  // A pipe read here would be empty for gflags, which reads the file again
  // (a named one waits for a writer); a device may never end (/dev/zero).
  if (std::filesystem::exists(path, ec) &&
      !std::filesystem::is_regular_file(path, ec)) {
    *error = OptionError("flagfile", path,
                         "not a regular file (a device, pipe or socket)",
                         "a file path");
    return false;
  }
  std::ifstream in(path);
  if (!in) {
    *error = OptionError("flagfile", path, "cannot open for reading");
    return false;
  }
  open->push_back(canonical);
  if (read) read->push_back(path);
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const std::string text = Trim(line);
    if (text.empty() || text[0] == '#') continue;
    const std::string where = path + ":" + std::to_string(number) + ": ";
    const std::string name = FlagName(text);
    if (name.empty()) {
      *error =
          where + "expected --name=value, got '" + text.substr(0, 80) + "'";
      return false;
    }
    if (!CheckFromEnvironment(name, FlagValue(text), error)) {
      *error = where + *error;
      return false;
    }
    if (name == "flagfile") {
      if (!NamesEveryFile(FlagValue(text), error)) {
        *error = where + *error;
        return false;
      }
      for (const std::string& nested : SplitCommas(FlagValue(text))) {
        if (!CheckFlagfile(nested, kind_of, on_flag, open, read, error)) {
          return false;
        }
      }
      continue;
    }
    const FlagKind kind = kind_of(name);
    if (kind == FlagKind::kUnknown) {
      *error = where + "unknown flag '--" + name + "'";
      return false;
    }
    if (kind == FlagKind::kValued && text.find('=') == std::string::npos) {
      *error = where + "'--" + name + "' needs a value: --" + name + "=VALUE";
      return false;
    }
    if (on_flag && !on_flag(where, line, error)) return false;
  }
  open->pop_back();
  return true;
}

}  // namespace

bool CheckFlagfiles(const std::vector<std::string>& args,
                    const FlagKindOf& kind_of, std::string* error,
                    const FlagLineVisitor& on_flag,
                    std::vector<std::string>* read) {
  for (std::size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--") break;
    const std::string name = FlagName(args[i]);
    if (name != "flagfile" && name != "fromenv" && name != "tryfromenv") {
      continue;
    }
    std::string list = FlagValue(args[i]);
    if (args[i].find('=') == std::string::npos && i + 1 < args.size()) {
      list = args[++i];
    }
    if (!CheckFromEnvironment(name, list, error)) return false;
    if (name != "flagfile") continue;
    if (!NamesEveryFile(list, error)) return false;
    for (const std::string& path : SplitCommas(list)) {
      std::vector<std::string> open;
      if (!CheckFlagfile(path, kind_of, on_flag, &open, read, error)) {
        return false;
      }
    }
  }
  return true;
}

}  // namespace rff
