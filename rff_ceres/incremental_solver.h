// The paper's online protocol: measurements in time order, a warm-started
// re-solve after every K of them. Trajectory blocks enter the problem (become
// variable) when a residual first touches them and are frozen once no
// residual has touched them for `lag` seconds; landmarks enter when their
// observations so far locate them. Residuals of frozen blocks are folded into
// a prior on the landmarks and calibrations they move (a fixed-lag smoother,
// SlamProblem::FoldFrozenResiduals).
#ifndef RFF_CERES_INCREMENTAL_SOLVER_H_
#define RFF_CERES_INCREMENTAL_SOLVER_H_

#include <cstddef>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "Eigen/Core"
#include "ceres/problem.h"
#include "ceres/solver.h"
#include "rff_ceres/odometry_preintegration.h"
#include "rff_ceres/slam_problem.h"
#include "rff_ceres/slam_solver.h"
#include "rff_ceres/trajectory_model.h"
#include "rff_ceres/types.h"

namespace rff {

// One incremental run (SlamOptions::incremental) over `dataset`, warm-started
// from `model`'s blocks. The problem it builds is left in `problem`.
class IncrementalSolver {
 public:
  IncrementalSolver(const Dataset& dataset, const SlamOptions& options,
                    ceres::Solver::Options ceres_options,
                    TrajectoryModel* model,
                    std::map<LandmarkId, Eigen::Vector2d>* landmarks,
                    std::unique_ptr<SlamProblem>* problem, SlamResult* result)
      : dataset_(dataset),
        options_(options),
        ceres_options_(std::move(ceres_options)),
        model_(model),
        landmarks_(landmarks),
        problem_(problem),
        result_(result) {}

  // Feeds the data in and solves after every update; on success the
  // landmarks, calibrations and result->updates hold the last solve.
  bool Solve(std::string* error);

 private:
  // The problem with the landmark priors and the odometry chains, before
  // any measurement.
  bool Begin(std::string* error);
  // Newest time each block has been touched at, for the blocks `t` reaches.
  void Touch(double t);
  bool InUse(int block) const;
  // The pose priors and odometry up to `now`.
  void AddDataUpTo(double now);
  // Adds the landmarks the pending observations now locate, and those
  // observations.
  void LocatePendingLandmarks(std::string* error);
  // Prior terms of the blocks in use; a WNOA term to a state still in the
  // future would pin the present to the prior mean.
  void AddPriorTermsOfBlocksInUse();
  // Frees the blocks in use touched within the lag, freezes the others;
  // returns how many are free.
  int SetActiveBlocks(double now);
  // Adds the priors and odometry up to `now` and the landmarks that can be
  // located, then solves the blocks in use.
  bool SolveUpdate(double now, int num_measurements, std::string* error);
  // The whole problem over the last update's values, the folded residuals
  // back in place, for covariances and reports.
  bool RebuildWhole(std::string* error);

  const Dataset& dataset_;
  const SlamOptions& options_;
  ceres::Solver::Options ceres_options_;
  TrajectoryModel* model_;
  std::map<LandmarkId, Eigen::Vector2d>* landmarks_;
  std::unique_ptr<SlamProblem>* problem_;
  SlamResult* result_;

  SlamProblem* slam_ = nullptr;
  ceres::Problem* ceres_problem_ = nullptr;
  // Newest time each trajectory block has been touched at (-inf: never).
  std::vector<double> touched_;
  std::vector<PreintegratedOdometry> odometry_;
  std::size_t next_odometry_ = 0, next_prior_ = 0;
  int prior_end_ = 0;  // Trajectory prior terms added for blocks below this.
  std::vector<Observation> pending_;  // Of landmarks not located yet.
  double data_end_ = 0.0;  // Newest time of any record: the last update's t.
};

}  // namespace rff

#endif  // RFF_CERES_INCREMENTAL_SOLVER_H_
