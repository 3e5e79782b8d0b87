// The batch solve: the whole dataset in one Ceres problem, with the outer
// rounds of the smoothing-spline mean (paper III-B.2), and the divergence
// guards every solve's trajectory passes through.
#ifndef RFF_CERES_BATCH_SOLVER_H_
#define RFF_CERES_BATCH_SOLVER_H_

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "Eigen/Core"
#include "ceres/solver.h"
#include "rff_ceres/slam_problem.h"
#include "rff_ceres/slam_solver.h"
#include "rff_ceres/trajectory_model.h"
#include "rff_ceres/types.h"

namespace rff {

// Largest |coordinate| of the poses and landmarks, for the runaway check.
double Extent(const std::vector<TimedPose>& poses,
              const std::map<LandmarkId, Eigen::Vector2d>& landmarks);

// The trajectory at the output times, with the divergence guards: every
// value finite, and nothing run away to more than 1000 times the scale of
// the initial scene (which a converged solution never does).
bool CollectTrajectory(const Dataset& dataset, const TrajectoryModel& model,
                       const std::map<LandmarkId, Eigen::Vector2d>& landmarks,
                       double initial_extent, SlamResult* result,
                       std::string* error);

// Paper III-B.2: after each solve the prior mean becomes a smoothing spline
// of the estimate and the weights restart from zero. With
// `reuse_problem`, the first solve is of `*problem` as it stands (built
// over `model` with `options.problem`, its costs following the model's
// scales in place: TrajectoryModel::AdoptScales) instead of a new build.
bool SolveBatch(const Dataset& dataset, const SlamOptions& options,
                ceres::Solver::Options ceres_options, TrajectoryModel* model,
                std::map<LandmarkId, Eigen::Vector2d>* landmarks,
                double initial_extent, std::unique_ptr<SlamProblem>* problem,
                SlamResult* result, std::string* error,
                bool reuse_problem = false);

}  // namespace rff

#endif  // RFF_CERES_BATCH_SOLVER_H_
