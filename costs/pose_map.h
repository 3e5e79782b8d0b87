// The pose at one time as an affine function of parameter blocks,
//
//   pose(t) = mean(t) + sum_i  e_{c_i} * phi_i(t)^T b_{j_i},
//
// one term per (coordinate c_i, block j_i): the weight-space form of the
// paper's eq. (4), x_k(t) = mu_k(t) + phi_k(t)^T b_k. A cost functor that
// observes a pose evaluates it through this map and turns its gradient with
// respect to the pose into block Jacobians as rank-1 products
// (dr/dx_c) phi^T, never forming a dense 3 x D matrix. The same map serves
// windowed weights (terms in two blocks) and discrete GP states (phi picks
// the state entries).
#ifndef RFF_COSTS_POSE_MAP_H_
#define RFF_COSTS_POSE_MAP_H_

#include <memory>
#include <vector>

#include "Eigen/Core"

namespace rff {

struct PoseTerm {
  int block = 0;       // Index into the cost's parameter blocks.
  int coordinate = 0;  // 0: x, 1: y, 2: theta.
  // Shared between the terms and costs that see the same time (x and y often
  // share one feature vector).
  std::shared_ptr<const Eigen::VectorXd> phi;
};

struct PoseMap {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  std::vector<PoseTerm> terms;
};

// A cost that sees poses only through PoseMaps (PoseCost): row r of the
// Jacobian of term i's block is (dr/dpose)(r, c_i) phi_i^T, so the rows of
// the costs at one time span at most the pose's 3 directions
// (banded_pose_runs.cc).
class PoseMapped {
 public:
  virtual ~PoseMapped() = default;
  virtual int num_pose_maps() const = 0;
  virtual const PoseMap& pose_map(int k) const = 0;
  // Whether a 2-D landmark block follows the pose maps' blocks.
  virtual bool has_landmark() const = 0;
  // The residuals and, unless `dr_dposes` is null, their gradients with
  // respect to pose k (row-major num_residuals x 3 at dr_dposes + 3
  // num_residuals k) and to the landmark (num_residuals x 2, where the cost
  // has one): the Jacobians without their feature vectors.
  virtual bool EvaluateAtPoses(double const* const* parameters,
                               double* residuals, double* dr_dposes,
                               double* dr_dlandmark) const = 0;
};

// pose = mean + sum of phi^T b over the terms.
inline Eigen::Vector3d EvaluatePose(const PoseMap& map,
                                    double const* const* parameters) {
  Eigen::Vector3d pose = map.mean;
  for (const PoseTerm& term : map.terms) {
    const Eigen::Index n = term.phi->size();
    pose[term.coordinate] += term.phi->dot(
        Eigen::Map<const Eigen::VectorXd>(parameters[term.block], n));
  }
  return pose;
}

// Adds d residual / d block = dr_dpose * d pose / d block for every term:
// row r of the block Jacobian gains dr_dpose(r, c) * phi^T. `dr_dpose` is
// num_residuals x 3; Jacobians are row-major as Ceres stores them. Blocks
// that a term touches must be zeroed first (ZeroPoseJacobians).
inline void AccumulatePoseJacobians(const PoseMap& map, const double* dr_dpose,
                                    int num_residuals, double** jacobians) {
  for (const PoseTerm& term : map.terms) {
    double* jacobian = jacobians[term.block];
    if (jacobian == nullptr) continue;
    const Eigen::Index n = term.phi->size();
    for (int r = 0; r < num_residuals; ++r) {
      const double g = dr_dpose[3 * r + term.coordinate];
      if (g == 0.0) continue;
      Eigen::Map<Eigen::VectorXd>(jacobian + r * n, n) += g * *term.phi;
    }
  }
}

// Zeroes the Jacobians of the blocks the terms of `map` touch.
inline void ZeroPoseJacobians(const PoseMap& map, int num_residuals,
                              double** jacobians) {
  for (const PoseTerm& term : map.terms) {
    double* jacobian = jacobians[term.block];
    if (jacobian == nullptr) continue;
    const Eigen::Index n = term.phi->size();
    Eigen::Map<Eigen::VectorXd>(jacobian, num_residuals * n).setZero();
  }
}

// Parameter block sizes implied by the maps (blocks not touched by any map
// must be set by the caller); used to size a cost's parameter list.
inline void ExtendBlockSizes(const PoseMap& map, std::vector<int>* sizes) {
  for (const PoseTerm& term : map.terms) {
    if (term.block >= static_cast<int>(sizes->size())) {
      sizes->resize(term.block + 1, 0);
    }
    (*sizes)[term.block] = static_cast<int>(term.phi->size());
  }
}

}  // namespace rff

#endif  // RFF_COSTS_POSE_MAP_H_
