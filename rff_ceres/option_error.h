// The one form of every message about a bad option or flag value:
//
//   --flag=value: why; allowed range
//
// so that the user sees the spelling to change, what it was, and what it may
// be. Library options are named by the flag that sets them (apps/*.cc).
#ifndef RFF_CERES_OPTION_ERROR_H_
#define RFF_CERES_OPTION_ERROR_H_

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <string>
#include <vector>

#include "rff_ceres/io/text_parser.h"  // FormatNumber, for the values.

namespace rff {

// `flag` without the leading "--"; `value` as given (a double through
// FormatNumber); an empty `why` or `allowed` is left out.
inline std::string OptionError(const std::string& flag,
                               const std::string& value, const std::string& why,
                               const std::string& allowed = "") {
  std::string message = "--" + flag + "=" + value + ":";
  if (!why.empty()) message += " " + why + (allowed.empty() ? "" : ";");
  if (!allowed.empty()) message += " allowed " + allowed;
  return message;
}

// Positive and normal: the floor of every "more than 0" option.
inline bool IsNormalPositive(double value) {
  return value >= std::numeric_limits<double>::min() && std::isfinite(value);
}

// Why a finite value is refused: a denormal (below double precision's
// normal range, 2.2e-308) loses its digits, and its inverse overflows.
inline std::string WhyNotOption(double value) {
  if (!std::isfinite(value)) return "not a finite number";
  if (value != 0.0 && std::abs(value) < std::numeric_limits<double>::min()) {
    return "a denormal number, below double precision's normal range";
  }
  return "";
}
// `value` must be finite and > 0 (>= 0); otherwise `error` names the flag.
inline bool CheckPositiveOption(double value, const char* flag,
                                std::string* error) {
  if (IsNormalPositive(value)) return true;
  *error = OptionError(flag, FormatNumber(value), WhyNotOption(value),
                       "more than 0");
  return false;
}
// More than 0 (normal) and at most `largest`; `too_large` says why a larger
// value is refused, where the allowed range alone does not.
inline bool CheckPositiveUpToOption(double value, const std::string& flag,
                                    double largest, std::string* error,
                                    const std::string& too_large = "") {
  if (IsNormalPositive(value) && value <= largest) return true;
  *error = OptionError(flag, FormatNumber(value),
                       value > largest ? too_large : WhyNotOption(value),
                       "more than 0 up to " + FormatNumber(largest));
  return false;
}
inline bool CheckNonNegativeOption(double value, const char* flag,
                                   std::string* error) {
  if (value == 0.0 || IsNormalPositive(value)) return true;
  *error =
      OptionError(flag, FormatNumber(value), WhyNotOption(value), "0 or more");
  return false;
}

// `value` must be one of `allowed`; otherwise `error` names the flag, says
// `what` is wrong ("unknown prior") and lists the allowed values.
inline bool CheckOneOf(const std::string& value, const char* flag,
                       const char* what,
                       const std::vector<std::string>& allowed,
                       std::string* error) {
  if (std::find(allowed.begin(), allowed.end(), value) != allowed.end()) {
    return true;
  }
  *error = OptionError(flag, value, what, JoinAlternatives(allowed));
  return false;
}

// A numeric option and its flag: more than 0, or 0 or more when
// `zero_allowed`.
struct NumericOption {
  double value;
  const char* flag;
  bool zero_allowed;
};

// Checks `options` in order; the first bad one fills `error`.
inline bool CheckNumericOptions(std::initializer_list<NumericOption> options,
                                std::string* error) {
  for (const NumericOption& o : options) {
    if (!(o.zero_allowed ? CheckNonNegativeOption(o.value, o.flag, error)
                         : CheckPositiveOption(o.value, o.flag, error))) {
      return false;
    }
  }
  return true;
}

}  // namespace rff

#endif  // RFF_CERES_OPTION_ERROR_H_
