// The paper's simulated protocol (rff_ceres/simulate.h, PaperOptions) cut
// to size, for tests that need a small run with odometry.
#ifndef RFF_TEST_PAPER_DATASET_H_
#define RFF_TEST_PAPER_DATASET_H_

#include <cstdint>
#include <string>

#include "gtest/gtest.h"
#include "rff_ceres/simulate.h"
#include "rff_ceres/types.h"

namespace rff {
namespace testing {

// The paper's simulator (seed `seed`) with `steps` poses, `landmarks`
// landmarks and `per_step` observations per pose; empty if it fails.
inline Dataset PaperDataset(std::uint64_t seed, int steps, int landmarks,
                            int per_step) {
  SimulationOptions sim = PaperOptions(seed);
  sim.num_steps = steps;
  sim.num_landmarks = landmarks;
  sim.observations_per_step = per_step;
  Dataset dataset;
  std::string error;
  EXPECT_TRUE(Simulate(sim, &dataset, &error)) << error;
  return dataset;
}

}  // namespace testing
}  // namespace rff

#endif  // RFF_TEST_PAPER_DATASET_H_
