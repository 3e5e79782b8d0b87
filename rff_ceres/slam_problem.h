// Builds the MAP problem of the paper as a ceres::Problem: one residual block
// per observation over the trajectory blocks its pose map touches and one
// landmark block; odometry over the blocks of two poses; pose, landmark and
// trajectory priors. Landmarks go into elimination group 0 so that the Schur
// solvers eliminate them first.
#ifndef RFF_CERES_SLAM_PROBLEM_H_
#define RFF_CERES_SLAM_PROBLEM_H_

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "Eigen/Core"
#include "ceres/loss_function.h"
#include "ceres/ordered_groups.h"
#include "ceres/problem.h"
#include "rff_ceres/trajectory_model.h"
#include "rff_ceres/types.h"

namespace rff {

// Robust loss on the whitened observation residuals (range, bearing,
// range-bearing); the scale is in units of sigma.
struct LossOptions {
  std::string name = "none";  // none | huber | cauchy
  double scale = 1.0;
};

// Returns the loss (nullptr for "none"), or sets `error` for an unknown name
// or a scale that is not positive.
bool CreateLoss(const LossOptions& options,
                std::unique_ptr<ceres::LossFunction>* loss, std::string* error);

struct ProblemOptions {
  LossOptions loss;
  bool use_odometry = true;
  // Compose ODOM chains between observation times into one residual each
  // (see odometry_preintegration.h).
  bool preintegrate_odometry = true;
  double max_preintegration_seconds = 1.0;
};

class SlamProblem {
 public:
  // `model` must outlive the problem; its blocks are the problem's.
  SlamProblem(TrajectoryModel* model, const ProblemOptions& options);

  // Adds every residual of `dataset`; `landmarks` holds the initial position
  // of every observed or prior landmark (see InitializeLandmarks).
  bool Build(const Dataset& dataset,
             const std::map<LandmarkId, Eigen::Vector2d>& landmarks,
             std::string* error);

  ceres::Problem* problem() { return problem_.get(); }
  const std::map<LandmarkId, Eigen::Vector2d>& landmarks() const {
    return landmarks_;
  }
  // Landmarks in group 0 (eliminated first), trajectory blocks in group 1.
  std::shared_ptr<ceres::ParameterBlockOrdering> Ordering();

 private:
  // Parameter blocks of a cost over `maps` (model block ids rewritten to the
  // cost's local indices, in place), with `landmark` appended if non-null.
  std::vector<double*> LocalBlocks(std::vector<PoseMap*> maps,
                                   double* landmark);
  void AddObservation(const Observation& observation);

  TrajectoryModel* model_;
  ProblemOptions options_;
  std::unique_ptr<ceres::LossFunction> loss_;
  std::unique_ptr<ceres::Problem> problem_;
  std::map<LandmarkId, Eigen::Vector2d> landmarks_;
};

}  // namespace rff

#endif  // RFF_CERES_SLAM_PROBLEM_H_
