#include "rff_ceres/trajectory_model.h"

#include <map>

namespace rff {

Eigen::Vector3d TrajectoryModel::Pose(double t) const {
  std::vector<const double*> blocks(num_blocks());
  for (int i = 0; i < num_blocks(); ++i) blocks[i] = block(i);
  return EvaluatePose(PoseAt(t), blocks.data());
}

std::vector<double*> BindPoseMaps(TrajectoryModel* model,
                                  const std::vector<PoseMap*>& maps) {
  std::vector<double*> blocks;
  std::map<int, int> local;  // Model block id -> index in `blocks`.
  for (PoseMap* map : maps) {
    for (PoseTerm& term : map->terms) {
      auto [it, inserted] =
          local.emplace(term.block, static_cast<int>(blocks.size()));
      if (inserted) blocks.push_back(model->mutable_block(term.block));
      term.block = it->second;
    }
  }
  return blocks;
}

}  // namespace rff
