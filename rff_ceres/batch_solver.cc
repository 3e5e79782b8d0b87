#include "rff_ceres/batch_solver.h"

#include <algorithm>
#include <cmath>

#include "glog/logging.h"
#include "rff_ceres/ceres_solve.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/mean/spline_mean.h"
#include "rff_ceres/mean_rotation.h"

namespace rff {
namespace {

// Where the turn of the mean's start has grown beyond its first-order form
// (kMaxRotationLinearization) at the times of `trajectory`, applies it
// exactly and returns true: the problem is then solved again about the
// turned mean.
constexpr double kMaxRotationLinearization = 0.01;  // m
bool FoldMeanRotation(TrajectoryModel* model,
                      const std::vector<TimedPose>& trajectory) {
  auto* rotation = dynamic_cast<MeanRotationTrajectory*>(model);
  if (rotation == nullptr) return false;
  std::vector<double> times;
  times.reserve(trajectory.size());
  for (const TimedPose& p : trajectory) times.push_back(p.t);
  if (rotation->LinearizationError(times) <= kMaxRotationLinearization) {
    return false;
  }
  VLOG(1) << "turning the mean by " << rotation->delta() << " rad";
  rotation->FoldRotation();
  return true;
}

}  // namespace

double Extent(const std::vector<TimedPose>& poses,
              const std::map<LandmarkId, Eigen::Vector2d>& landmarks) {
  double extent = 0.0;
  for (const TimedPose& p : poses) {
    extent = std::max({extent, std::abs(p.x), std::abs(p.y)});
  }
  for (const auto& [id, l] : landmarks) extent = std::max(extent, l.norm());
  return extent;
}

bool CollectTrajectory(const Dataset& dataset, const TrajectoryModel& model,
                       const std::map<LandmarkId, Eigen::Vector2d>& landmarks,
                       double initial_extent, SlamResult* result,
                       std::string* error) {
  result->trajectory.clear();
  for (const double t : OutputTimes(dataset)) {
    const Eigen::Vector3d pose = model.Pose(t);
    if (!pose.allFinite()) {
      *error = "the solve diverged: non-finite pose at t = " + FormatNumber(t);
      return false;
    }
    result->trajectory.push_back({t, pose.x(), pose.y(), WrapAngle(pose.z())});
  }
  for (const auto& [id, position] : landmarks) {
    if (!position.allFinite()) {
      *error = "the solve diverged: non-finite landmark " + std::to_string(id);
      return false;
    }
  }
  const double limit = 1000.0 * (initial_extent + 1.0);
  const double extent = Extent(result->trajectory, landmarks);
  if (extent > limit) {
    *error = "the solve diverged: the estimate reaches " +
             FormatNumber(extent) + " m from the origin, the initial scene " +
             FormatNumber(initial_extent) + " m";
    return false;
  }
  return true;
}

bool SolveBatch(const Dataset& dataset, const SlamOptions& options,
                ceres::Solver::Options ceres_options, TrajectoryModel* model,
                std::map<LandmarkId, Eigen::Vector2d>* landmarks,
                double initial_extent, std::unique_ptr<SlamProblem>* problem,
                SlamResult* result, std::string* error, bool reuse_problem) {
  bool reuse = reuse_problem && *problem != nullptr;
  for (int round = 0;; ++round, reuse = false) {
    if (!reuse) {
      *problem = std::make_unique<SlamProblem>(model, options.problem);
      (*problem)->set_range_calibration(result->range_calibration);
      (*problem)->set_odometry_calibration(result->odometry_calibration);
      if (!(*problem)->Build(dataset, *landmarks, error)) return false;
    }
    ChooseLinearSolver(options.solver, *model, &ceres_options, result);
    const bool solved =
        RunSolve(options.solver, ceres_options, problem->get(), result, error,
                 /*keep_linearization=*/true);
    VLOG(1) << result->summary.FullReport();
    if (!solved) return false;
    result->converged = result->summary.termination_type == ceres::CONVERGENCE;
    result->total_iterations +=
        static_cast<int>(result->summary.iterations.size());
    *landmarks = (*problem)->landmarks();
    result->range_calibration = (*problem)->range_calibration();
    result->odometry_calibration = (*problem)->odometry_calibration();
    if (!CollectTrajectory(dataset, *model, *landmarks, initial_extent, result,
                           error)) {
      return false;
    }
    if (FoldMeanRotation(model, result->trajectory)) {
      --round;  // The same round again, about the turned mean.
      continue;
    }
    if (round >= options.mean.outer_rounds) return true;
    std::shared_ptr<const MeanFunction> mean =
        RefitSplineMean(result->trajectory,
                        DataFitWeights(dataset, result->trajectory, *landmarks),
                        options.mean.spline_smoothing, error);
    if (!mean) return false;
    model->set_mean(mean);
    ZeroModelBlocks(model);
  }
}

}  // namespace rff
