#include "rff_ceres/trajectory_model.h"

namespace rff {

Eigen::Vector3d TrajectoryModel::Pose(double t) const {
  std::vector<const double*> blocks(num_blocks());
  for (int i = 0; i < num_blocks(); ++i) blocks[i] = block(i);
  return EvaluatePose(PoseAt(t), blocks.data());
}

}  // namespace rff
