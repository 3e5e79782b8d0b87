#include "rff_ceres/experiment/methods.h"

#include <set>
#include <sstream>

#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/option_error.h"

namespace rff {
namespace {

// The values of --methods, for its messages.
constexpr char kAllowedMethods[] =
    "a comma list of rff, wnoa or name=flagfile-pattern (e.g. "
    "mine=configs/{family}_mine.flags)";

std::vector<std::string> Split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::string part;
  std::istringstream stream(text);
  while (std::getline(stream, part, separator)) parts.push_back(part);
  if (!text.empty() && text.back() == separator) parts.push_back("");
  return parts;
}

std::string Trim(const std::string& text) {
  const std::size_t begin = text.find_first_not_of(" \t");
  if (begin == std::string::npos) return "";
  const std::size_t end = text.find_last_not_of(" \t");
  return text.substr(begin, end - begin + 1);
}

}  // namespace

bool ParseMethods(const std::string& list, std::vector<Method>* methods,
                  std::string* error) {
  methods->clear();
  std::set<std::string> seen;
  for (const std::string& raw : Split(list, ',')) {
    const std::string item = Trim(raw);
    Method method;
    const std::size_t equals = item.find('=');
    if (equals == std::string::npos) {
      method.name = item;
      if (item == "rff") {
        method.flagfile_pattern = "{configs}/{family}.flags";
      } else if (item == "wnoa") {
        method.flagfile_pattern = "{configs}/{family}_wnoa.flags";
      } else if (!item.empty()) {
        *error = OptionError("methods", list, "unknown method " + item,
                             kAllowedMethods);
        return false;
      }
    } else {
      method.name = Trim(item.substr(0, equals));
      method.flagfile_pattern = Trim(item.substr(equals + 1));
      if (method.flagfile_pattern.empty()) {
        *error = OptionError(
            "methods", list,
            "method " + method.name + " has an empty flagfile pattern",
            kAllowedMethods);
        return false;
      }
    }
    if (method.name.empty()) {
      *error = OptionError("methods", list, "a method has an empty name",
                           kAllowedMethods);
      return false;
    }
    if (!seen.insert(method.name).second) {
      *error = OptionError("methods", list,
                           "method " + method.name + " is given twice",
                           "each method once");
      return false;
    }
    methods->push_back(method);
  }
  if (methods->empty()) {
    *error = OptionError("methods", list, "no method", kAllowedMethods);
    return false;
  }
  return true;
}

std::string MethodFlagfile(const Method& method, const std::string& family,
                           const std::string& configs_dir) {
  return ReplaceAll(
      ReplaceAll(method.flagfile_pattern, "{configs}", configs_dir), "{family}",
      family);
}

std::string MethodNames(const std::vector<Method>& methods) {
  std::string text;
  for (const Method& m : methods) text += (text.empty() ? "" : ", ") + m.name;
  return text;
}

}  // namespace rff
