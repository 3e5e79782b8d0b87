// What a fixed-lag smoother keeps of the residuals it removes: their
// Gauss-Newton quadratic in the blocks they still move (landmarks,
// calibrations), each taken where those blocks were when it was folded,
//
//   q(x) = sum_i [c_i + g_i^T (x - x_i) + 1/2 (x - x_i)^T J_i^T J_i (x - x_i)],
//   g_i = J_i^T r_i,
//
// with r_i and J_i the residual and Jacobian (weighted by the caller, e.g.
// by a robust loss's rho'), c_i its cost. Summed about the blocks' first
// values x_ref, so that large coordinates do not cancel.
#ifndef RFF_CERES_FOLDED_PRIOR_H_
#define RFF_CERES_FOLDED_PRIOR_H_

#include <cstdint>
#include <map>
#include <memory>
#include <vector>

#include "Eigen/Core"
#include "costs/folded_prior_cost.h"

namespace rff {

class FoldedPrior {
 public:
  // One residual of `rows` entries `residual` and cost `cost`, over
  // `blocks` of `sizes`; `jacobians[j]` row-major (rows x sizes[j]), or
  // nullptr for a block held constant (not part of the quadratic).
  void Add(const std::vector<double*>& blocks,
           const std::vector<int32_t>& sizes,
           const std::vector<double*>& jacobians, const double* residual,
           int rows, double cost);

  int num_folded() const { return num_folded_; }
  // The blocks of the quadratic, in the order MakeCost's cost takes them.
  const std::vector<double*>& blocks() const { return blocks_; }
  // q as a cost over blocks(): its directions of curvature above 1e-12 of
  // the largest (FoldedPriorCost).
  std::unique_ptr<FoldedPriorCost> MakeCost() const;

 private:
  std::vector<double*> blocks_;
  std::vector<int> sizes_;
  std::map<const double*, int> column_;  // Each block's first column.
  Eigen::VectorXd reference_;            // x_ref.
  Eigen::MatrixXd hessian_;              // sum_i J_i^T J_i.
  Eigen::VectorXd linear_;               // b: q = 1/2 d^T H d - b^T d + k,
  double constant_ = 0.0;                // k, with d = x - x_ref.
  int num_folded_ = 0;
};

}  // namespace rff

#endif  // RFF_CERES_FOLDED_PRIOR_H_
