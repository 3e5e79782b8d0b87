// Replays every file of the fuzz corpus (test/fuzz/corpus, minimised by
// libFuzzer, see test/fuzz/README.md) through ParseDataset in the normal
// suite: each must return true, or false with an error naming the source,
// never crash (ASan/UBSan builds catch memory and UB errors here too).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "rff_ceres/io/dataset_io.h"

namespace rff {
namespace {

using ::testing::StartsWith;

const std::string kCorpus = std::string(RFF_SOURCE_DIR) + "/test/fuzz/corpus";

std::vector<std::string> CorpusFiles() {
  std::vector<std::string> files;
  for (const auto& entry : std::filesystem::directory_iterator(kCorpus)) {
    if (entry.is_regular_file()) files.push_back(entry.path().string());
  }
  std::sort(files.begin(), files.end());
  return files;
}

bool AllFinite(const Dataset& d) {
  for (const PosePrior& p : d.pose_priors) {
    if (!std::isfinite(p.pose.x + p.pose.y + p.pose.theta + p.pose.t +
                       p.sigma_xy + p.sigma_theta)) {
      return false;
    }
  }
  for (const Odometry& o : d.odometry) {
    if (!std::isfinite(o.t0 + o.t1 + o.dx + o.dy + o.dtheta + o.sigma_x +
                       o.sigma_y + o.sigma_theta)) {
      return false;
    }
  }
  for (const Observation& o : d.observations) {
    if (!std::isfinite(o.t + o.range + o.bearing + o.sigma_range +
                       o.sigma_bearing)) {
      return false;
    }
  }
  return true;
}

TEST(FuzzCorpusReplayTest, EveryFileParsesOrFailsWithNamedError) {
  const std::vector<std::string> files = CorpusFiles();
  // The seeds alone are 9 files; an empty directory must not pass.
  ASSERT_GE(files.size(), 9u) << kCorpus;
  int accepted = 0, rejected = 0;
  for (const std::string& path : files) {
    SCOPED_TRACE(path);
    Dataset d;
    std::string error;
    if (ReadDataset(path, &d, &error)) {
      ++accepted;
      EXPECT_TRUE(error.empty());
      EXPECT_FALSE(d.pose_priors.empty());
      EXPECT_TRUE(AllFinite(d));
    } else {
      ++rejected;
      EXPECT_THAT(error, StartsWith(path + ":"));
      EXPECT_GT(error.size(), path.size() + 2);
    }
  }
  // The corpus keeps both kinds: valid datasets and every kind of bad line.
  EXPECT_GT(accepted, 0);
  EXPECT_GT(rejected, 0);
}

// The hand-written seeds keep their meaning through minimisation.
TEST(FuzzCorpusReplayTest, SeedsParseAsWritten) {
  Dataset d;
  std::string error;
  ASSERT_TRUE(ReadDataset(kCorpus + "/seed_every_record.rffd", &d, &error))
      << error;
  EXPECT_EQ(d.observations.size(), 2u);
  EXPECT_EQ(d.ground_truth_landmarks.size(), 2u);
  ASSERT_FALSE(ReadDataset(kCorpus + "/seed_odom_zero.rffd", &d, &error));
  EXPECT_EQ(error, kCorpus +
                       "/seed_odom_zero.rffd:3: ODOM needs t1 > t0, got t0 = "
                       "1, t1 = 1");
  ASSERT_FALSE(ReadDataset(kCorpus + "/seed_epoch_overflow.rffd", &d, &error));
  EXPECT_EQ(error, kCorpus +
                       "/seed_epoch_overflow.rffd:3: landmark id "
                       "'18446744073709551616' is not a non-negative 64-bit "
                       "integer");
}

}  // namespace
}  // namespace rff
