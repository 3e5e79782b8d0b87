// Runs the built command-line tools (from RFF_BINARY_DIR) in tests: a
// command with a time limit, its exit code and output, and a small valid
// dataset to run them on.
#ifndef RFF_TEST_APP_RUNNER_H_
#define RFF_TEST_APP_RUNNER_H_

#include <sys/wait.h>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <ostream>
#include <sstream>
#include <string>
#include <utility>

#include "rff_ceres/io/text_parser.h"

namespace rff {
namespace testing {

struct RunResult {
  int exit_code = -1;  // 128 + signal when killed by a signal.
  std::string output;  // stdout and stderr.
};

// Runs `command` through the shell with a time limit (a hang is a failure:
// exit code 124).
inline RunResult RunCommand(const std::string& command) {
  RunResult result;
  const std::string full = "timeout 300 " + command + " 2>&1";
  FILE* pipe = popen(full.c_str(), "r");
  if (pipe == nullptr) return result;
  char buffer[4096];
  std::size_t n;
  while ((n = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0) {
    result.output.append(buffer, n);
  }
  const int status = pclose(pipe);
  if (WIFEXITED(status)) {
    result.exit_code = WEXITSTATUS(status);
  } else if (WIFSIGNALED(status)) {
    result.exit_code = 128 + WTERMSIG(status);
  }
  return result;
}

// Replaces {bin} (the build directory) and {dir} (the test's scratch
// directory) in `pattern`.
inline std::string Expand(std::string pattern, const std::string& dir) {
  const std::pair<std::string, std::string> keys[] = {{"{bin}", RFF_BINARY_DIR},
                                                      {"{dir}", dir}};
  for (const auto& [key, value] : keys) {
    for (std::size_t at = pattern.find(key); at != std::string::npos;
         at = pattern.find(key, at + value.size())) {
      pattern.replace(at, key.size(), value);
    }
  }
  return pattern;
}

inline bool HasNonFiniteToken(const std::string& text) {
  std::istringstream in(text);
  std::string token;
  while (in >> token) {
    std::string lower;
    for (const char c : token) lower += static_cast<char>(std::tolower(c));
    if (lower.find("nan") != std::string::npos ||
        lower.find("inf") != std::string::npos) {
      return true;
    }
  }
  return false;
}

// The robot drives along x at 1 m/s for 10 s; three landmarks with priors;
// noise-free range-bearing every second and odometry between. Times start
// at `t0` (0, or a Unix-epoch time).
inline std::string ValidDataset(double t0) {
  auto n = [](double v) { return FormatNumber(v); };
  std::ostringstream out;
  out << "# source: app_errors_test\nRFFD 1\n"
      << "PRIOR_POSE " << n(t0) << " 0 0 0 0.1 0.01\n";
  const double landmarks[3][2] = {{5, 5}, {5, -5}, {10, 3}};
  for (int i = 0; i < 3; ++i) {
    out << "PRIOR_LANDMARK " << i + 1 << " " << landmarks[i][0] << " "
        << landmarks[i][1] << " 1\n";
    out << "GT_LANDMARK " << i + 1 << " " << landmarks[i][0] << " "
        << landmarks[i][1] << "\n";
  }
  for (int k = 0; k <= 10; ++k) {
    const double t = t0 + k;
    if (k < 10) {
      out << "ODOM " << n(t) << " " << n(t + 1) << " 1 0 0 0.05 0.05 0.01\n";
    }
    for (int i = 0; i < 3; ++i) {
      const double dx = landmarks[i][0] - k, dy = landmarks[i][1];
      out << "RANGE_BEARING " << n(t) << " " << i + 1 << " "
          << n(std::hypot(dx, dy)) << " " << n(std::atan2(dy, dx))
          << " 0.1 0.02\n";
    }
    out << "GT_POSE " << n(t) << " " << k << " 0 0\n";
  }
  return out.str();
}

// One command of a table-driven tool test: the expected part of its output
// and a file it must not write.
struct ToolCase {
  const char* name;
  const char* command;
  const char* message;  // Expected part of the output.
  const char* output;   // The file that must not be written ("" for none).
};
// Test names in ctest say the case, not the bytes of the struct.
inline void PrintTo(const ToolCase& c, std::ostream* out) { *out << c.name; }

}  // namespace testing
}  // namespace rff

#endif  // RFF_TEST_APP_RUNNER_H_
