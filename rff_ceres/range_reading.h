// Whether the ranges of RANGE_BEARING records are distances or depths along
// the heading. A camera that reads a landmark's range from its apparent size
// measures its depth, |l - p| cos(b) for a landmark at bearing b (the UTIAS
// MRCLAM recordings: against their Vicon truth the ranges' error follows
// -|l - p| (1 - cos b), up to 0.45 m at the image's edges).
//
// After a solve that read them as distances, the whitened range residuals
// r_i = (z_i - d_i) / sigma_i are regressed on an offset and a scale
// (1 / sigma_i, d_i / sigma_i: a range calibration's, so that a biased
// distance sensor is not taken for a camera) and on what reading them as
// depths changes, g_i = -d_i (1 - cos b_i) / sigma_i (d, b the estimate's
// distance and bearing). g's slope is 0 for distances and at most 1 for
// depths (less where the fit bent the trajectory to them); its t statistic
// says whether the data tell the two apart. It counts rows as independent,
// which a camera's consecutive sightings are not, hence a threshold far
// above a test's usual 2-3.
#ifndef RFF_CERES_RANGE_READING_H_
#define RFF_CERES_RANGE_READING_H_

#include <functional>
#include <map>

#include "Eigen/Core"
#include "rff_ceres/slam_problem.h"
#include "rff_ceres/types.h"

namespace rff {

struct DepthEvidence {
  int rows = 0;  // Range-bearing rows regressed, outliers left out.
  double slope = 0.0;        // Of g; 0 where nothing is told.
  double t_statistic = 0.0;  // Finite; 0 where nothing is told.
};

// Depths where the slope is positive and its t statistic above this: on
// the held-out protocol's tune side MRCLAM's first solves give 26.6-62.8 and
// every other file under 0.83 in size (docs/heldout.md).
inline constexpr double kMinDepthEvidence = 10.0;

// The regression above over the RANGE_BEARING records of `dataset` whose
// landmark `landmarks` places and whose range is not near it (those keep the
// near-landmark form, near_landmark_cost.h). Rows whose residual exceeds 5
// robust sigmas of all residuals are left out.
DepthEvidence MeasureDepthEvidence(
    const Dataset& dataset,
    const std::function<Eigen::Vector3d(double)>& pose_at,
    const std::map<LandmarkId, Eigen::Vector2d>& landmarks);

// Settles range_bearing_ranges "auto" by `evidence`: "depth", with the range
// calibration estimated (a camera's depth scale and its place on the robot
// are not known), or "distance". True when it became "depth": a problem
// built before reads the ranges as distances.
bool SettleRangeReading(const DepthEvidence& evidence, ProblemOptions* options);

}  // namespace rff

#endif  // RFF_CERES_RANGE_READING_H_
