// Consistency of an estimate's pose covariances with its errors against the
// ground truth (ConsistencySummary in metrics.h): what rff_evaluate
// --covariance reports.
#ifndef RFF_CERES_CONSISTENCY_H_
#define RFF_CERES_CONSISTENCY_H_

#include <string>
#include <vector>

#include "Eigen/Core"
#include "rff_ceres/io/pose_covariance_io.h"
#include "rff_ceres/metrics.h"
#include "rff_ceres/types.h"

namespace rff {

// The covariance at t, linear between the entries around it (a convex
// combination of covariances is one); an entry's own at its time, the end
// entry's outside their span. `covariances` is sorted by time, not empty.
Eigen::Matrix3d CovarianceAt(const std::vector<PoseCovariance>& covariances,
                             double t);

// Fills evaluation->consistency from `covariances`, given at the times of
// `estimate` (as rff_slam writes them): at each ground-truth time, the
// estimate and its covariance interpolated linearly, moved by the
// evaluation's alignment when it has one (Evaluate first). Fails, naming the
// time, when the covariance times are not the estimate's or a position
// covariance is singular.
bool EvaluateConsistency(const std::vector<TimedPose>& ground_truth,
                         const std::vector<TimedPose>& estimate,
                         const std::vector<PoseCovariance>& covariances,
                         Evaluation* evaluation, std::string* error);

}  // namespace rff

#endif  // RFF_CERES_CONSISTENCY_H_
