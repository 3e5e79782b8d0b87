// Base of every cost that observes one or more trajectory poses (through
// their PoseMaps) and optionally one landmark. The parameter blocks are the
// blocks of the pose maps, indexed as their terms say, followed by the 2-D
// landmark block when there is one. A derived cost supplies only the residual
// and its gradients with respect to the poses and the landmark; this class
// evaluates the poses and maps the gradients onto the weight blocks.
#ifndef RFF_COSTS_POSE_COST_H_
#define RFF_COSTS_POSE_COST_H_

#include <array>
#include <utility>
#include <vector>

#include "Eigen/Core"
#include "ceres/cost_function.h"
#include "costs/pose_map.h"

namespace rff {

template <int kNumResiduals, int kNumPoses, bool kHasLandmark>
class PoseCost : public ceres::CostFunction, public PoseMapped {
 public:
  using PoseGradient = Eigen::Matrix<double, kNumResiduals, 3, Eigen::RowMajor>;
  using LandmarkGradient =
      Eigen::Matrix<double, kNumResiduals, 2, Eigen::RowMajor>;
  using Residuals = Eigen::Matrix<double, kNumResiduals, 1>;

  explicit PoseCost(std::array<PoseMap, kNumPoses> maps)
      : maps_(std::move(maps)) {
    set_num_residuals(kNumResiduals);
    std::vector<int> sizes;
    for (const PoseMap& map : maps_) ExtendBlockSizes(map, &sizes);
    num_pose_blocks_ = static_cast<int>(sizes.size());
    if (kHasLandmark) sizes.push_back(2);
    *mutable_parameter_block_sizes() = sizes;
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const final {
    if (jacobians == nullptr) {
      return ResidualAt(parameters, residuals, nullptr, nullptr);
    }
    std::array<PoseGradient, kNumPoses> dr_dposes;
    LandmarkGradient dr_dlandmark;
    if (!ResidualAt(parameters, residuals, &dr_dposes, &dr_dlandmark)) {
      return false;
    }
    for (const PoseMap& map : maps_) {
      ZeroPoseJacobians(map, kNumResiduals, jacobians);
    }
    for (int k = 0; k < kNumPoses; ++k) {
      AccumulatePoseJacobians(maps_[k], dr_dposes[k].data(), kNumResiduals,
                              jacobians);
    }
    if (kHasLandmark && jacobians[num_pose_blocks_] != nullptr) {
      Eigen::Map<LandmarkGradient> jacobian(jacobians[num_pose_blocks_]);
      jacobian = dr_dlandmark;
    }
    return true;
  }

  bool EvaluateAtPoses(double const* const* parameters, double* residuals,
                       double* dr_dposes, double* dr_dlandmark) const final {
    if (dr_dposes == nullptr) {
      return ResidualAt(parameters, residuals, nullptr, nullptr);
    }
    std::array<PoseGradient, kNumPoses> pose_gradients;
    LandmarkGradient landmark_gradient;
    if (!ResidualAt(parameters, residuals, &pose_gradients,
                    &landmark_gradient)) {
      return false;
    }
    for (int k = 0; k < kNumPoses; ++k) {
      Eigen::Map<PoseGradient> out(dr_dposes + 3 * kNumResiduals * k);
      out = pose_gradients[k];
    }
    if (kHasLandmark && dr_dlandmark != nullptr) {
      Eigen::Map<LandmarkGradient> out(dr_dlandmark);
      out = landmark_gradient;
    }
    return true;
  }

  bool has_landmark() const final { return kHasLandmark; }
  int num_pose_maps() const final { return kNumPoses; }
  const PoseMap& pose_map(int k) const final { return maps_[k]; }

 protected:
  // Fills the residual and, when the gradient pointers are non-null, its
  // derivatives with respect to each pose (x, y, theta) and the landmark.
  // Returns false where the residual is undefined.
  virtual bool Residual(const std::array<Eigen::Vector3d, kNumPoses>& poses,
                        const Eigen::Vector2d& landmark,
                        Eigen::Map<Residuals>* residual,
                        std::array<PoseGradient, kNumPoses>* dr_dposes,
                        LandmarkGradient* dr_dlandmark) const = 0;

 private:
  // The poses and landmark at the parameters, then Residual.
  bool ResidualAt(double const* const* parameters, double* residuals,
                  std::array<PoseGradient, kNumPoses>* dr_dposes,
                  LandmarkGradient* dr_dlandmark) const {
    std::array<Eigen::Vector3d, kNumPoses> poses;
    for (int k = 0; k < kNumPoses; ++k) {
      poses[k] = EvaluatePose(maps_[k], parameters);
    }
    const Eigen::Vector2d landmark =
        kHasLandmark ? Eigen::Vector2d(parameters[num_pose_blocks_][0],
                                       parameters[num_pose_blocks_][1])
                     : Eigen::Vector2d::Zero();
    Eigen::Map<Residuals> r(residuals);
    return Residual(poses, landmark, &r, dr_dposes, dr_dlandmark);
  }

  std::array<PoseMap, kNumPoses> maps_;
  int num_pose_blocks_ = 0;
};

}  // namespace rff

#endif  // RFF_COSTS_POSE_COST_H_
