#include "rff_ceres/incremental_solver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "glog/logging.h"
#include "rff_ceres/ceres_solve.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/landmark_init.h"
#include "rff_ceres/linear_system_size.h"

namespace rff {

bool IncrementalSolver::Begin(std::string* error) {
  *problem_ = std::make_unique<SlamProblem>(model_, options_.problem);
  slam_ = problem_->get();
  std::vector<LandmarkId> ids;
  for (const LandmarkPrior& p : dataset_.landmark_priors) ids.push_back(p.id);
  for (const Observation& o : dataset_.observations) ids.push_back(o.id);
  if (!slam_->Begin(ids, error)) return false;
  // A landmark that the whole run cannot locate never will be: an error now,
  // not a retry at every update.
  std::map<LandmarkId, Eigen::Vector2d> locatable;
  if (!InitializeLandmarks(
          dataset_, [&](double t) { return model_->Pose(t); }, &locatable,
          error)) {
    return false;
  }
  ceres_problem_ = slam_->problem();
  ChooseLinearSolver(options_.solver, *model_, &ceres_options_, result_);

  touched_.assign(model_->num_blocks(),
                  -std::numeric_limits<double>::infinity());
  for (const LandmarkPrior& p : dataset_.landmark_priors) {
    slam_->AddLandmark(p.id, Eigen::Vector2d(p.x, p.y));
    slam_->AddLandmarkPrior(p);
  }
  if (!OdometryChains(dataset_, options_.problem, &odometry_, error)) {
    return false;
  }

  data_end_ = -std::numeric_limits<double>::infinity();
  for (const Observation& o : dataset_.observations) {
    data_end_ = std::max(data_end_, o.t);
  }
  for (const PreintegratedOdometry& o : odometry_) {
    data_end_ = std::max(data_end_, o.t1);
  }
  for (const PosePrior& p : dataset_.pose_priors) {
    data_end_ = std::max(data_end_, p.pose.t);
  }
  return true;
}

void IncrementalSolver::Touch(double t) {
  for (const PoseTerm& term : model_->PoseAt(t).terms) {
    touched_[term.block] = std::max(touched_[term.block], t);
  }
}

bool IncrementalSolver::InUse(int block) const {
  return std::isfinite(touched_[block]);
}

void IncrementalSolver::AddDataUpTo(double now) {
  for (; next_prior_ < dataset_.pose_priors.size() &&
         dataset_.pose_priors[next_prior_].pose.t <= now;
       ++next_prior_) {
    slam_->AddPosePrior(dataset_.pose_priors[next_prior_]);
    Touch(dataset_.pose_priors[next_prior_].pose.t);
  }
  for (;
       next_odometry_ < odometry_.size() && odometry_[next_odometry_].t1 <= now;
       ++next_odometry_) {
    slam_->AddOdometry(odometry_[next_odometry_]);
    Touch(odometry_[next_odometry_].t0);
    Touch(odometry_[next_odometry_].t1);
  }
}

void IncrementalSolver::LocatePendingLandmarks(std::string* error) {
  Dataset seen;
  seen.observations = pending_;
  std::map<LandmarkId, Eigen::Vector2d> located;
  std::vector<LandmarkId> unlocated;
  InitializeLandmarks(
      seen, [&](double t) { return model_->Pose(t); }, &located, error,
      &unlocated);
  std::vector<Observation> still_pending;
  for (const auto& [id, position] : located) slam_->AddLandmark(id, position);
  for (const Observation& p : pending_) {
    if (slam_->has_landmark(p.id)) {
      slam_->AddObservation(p);
    } else {
      still_pending.push_back(p);
    }
  }
  pending_.swap(still_pending);
}

void IncrementalSolver::AddPriorTermsOfBlocksInUse() {
  int used_end = prior_end_;
  for (int b = prior_end_; b < model_->num_blocks(); ++b) {
    if (InUse(b)) {
      used_end = b + 1;
    }
  }
  model_->AddPriorCosts(ceres_problem_, prior_end_, used_end);
  prior_end_ = used_end;
}

int IncrementalSolver::SetActiveBlocks(double now) {
  const double lag = options_.incremental.lag;
  int active_blocks = 0;
  for (int b = 0; b < model_->num_blocks(); ++b) {
    const bool active = InUse(b) && (lag <= 0.0 || touched_[b] >= now - lag);
    if (active) {
      ceres_problem_->SetParameterBlockVariable(model_->mutable_block(b));
      ++active_blocks;
    } else {
      ceres_problem_->SetParameterBlockConstant(model_->mutable_block(b));
    }
  }
  return active_blocks;
}

bool IncrementalSolver::SolveUpdate(double now, int num_measurements,
                                    std::string* error) {
  const auto start = std::chrono::steady_clock::now();
  AddDataUpTo(now);
  if (!pending_.empty()) LocatePendingLandmarks(error);
  AddPriorTermsOfBlocksInUse();

  IncrementalUpdate update;
  update.t = std::min(now, data_end_);
  update.num_measurements = num_measurements;
  update.active_blocks = SetActiveBlocks(now);
  // A fixed-lag smoother: what frozen blocks' residuals still say of the
  // landmarks and calibrations, as a prior (each update costs the window,
  // not the run).
  slam_->FoldFrozenResiduals();
  update.folded_residuals = slam_->num_folded();
  // Settled afresh: RunSolve records its own choice for this update.
  ChooseLinearSolver(options_.solver, *model_, &ceres_options_, result_);
  if (!RunSolve(options_.solver, ceres_options_, slam_, result_, error)) {
    *error = "update at t = " + FormatNumber(update.t) + ": " + *error;
    return false;
  }
  update.iterations = static_cast<int>(result_->summary.iterations.size());
  result_->total_iterations += update.iterations;
  update.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
          .count();
  result_->updates.push_back(update);
  VLOG(1) << "update at t = " << now << ": " << update.num_measurements
          << " measurements, " << update.active_blocks << " active blocks, "
          << update.iterations << " iterations, " << update.folded_residuals
          << " folded, " << update.seconds << " s";
  return true;
}

bool IncrementalSolver::RebuildWhole(std::string* error) {
  auto whole = std::make_unique<SlamProblem>(model_, options_.problem);
  whole->set_range_calibration(slam_->range_calibration());
  whole->set_odometry_calibration(slam_->odometry_calibration());
  if (!whole->Build(dataset_, slam_->landmarks(), error)) return false;
  *problem_ = std::move(whole);
  slam_ = problem_->get();
  ceres_problem_ = slam_->problem();
  // Blocks no data touched stay as the updates left them.
  for (int b = 0; b < model_->num_blocks(); ++b) {
    if (!InUse(b)) {
      ceres_problem_->SetParameterBlockConstant(model_->mutable_block(b));
    }
  }
  // The summary counts the data's problem, not the last update's window.
  result_->summary.num_residual_blocks = ceres_problem_->NumResidualBlocks();
  return true;
}

bool IncrementalSolver::Solve(std::string* error) {
  if (!Begin(error)) return false;
  const int every = options_.incremental.every;
  const std::vector<Observation>& observations = dataset_.observations;
  for (std::size_t i = 0; i < observations.size(); ++i) {
    const Observation& o = observations[i];
    Touch(o.t);
    if (slam_->has_landmark(o.id)) {
      slam_->AddObservation(o);
    } else {
      pending_.push_back(o);
    }
    if ((i + 1) % every != 0) continue;
    if (!SolveUpdate(o.t, static_cast<int>(i + 1), error)) return false;
  }
  // The data after the last update (the last observations, odometry and
  // priors after them), or all of it when no update ran.
  if (result_->updates.empty() || next_odometry_ < odometry_.size() ||
      next_prior_ < dataset_.pose_priors.size() ||
      observations.size() % every != 0) {
    if (!SolveUpdate(std::numeric_limits<double>::infinity(),
                     static_cast<int>(observations.size()), error)) {
      return false;
    }
  }
  if (!pending_.empty()) {
    *error = "landmark " + std::to_string(pending_.front().id) +
             " has no PRIOR_LANDMARK and its observations do not locate it";
    return false;
  }
  if (slam_->num_folded() > 0 && !RebuildWhole(error)) return false;
  // Everything the data touched is a variable again, for the covariance.
  for (int b = 0; b < model_->num_blocks(); ++b) {
    if (InUse(b)) {
      ceres_problem_->SetParameterBlockVariable(model_->mutable_block(b));
    }
  }
  result_->converged = result_->summary.termination_type == ceres::CONVERGENCE;
  *landmarks_ = slam_->landmarks();
  result_->range_calibration = slam_->range_calibration();
  result_->odometry_calibration = slam_->odometry_calibration();
  return true;
}

}  // namespace rff
