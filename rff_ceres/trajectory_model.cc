#include "rff_ceres/trajectory_model.h"

#include <algorithm>
#include <map>

namespace rff {

Eigen::Vector3d TrajectoryModel::Pose(double t) const {
  // Only the blocks the map touches: a pose costs its terms, not the run.
  const PoseMap map = PoseAt(t);
  Eigen::Vector3d pose = map.mean;
  for (const PoseTerm& term : map.terms) {
    pose[term.coordinate] += term.phi->dot(Eigen::Map<const Eigen::VectorXd>(
        block(term.block), term.phi->size()));
  }
  return pose;
}

std::vector<double> ModelBlocks(const TrajectoryModel& model) {
  std::vector<double> values;
  for (int b = 0; b < model.num_blocks(); ++b) {
    values.insert(values.end(), model.block(b),
                  model.block(b) + model.block_size(b));
  }
  return values;
}

void SetModelBlocks(const std::vector<double>& values,
                    TrajectoryModel* model) {
  std::size_t offset = 0;
  for (int b = 0; b < model->num_blocks(); ++b) {
    std::copy_n(values.begin() + offset, model->block_size(b),
                model->mutable_block(b));
    offset += model->block_size(b);
  }
}

void ZeroModelBlocks(TrajectoryModel* model) {
  for (int b = 0; b < model->num_blocks(); ++b) {
    std::fill_n(model->mutable_block(b), model->block_size(b), 0.0);
  }
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
