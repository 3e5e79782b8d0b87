// Initial landmark positions for the solver: the prior mean where a
// PRIOR_LANDMARK exists, otherwise from the landmark's observations over the
// initial trajectory: range-bearing inversion, bearing triangulation, or
// range multilateration (paper: landmarks without priors start from their
// measurements).
#ifndef RFF_CERES_LANDMARK_INIT_H_
#define RFF_CERES_LANDMARK_INIT_H_

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "Eigen/Core"
#include "rff_ceres/types.h"

namespace rff {

// Pose (x, y, theta) of the initial trajectory at time t.
using PoseFunction = std::function<Eigen::Vector3d(double t)>;

// Fills `landmarks` with one initial position per landmark that has a prior
// or an observation (a prior mean exactly on a pose the landmark is seen
// from by a bearing moves one prior sigma along that bearing). Fails, naming
// the landmark, when a landmark without a prior cannot be located from its
// observations (e.g. one range only, or bearings from a single direction). With
// `unlocated` non-null such landmarks are listed there instead (incremental
// mode waits for more data).
bool InitializeLandmarks(const Dataset& dataset, const PoseFunction& pose,
                         std::map<LandmarkId, Eigen::Vector2d>* landmarks,
                         std::string* error,
                         std::vector<LandmarkId>* unlocated = nullptr);

}  // namespace rff

#endif  // RFF_CERES_LANDMARK_INIT_H_
