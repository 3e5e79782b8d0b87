// Scratch files for tests that read and write real files.
#ifndef RFF_TEST_TEST_FILES_H_
#define RFF_TEST_TEST_FILES_H_

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "gtest/gtest.h"

namespace rff {
namespace testing {

// A fresh directory per test case under the build tree (ctest runs the
// cases in parallel, so each gets its own).
inline std::string TempDir(const std::string& suite) {
  const std::string dir =
      std::string(RFF_BINARY_DIR) + "/test_tmp/" + suite + "/" +
      ::testing::UnitTest::GetInstance()->current_test_info()->name();
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline void WriteFile(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
}

inline std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

// How many times `what` occurs in `text` (overlaps counted).
inline int CountOccurrences(const std::string& text, const std::string& what) {
  int count = 0;
  for (std::size_t at = text.find(what); at != std::string::npos;
       at = text.find(what, at + 1)) {
    ++count;
  }
  return count;
}

}  // namespace testing
}  // namespace rff

#endif  // RFF_TEST_TEST_FILES_H_
