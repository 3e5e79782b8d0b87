// The `../shared` data beside the repository, for tests that skip cleanly
// without it.
#ifndef RFF_TEST_SHARED_DATA_H_
#define RFF_TEST_SHARED_DATA_H_

#include <filesystem>
#include <string>

#include "gtest/gtest.h"
#include "rff_ceres/io/dataset_io.h"
#include "rff_ceres/types.h"

namespace rff {
namespace testing {

// The `../shared` file at `relative` into `dataset`; false, with nothing
// read, where it does not exist (the caller skips). A file there that does
// not read fails the test.
inline bool ReadSharedDataset(const std::string& relative, Dataset* dataset) {
  const std::string path = std::string(RFF_SHARED_DIR) + "/" + relative;
  if (!std::filesystem::exists(path)) return false;
  std::string error;
  EXPECT_TRUE(ReadDataset(path, dataset, &error)) << error;
  return true;
}

}  // namespace testing
}  // namespace rff

#endif  // RFF_TEST_SHARED_DATA_H_
