// How far apart two solves of the same data ended, for tests that compare
// one path against another.
#ifndef RFF_TEST_TRAJECTORY_DIFFERENCE_H_
#define RFF_TEST_TRAJECTORY_DIFFERENCE_H_

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

#include "rff_ceres/slam_solver.h"

namespace rff {
namespace testing {

// The largest distance between two solves' positions at the same times;
// infinity if their trajectories differ in length.
inline double LargestPositionDifference(const SlamResult& a,
                                        const SlamResult& b) {
  if (a.trajectory.size() != b.trajectory.size()) {
    return std::numeric_limits<double>::infinity();
  }
  double largest = 0.0;
  for (std::size_t i = 0; i < a.trajectory.size(); ++i) {
    largest = std::max(largest,
                       std::hypot(a.trajectory[i].x - b.trajectory[i].x,
                                  a.trajectory[i].y - b.trajectory[i].y));
  }
  return largest;
}

}  // namespace testing
}  // namespace rff

#endif  // RFF_TEST_TRAJECTORY_DIFFERENCE_H_
