// A trajectory model whose prior mean may turn about its anchor. A mean
// integrated from odometry inherits the error of its start heading, and a
// stationary prior on the deviation cannot undo a rotation of the whole
// path: its deviation (R(delta) - I)(m(t) - a) carries every turn of the run.
// One more block, the rotation delta ~ N(0, sigma^2) with sigma the start
// heading's prior uncertainty, adds the first-order effect of that rotation,
//
//   pose(t) = inner(t) + delta * g(t),   g(t) = (-(m_y(t) - a_y),
//                                                  m_x(t) - a_x, 1),
//
// a = m(t_anchor): the linearised rotation of the mean about the anchor, a
// kernel component built from the inputs alone. FoldRotation applies delta
// to the mean exactly and sets it back to zero.
#ifndef RFF_CERES_MEAN_ROTATION_H_
#define RFF_CERES_MEAN_ROTATION_H_

#include <memory>
#include <vector>

#include "rff_ceres/trajectory_model.h"

namespace rff {

// The mean rotated by `angle` about its value at `anchor_time`.
class RotatedMean : public MeanFunction {
 public:
  RotatedMean(std::shared_ptr<const MeanFunction> mean, double anchor_time,
              double angle);
  Eigen::Vector3d Evaluate(double t) const override;

 private:
  std::shared_ptr<const MeanFunction> mean_;
  Eigen::Vector2d anchor_;
  Eigen::Matrix2d rotation_;
  double angle_;
};

class MeanRotationTrajectory : public TrajectoryModel {
 public:
  // Block 0 is delta; block b + 1 is the inner model's block b. `mean` is
  // the inner model's mean.
  MeanRotationTrajectory(std::unique_ptr<TrajectoryModel> inner,
                         std::shared_ptr<const MeanFunction> mean,
                         double anchor_time, double sigma);

  int num_blocks() const override { return inner_->num_blocks() + 1; }
  int block_size(int block) const override {
    return block == 0 ? 1 : inner_->block_size(block - 1);
  }
  double* mutable_block(int block) override {
    return block == 0 ? &delta_ : inner_->mutable_block(block - 1);
  }
  bool HasDenseReducedSystem() const override {
    return inner_->HasDenseReducedSystem();
  }
  bool IsSharedBlock(int block) const override {
    return block == 0 || inner_->IsSharedBlock(block - 1);
  }
  PoseMap PoseAt(double t) const override;
  using TrajectoryModel::AddPriorCosts;
  void AddPriorCosts(ceres::Problem* problem, int begin, int end) override;
  const MeanFunction& mean() const override { return inner_->mean(); }
  // The rotation's prior is fixed (the start heading's uncertainty).
  std::vector<PriorScale> PriorRowScales(const std::vector<double*>& blocks,
                                         int num_rows) const override {
    if (blocks.front() == &delta_) {
      return std::vector<PriorScale>(num_rows, PriorScale::kNone);
    }
    return inner_->PriorRowScales(blocks, num_rows);
  }
  bool PriorScalesWhitenRows() const override {
    return inner_->PriorScalesWhitenRows();
  }
  void set_mean(std::shared_ptr<const MeanFunction> mean) override;
  // The rotation's prior has no scale; the inner model's costs follow it.
  void UpdatePriorCosts(
      const std::vector<ceres::CostFunction*>& costs) const override {
    inner_->UpdatePriorCosts(costs);
  }

  // The inner model's, turned about the same anchor by the same delta.
  std::unique_ptr<TrajectoryModel> WithMoreModes(
      double tail_fraction, int most_multiple, std::string* why) const override;
  TrajectoryModel* inner() { return inner_.get(); }
  const TrajectoryModel* inner() const { return inner_.get(); }
  double delta() const { return delta_; }
  double sigma() const { return sigma_; }
  double anchor_time() const { return anchor_time_; }

  // Largest distance over `times` between the exact rotation of the mean by
  // delta and its first-order form: what FoldRotation would change.
  double LinearizationError(const std::vector<double>& times) const;
  // Replaces the mean by its exact rotation by delta and sets delta to zero.
  void FoldRotation();

 private:
  std::unique_ptr<TrajectoryModel> inner_;
  std::shared_ptr<const MeanFunction> mean_;
  double anchor_time_;
  double sigma_;
  double delta_ = 0.0;
};

// The model itself, or the inner model of a MeanRotationTrajectory.
TrajectoryModel* InnerModel(TrajectoryModel* model);
const TrajectoryModel* InnerModel(const TrajectoryModel* model);

}  // namespace rff

#endif  // RFF_CERES_MEAN_ROTATION_H_
