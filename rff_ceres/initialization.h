// Where the solve starts, kept apart from the prior: the data may choose the
// initial value of the blocks, never the prior mean they deviate from.
//
// - An unknown start heading (PRIOR_POSE heading sigma beyond
//   kLooseHeadingSigma) with odometry is resolved by scoring dead reckoning
//   rotated about the start against the landmark priors.
// - A pilot trajectory (localisation against the landmark priors, fused with
//   dead reckoning when there is odometry) is projected onto the model's
//   blocks as their initial value.
#ifndef RFF_CERES_INITIALIZATION_H_
#define RFF_CERES_INITIALIZATION_H_

#include <string>
#include <vector>

#include "ceres/problem.h"
#include "rff_ceres/mean/localization_mean.h"
#include "rff_ceres/trajectory_model.h"
#include "rff_ceres/types.h"

namespace rff {

// A start heading prior looser than this (rad) is treated as unknown.
inline constexpr double kLooseHeadingSigma = 0.5;

struct StartHeading {
  bool resolved = false;  // False: the prior was tight, or no odometry.
  double heading = 0.0;   // Chosen heading of the earliest PRIOR_POSE.
  double prior_heading = 0.0;
  // Robust observation cost of dead reckoning from the chosen heading and
  // from the prior's own heading (lower is better).
  double cost = 0.0;
  double prior_cost = 0.0;
};

// When the PRIOR_POSEs at the earliest time hold the heading loosely
// (together) and the dataset has odometry and landmark priors, scans start
// headings (every 2 pi / 72, then a golden-section refinement) for the one
// whose dead reckoning best explains the observations against the landmark
// priors (Cauchy cost of the whitened residuals, landmark sigma added to
// the measurement noise). Returns a copy of `dataset` whose PRIOR_POSEs at
// that time are turned by the same angle (same sigmas).
Dataset ResolveStartHeading(const Dataset& dataset, StartHeading* report);

// The pilot: localisation against the landmark priors (fused with odometry
// when there is some), at `times`. False when it cannot be built (no landmark
// priors, nothing localisable); `why` says why.
bool BuildPilotTrajectory(const Dataset& dataset,
                          const LocalizationOptions& localization,
                          const std::vector<double>& times,
                          std::vector<TimedPose>* pilot, std::string* why);

// Sets the blocks of `model` to the MAP fit of `poses` (sigmas 0.05 m and
// 0.05 rad) under the model's own prior: the initial value that reproduces
// a pilot trajectory as closely as the model can. A model with a rule of
// its own uses it (TrajectoryModel::SetBlocksFromPoses: WNOA states); a
// time-ordered one is solved on its envelope (BANDED_CHOLESKY).
bool FitModelToPoses(const std::vector<TimedPose>& poses,
                     TrajectoryModel* model, std::string* error);
// The costs of that fit over the model's blocks: the model's prior and a
// pose prior at each of `poses`.
void AddPoseFitCosts(const std::vector<TimedPose>& poses,
                     TrajectoryModel* model, ceres::Problem* problem);

}  // namespace rff

#endif  // RFF_CERES_INITIALIZATION_H_
