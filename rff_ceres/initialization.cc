#include "rff_ceres/initialization.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>

#include "Eigen/Geometry"
#include "ceres/problem.h"
#include "ceres/solver.h"
#include "costs/pose_prior_cost.h"
#include "rff_ceres/banded_minimizer.h"
#include "rff_ceres/dead_reckoning.h"
#include "rff_ceres/mean_rotation.h"
#include "rff_ceres/se2.h"
#include "rff_ceres/slam_problem.h"

namespace rff {
namespace {

// Candidate start headings of the scan; the refinement then searches the
// best cell, so the scan only has to land in the right basin.
constexpr int kHeadingCandidates = 72;
// Cauchy scale of the heading score (whitened units): far-off residuals of a
// wrong heading saturate instead of dominating.
constexpr double kScoreLossScale = 2.0;
// Sigmas of the pilot fit: tighter than any pilot is accurate, looser than
// the model's feature resolution, so the fit follows the pilot's shape.
constexpr double kFitSigmaXy = 0.05;
constexpr double kFitSigmaTheta = 0.05;
// Largest step of the fit's heading targets per stage (rad): well inside
// the pi where the wrapped residual would turn the other way.
constexpr double kMaxHeadingStage = 0.5 * M_PI;

// Observations grouped by time with the dead-reckoned pose there, for
// scoring rotations of the dead reckoning about its start.
struct ScoredTime {
  Eigen::Vector3d pose;
  std::vector<Observation> observations;
};

// Sum of Cauchy(whitened residual) of the observations when dead reckoning
// is rotated by `rotation` about the start position.
double HeadingCost(const std::vector<ScoredTime>& times,
                   const Eigen::Vector2d& start,
                   const std::map<LandmarkId, KnownLandmark>& landmarks,
                   double rotation) {
  const Eigen::Rotation2Dd r(rotation);
  const double c2 = kScoreLossScale * kScoreLossScale;
  double cost = 0.0;
  for (const ScoredTime& s : times) {
    Eigen::Vector3d pose;
    pose << start + r * (s.pose.head<2>() - start), s.pose.z() + rotation;
    for (const MapResidualRow& row :
         MapResiduals(s.observations, landmarks, pose)) {
      cost += std::log1p(row.residual * row.residual / c2);
    }
  }
  return cost;
}

// One MAP fit of the blocks to `poses` under the model's prior (see
// FitModelToPoses), from the blocks' current values.
bool FitModelToPosesOnce(const std::vector<TimedPose>& poses,
                         TrajectoryModel* model, std::string* error) {
  ceres::Problem problem;
  AddPoseFitCosts(poses, model, &problem);
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  options.max_num_iterations = 20;
  // The pose maps are affine in the weights and the staged targets keep
  // the headings off their wrap: linear least squares, whose undamped
  // first step is the minimum and whose second confirms it.
  options.initial_trust_region_radius = options.max_trust_region_radius;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  // The model's blocks in time order: a narrow envelope (feature windows,
  // WNOA states) factorises with no symbolic analysis, as the solves do.
  const BandedColumns columns = ModelBandColumns(model);
  std::string why;
  std::unique_ptr<BandedProblem> banded;
  if (BandedSolvable(problem, columns, &why)) {
    banded = std::make_unique<BandedProblem>(problem, columns);
    if (!banded->BeatsSparseCholesky()) banded.reset();
  }
  if (banded) {
    MinimizeBanded(options, banded.get(), &problem, &summary);
  } else {
    ceres::Solve(options, &problem, &summary);
  }
  if (summary.termination_type == ceres::FAILURE ||
      !std::isfinite(summary.final_cost)) {
    *error = "fitting the initial trajectory failed: " + summary.message;
    return false;
  }
  return true;
}

}  // namespace

void AddPoseFitCosts(const std::vector<TimedPose>& poses,
                     TrajectoryModel* model, ceres::Problem* problem) {
  for (int b = 0; b < model->num_blocks(); ++b) {
    problem->AddParameterBlock(model->mutable_block(b), model->block_size(b));
  }
  model->AddPriorCosts(problem);
  const Eigen::Vector3d sigma(kFitSigmaXy, kFitSigmaXy, kFitSigmaTheta);
  for (const TimedPose& p : poses) {
    PoseMap map = model->PoseAt(p.t);
    const std::vector<double*> blocks = BindPoseMaps(model, {&map});
    problem->AddResidualBlock(
        new PosePriorCost(std::move(map), Eigen::Vector3d(p.x, p.y, p.theta),
                          sigma),
        nullptr, blocks);
  }
}

Dataset ResolveStartHeading(const Dataset& dataset, StartHeading* report) {
  *report = StartHeading();
  Dataset resolved = dataset;
  if (resolved.pose_priors.empty() || resolved.odometry.empty() ||
      resolved.landmark_priors.empty()) {
    return resolved;
  }
  PosePrior* first = &EarliestPosePrior(&resolved);
  report->prior_heading = report->heading = first->pose.theta;
  // Every PRIOR_POSE at the start holds its heading: it is unknown only
  // when their information together is looser than kLooseHeadingSigma.
  double information = 0.0;
  for (const PosePrior& p : resolved.pose_priors) {
    if (p.pose.t == first->pose.t) {
      information += 1.0 / (p.sigma_theta * p.sigma_theta);
    }
  }
  if (!(information < 1.0 / (kLooseHeadingSigma * kLooseHeadingSigma))) {
    return resolved;
  }

  DeadReckoningResult dr;
  DeadReckoningOptions dr_options;
  dr_options.hold_through_gaps = true;
  std::string ignored;
  if (!DeadReckon(resolved, dr_options, &dr, &ignored)) return resolved;
  std::map<LandmarkId, KnownLandmark> landmarks;
  for (const LandmarkPrior& l : resolved.landmark_priors) {
    landmarks[l.id] = {Eigen::Vector2d(l.x, l.y), l.sigma};
  }
  std::map<double, ScoredTime> by_time;
  for (const Observation& o : resolved.observations) {
    if (landmarks.count(o.id) == 0) continue;
    ScoredTime& s = by_time[o.t];
    if (s.observations.empty()) {
      const TimedPose p = PoseAtTime(dr.poses, o.t);
      s.pose << p.x, p.y, p.theta;
    }
    s.observations.push_back(o);
  }
  if (by_time.empty()) return resolved;
  std::vector<ScoredTime> times;
  for (auto& [t, s] : by_time) times.push_back(std::move(s));
  const Eigen::Vector2d start(first->pose.x, first->pose.y);
  auto cost = [&](double rotation) {
    return HeadingCost(times, start, landmarks, rotation);
  };

  const double cell = 2.0 * M_PI / kHeadingCandidates;
  double best = 0.0, best_cost = cost(0.0);
  report->prior_cost = best_cost;
  for (int k = 1; k < kHeadingCandidates; ++k) {
    const double c = cost(k * cell);
    if (c < best_cost) {
      best = k * cell;
      best_cost = c;
    }
  }
  // Golden-section search over the best candidate's neighbourhood.
  const double ratio = 0.5 * (std::sqrt(5.0) - 1.0);
  double a = best - cell, b = best + cell;
  double x1 = b - ratio * (b - a), x2 = a + ratio * (b - a);
  double f1 = cost(x1), f2 = cost(x2);
  while (b - a > 1e-4) {
    if (f1 < f2) {
      b = x2, x2 = x1, f2 = f1;
      x1 = b - ratio * (b - a), f1 = cost(x1);
    } else {
      a = x1, x1 = x2, f1 = f2;
      x2 = a + ratio * (b - a), f2 = cost(x2);
    }
  }
  const double refined = 0.5 * (a + b);
  const double refined_cost = cost(refined);
  if (refined_cost < best_cost) {
    best = refined;
    best_cost = refined_cost;
  }
  for (PosePrior& p : resolved.pose_priors) {
    if (p.pose.t == first->pose.t) {
      p.pose.theta = WrapAngle(p.pose.theta + best);
    }
  }
  report->resolved = true;
  report->heading = first->pose.theta;
  report->cost = best_cost;
  return resolved;
}

bool BuildPilotTrajectory(const Dataset& dataset,
                          const LocalizationOptions& localization,
                          const std::vector<double>& times,
                          std::vector<TimedPose>* pilot, std::string* why) {
  pilot->clear();
  LocalizationReport report;
  const std::shared_ptr<const MeanFunction> localized =
      BuildLocalizationMean(dataset, localization, &report, why);
  if (!localized) return false;
  for (const double t : times) {
    const Eigen::Vector3d p = localized->Evaluate(t);
    pilot->push_back({t, p.x(), p.y(), p.z()});
  }
  return true;
}

bool FitModelToPoses(const std::vector<TimedPose>& poses,
                     TrajectoryModel* model, std::string* error) {
  if (auto* rotation = dynamic_cast<MeanRotationTrajectory*>(model)) {
    *rotation->mutable_block(0) = 0.0;
    return FitModelToPoses(poses, rotation->inner(), error);
  }
  if (poses.empty()) return true;
  if (model->SetBlocksFromPoses(poses)) return true;
  // The pose residual wraps the heading: a target more than pi from the
  // model's heading would pull it the wrong way round. The headings are
  // unwrapped along the poses from the model's branch and approached in
  // stages of at most kMaxHeadingStage (a continuation).
  std::vector<double> start(poses.size()), target(poses.size());
  double largest_gap = 0.0;
  for (std::size_t k = 0; k < poses.size(); ++k) {
    start[k] = model->Pose(poses[k].t).z();
    const double previous = k == 0 ? start[0] : target[k - 1];
    target[k] = previous + WrapAngle(poses[k].theta - previous);
    largest_gap = std::max(largest_gap, std::abs(target[k] - start[k]));
  }
  const int stages =
      std::max(1, static_cast<int>(std::ceil(largest_gap / kMaxHeadingStage)));
  for (int stage = 1; stage <= stages; ++stage) {
    const double fraction = static_cast<double>(stage) / stages;
    std::vector<TimedPose> staged = poses;
    for (std::size_t k = 0; k < poses.size(); ++k) {
      staged[k].theta = start[k] + fraction * (target[k] - start[k]);
    }
    if (!FitModelToPosesOnce(staged, model, error)) return false;
  }
  return true;
}

}  // namespace rff
