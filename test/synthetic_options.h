// configs/synthetic_range_bearing.flags (one solve, one thread) as
// SlamOptions, for the tests and benchmarks that solve the paper's
// simulated protocol.
#ifndef RFF_TEST_SYNTHETIC_OPTIONS_H_
#define RFF_TEST_SYNTHETIC_OPTIONS_H_

#include "rff_ceres/slam_solver.h"

namespace rff {
namespace testing {

inline SlamOptions SyntheticRangeBearingOptions() {
  SlamOptions options;
  options.mean.name = "localization";
  // The flags give the kernel hyperparameters, so "auto" learning is off.
  options.learn_hyperparameters = "off";
  FeatureTrajectoryOptions& t = options.features;
  t.position_kernel.name = "rbf";
  t.position_kernel.lengthscale = 5.0;
  t.position_kernel.variance = 100.0;
  t.heading_kernel = t.position_kernel;
  t.heading_kernel.variance = 0.25;
  t.family = "hilbert";
  t.num_position_features = 24;
  t.num_heading_features = 24;
  t.segment_length = 50.0;
  t.segment_overlap = 15.0;
  options.solver.linear_solver = "DENSE_SCHUR";
  options.solver.num_threads = 1;
  return options;
}

}  // namespace testing
}  // namespace rff

#endif  // RFF_TEST_SYNTHETIC_OPTIONS_H_
