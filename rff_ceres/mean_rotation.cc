#include "rff_ceres/mean_rotation.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <utility>

#include "Eigen/Geometry"
#include "costs/diagonal_prior_cost.h"

namespace rff {

RotatedMean::RotatedMean(std::shared_ptr<const MeanFunction> mean,
                         double anchor_time, double angle)
    : mean_(std::move(mean)),
      anchor_(mean_->Evaluate(anchor_time).head<2>()),
      rotation_(Eigen::Rotation2Dd(angle).toRotationMatrix()),
      angle_(angle) {}

Eigen::Vector3d RotatedMean::Evaluate(double t) const {
  const Eigen::Vector3d m = mean_->Evaluate(t);
  Eigen::Vector3d rotated;
  rotated << anchor_ + rotation_ * (m.head<2>() - anchor_), m.z() + angle_;
  return rotated;
}

MeanRotationTrajectory::MeanRotationTrajectory(
    std::unique_ptr<TrajectoryModel> inner,
    std::shared_ptr<const MeanFunction> mean, double anchor_time, double sigma)
    : inner_(std::move(inner)),
      mean_(std::move(mean)),
      anchor_time_(anchor_time),
      sigma_(sigma) {}

std::unique_ptr<TrajectoryModel> MeanRotationTrajectory::WithMoreModes(
    double tail_fraction, int most_multiple, std::string* why) const {
  std::unique_ptr<TrajectoryModel> inner =
      inner_->WithMoreModes(tail_fraction, most_multiple, why);
  if (!inner) return nullptr;
  auto model = std::make_unique<MeanRotationTrajectory>(std::move(inner), mean_,
                                                        anchor_time_, sigma_);
  model->delta_ = delta_;
  return model;
}

PoseMap MeanRotationTrajectory::PoseAt(double t) const {
  PoseMap map = inner_->PoseAt(t);
  for (PoseTerm& term : map.terms) ++term.block;
  const Eigen::Vector2d arm =
      mean_->Evaluate(t).head<2>() - mean_->Evaluate(anchor_time_).head<2>();
  const double g[3] = {-arm.y(), arm.x(), 1.0};
  for (int c = 0; c < 3; ++c) {
    if (g[c] != 0.0) {
      map.terms.push_back({0, c,
                           std::make_shared<const Eigen::VectorXd>(
                               Eigen::VectorXd::Constant(1, g[c]))});
    }
  }
  return map;
}

void MeanRotationTrajectory::AddPriorCosts(ceres::Problem* problem, int begin,
                                           int end) {
  if (begin == 0 && end > 0) {
    problem->AddResidualBlock(
        new DiagonalPriorCost(Eigen::VectorXd::Zero(1),
                              Eigen::VectorXd::Constant(1, sigma_)),
        nullptr, &delta_);
  }
  inner_->AddPriorCosts(problem, std::max(begin - 1, 0), std::max(end - 1, 0));
}

void MeanRotationTrajectory::set_mean(
    std::shared_ptr<const MeanFunction> mean) {
  mean_ = mean;
  inner_->set_mean(std::move(mean));
}

double MeanRotationTrajectory::LinearizationError(
    const std::vector<double>& times) const {
  const Eigen::Matrix2d second_order =
      Eigen::Rotation2Dd(delta_).toRotationMatrix() -
      Eigen::Matrix2d::Identity() -
      delta_ * (Eigen::Matrix2d() << 0, -1, 1, 0).finished();
  const Eigen::Vector2d anchor = mean_->Evaluate(anchor_time_).head<2>();
  double largest = 0.0;
  for (const double t : times) {
    largest = std::max(
        largest,
        (second_order * (mean_->Evaluate(t).head<2>() - anchor)).norm());
  }
  return largest;
}

void MeanRotationTrajectory::FoldRotation() {
  set_mean(std::make_shared<RotatedMean>(mean_, anchor_time_, delta_));
  delta_ = 0.0;
}

TrajectoryModel* InnerModel(TrajectoryModel* model) {
  auto* rotation = dynamic_cast<MeanRotationTrajectory*>(model);
  return rotation != nullptr ? rotation->inner() : model;
}

const TrajectoryModel* InnerModel(const TrajectoryModel* model) {
  return InnerModel(const_cast<TrajectoryModel*>(model));
}

}  // namespace rff
