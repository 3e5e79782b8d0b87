#include "rff_ceres/slam_problem.h"

#include <algorithm>

#include "costs/bearing_cost.h"
#include "costs/landmark_prior_cost.h"
#include "costs/odometry_cost.h"
#include "costs/pose_prior_cost.h"
#include "costs/range_bearing_cost.h"
#include "costs/range_cost.h"
#include "rff_ceres/odometry_preintegration.h"

namespace rff {

bool CreateLoss(const LossOptions& options,
                std::unique_ptr<ceres::LossFunction>* loss,
                std::string* error) {
  loss->reset();
  if (options.name == "none") return true;
  if (!(options.scale > 0.0) || !std::isfinite(options.scale)) {
    *error = "loss scale must be a positive number, got " +
             std::to_string(options.scale);
    return false;
  }
  if (options.name == "huber") {
    loss->reset(new ceres::HuberLoss(options.scale));
  } else if (options.name == "cauchy") {
    loss->reset(new ceres::CauchyLoss(options.scale));
  } else {
    *error =
        "unknown loss '" + options.name + "' (expected none, huber or cauchy)";
    return false;
  }
  return true;
}

SlamProblem::SlamProblem(TrajectoryModel* model, const ProblemOptions& options)
    : model_(model), options_(options) {
  ceres::Problem::Options problem_options;
  // One loss object serves every observation; the problem must not delete it.
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_ = std::make_unique<ceres::Problem>(problem_options);
}

std::vector<double*> SlamProblem::LocalBlocks(std::vector<PoseMap*> maps,
                                              double* landmark) {
  std::vector<double*> blocks;
  std::map<int, int> local;  // Model block id -> index in `blocks`.
  for (PoseMap* map : maps) {
    for (PoseTerm& term : map->terms) {
      auto [it, inserted] =
          local.emplace(term.block, static_cast<int>(blocks.size()));
      if (inserted) blocks.push_back(model_->mutable_block(term.block));
      term.block = it->second;
    }
  }
  if (landmark != nullptr) blocks.push_back(landmark);
  return blocks;
}

void SlamProblem::AddObservation(const Observation& o) {
  PoseMap map = model_->PoseAt(o.t);
  double* landmark = landmarks_.at(o.id).data();
  const std::vector<double*> blocks = LocalBlocks({&map}, landmark);
  ceres::CostFunction* cost = nullptr;
  switch (o.type) {
    case ObservationType::kRange:
      cost = new RangeCost(std::move(map), o.range, o.sigma_range);
      break;
    case ObservationType::kBearing:
      cost = new BearingCost(std::move(map), o.bearing, o.sigma_bearing);
      break;
    case ObservationType::kRangeBearing:
      cost = new RangeBearingCost(std::move(map), o.range, o.bearing,
                                  o.sigma_range, o.sigma_bearing);
      break;
  }
  problem_->AddResidualBlock(cost, loss_.get(), blocks);
}

bool SlamProblem::Build(const Dataset& dataset,
                        const std::map<LandmarkId, Eigen::Vector2d>& landmarks,
                        std::string* error) {
  if (!CreateLoss(options_.loss, &loss_, error)) return false;
  landmarks_ = landmarks;
  for (const Observation& o : dataset.observations) {
    if (landmarks_.count(o.id) == 0) {
      *error = "landmark " + std::to_string(o.id) +
               " is observed but has no initial position";
      return false;
    }
  }
  for (int b = 0; b < model_->num_blocks(); ++b) {
    problem_->AddParameterBlock(model_->mutable_block(b),
                                model_->block_size(b));
  }
  for (auto& [id, position] : landmarks_) {
    problem_->AddParameterBlock(position.data(), 2);
  }
  model_->AddPriorCosts(problem_.get());
  for (const PosePrior& p : dataset.pose_priors) {
    PoseMap map = model_->PoseAt(p.pose.t);
    const std::vector<double*> blocks = LocalBlocks({&map}, nullptr);
    problem_->AddResidualBlock(
        new PosePriorCost(
            std::move(map), Eigen::Vector3d(p.pose.x, p.pose.y, p.pose.theta),
            Eigen::Vector3d(p.sigma_xy, p.sigma_xy, p.sigma_theta)),
        nullptr, blocks);
  }
  for (const LandmarkPrior& p : dataset.landmark_priors) {
    problem_->AddResidualBlock(
        new LandmarkPriorCost(Eigen::Vector2d(p.x, p.y), p.sigma), nullptr,
        landmarks_.at(p.id).data());
  }
  if (options_.use_odometry) {
    // Chains end at every time a pose is needed; without preintegration,
    // at every record (each record is a chain of its own).
    std::vector<double> keep_times;
    for (const Observation& o : dataset.observations) keep_times.push_back(o.t);
    for (const PosePrior& p : dataset.pose_priors)
      keep_times.push_back(p.pose.t);
    if (!options_.preintegrate_odometry) {
      for (const Odometry& o : dataset.odometry) keep_times.push_back(o.t0);
    }
    std::sort(keep_times.begin(), keep_times.end());
    for (const PreintegratedOdometry& o :
         PreintegrateOdometry(dataset.odometry, keep_times,
                              options_.max_preintegration_seconds)) {
      PoseMap map0 = model_->PoseAt(o.t0);
      PoseMap map1 = model_->PoseAt(o.t1);
      const std::vector<double*> blocks = LocalBlocks({&map0, &map1}, nullptr);
      problem_->AddResidualBlock(
          new OdometryCost(std::move(map0), std::move(map1), o.motion,
                           SqrtInformation(o.covariance)),
          nullptr, blocks);
    }
  }
  for (const Observation& o : dataset.observations) AddObservation(o);
  return true;
}

std::shared_ptr<ceres::ParameterBlockOrdering> SlamProblem::Ordering() {
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  for (auto& [id, position] : landmarks_) {
    ordering->AddElementToGroup(position.data(), 0);
  }
  for (int b = 0; b < model_->num_blocks(); ++b) {
    ordering->AddElementToGroup(model_->mutable_block(b), 1);
  }
  return ordering;
}

}  // namespace rff
