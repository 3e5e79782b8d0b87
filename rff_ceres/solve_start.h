// Where a batch solve starts: its prior mean (for the RFF prior, a WNOA
// solve of the same data), the initial values of its blocks, and the scale
// of the initial scene. RunSlam (slam_solver.cc) calls them in that order.
#ifndef RFF_CERES_SOLVE_START_H_
#define RFF_CERES_SOLVE_START_H_

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "Eigen/Core"
#include "rff_ceres/mean/mean_function.h"
#include "rff_ceres/slam_solver.h"
#include "rff_ceres/trajectory_model.h"
#include "rff_ceres/types.h"

namespace rff {

// The prior mean. The RFF prior starts from a WNOA solve: as its mean with
// a "wnoa" mean (kept in `wnoa_mean_solve`); as its initial trajectory
// (`warm`) without odometry, where the localisation pilot has no motion
// model to bridge gaps between fixes. Its landmarks start the RFF solve
// either way (`warm`). `settled` takes the losses and noise scales
// that solve settled on. Null, with `error`, on failure.
std::shared_ptr<const MeanFunction> BuildMean(
    const Dataset& dataset, const Dataset& resolved, const SlamOptions& options,
    SlamOptions* warm, SlamOptions* settled, SlamResult* wnoa_mean_solve,
    SlamResult* result, std::string* error);

// The blocks start (initial_trajectory "auto") at dead reckoning about a
// constant mean with odometry, else at the fit of the pilot trajectory when
// there is one, else at zero (the prior mean). A "wnoa" mean is already a
// solve of the data, and a "localization" mean the pilot: the start.
bool InitializeBlocks(const Dataset& start, const SlamOptions& options,
                      TrajectoryModel* model, SlamResult* result,
                      std::string* error);

// The scale of the initial scene: the initial trajectory, the landmarks'
// initial positions and the longest range, to tell a run-away solution from
// a large scene.
double InitialExtent(const Dataset& dataset,
                     const std::vector<TimedPose>& initial,
                     const std::map<LandmarkId, Eigen::Vector2d>& landmarks);

}  // namespace rff

#endif  // RFF_CERES_SOLVE_START_H_
