// Variance-component estimation at a MAP: by how much the variance of each
// group of residual rows (a kind of data, a scale of the trajectory prior)
// should change for the residuals to be as large as the model says. With
// whitened rows r_g of group g, J_g their rows of the Jacobian and
// H = J^T J the Gauss-Newton Hessian of the whole problem,
//
//   s_g = r_g^T r_g / (n_g - tr(H^-1 J_g^T J_g)),
//
// the denominator being the group's redundancy: its rows less the share of
// the parameters they determine (Foerstner 1979; Koch 1999, 3.6; for the
// prior's scale it is MacKay's 1992 fixed point gamma). Under a robust loss
// rho a row's r_i^2 becomes rho'(|r_b|^2) r_i^2 / kappa over its block r_b
// of k rows, kappa = E[rho'(v |z|^2) |z|^2] / k for z ~ N(0, I_k) and v its
// group's redundancy over its rows (a fitted row's share of its variance):
// the squares the IRLS weights rho' give, made consistent so that Gaussian
// rows give s_g = 1 at their own sigma. Unscaled (the loss-corrected
// squares) they fall short by kappa (Cauchy at 2 sigma on 3 free rows:
// 0.49), and the rounds ran down by it. Not Huber's Proposal 2 (psi^2 =
// rho'^2 r^2): under a redescending loss its sigma collapses (MRCLAM's
// odometry went to zero).
// Iterating solve and rescale maximises the Laplace evidence over the
// scales. The traces come from Hutchinson's estimator tr(A) = E[z^T A z] with
// seeded Rademacher probes and one solve each: for banded states in the
// time-ordered envelope BANDED_CHOLESKY factorises, J z term by term; else
// through the sparse Jacobian.
#ifndef RFF_CERES_VARIANCE_COMPONENTS_H_
#define RFF_CERES_VARIANCE_COMPONENTS_H_

#include <array>
#include <string>
#include <vector>

#include "Eigen/SparseCore"
#include "ceres/loss_function.h"
#include "ceres/problem.h"
#include "rff_ceres/gauss_newton_system.h"
#include "rff_ceres/slam_problem.h"

namespace rff {

struct VarianceComponent {
  int rows = 0;
  double sum_squares = 0.0;  // r_g^T r_g (robust-weighted).
  double redundancy = 0.0;   // n_g - tr(H^-1 J_g^T J_g).
  // s_g; 1 where the group has no rows or too little redundancy to tell.
  double factor = 1.0;
  bool estimated = false;  // factor is s_g, not the 1 of too few data.
};

struct VarianceComponentOptions {
  int probes = 24;
  unsigned seed = 1;
  // Below this redundancy a group's factor is left at 1: the data say
  // little about it.
  double min_redundancy = 10.0;
};

struct VarianceComponents {
  std::array<VarianceComponent, kNumVarianceGroups> groups;
  // log det H, from the factorisation the traces use.
  double log_det_hessian = 0.0;

  VarianceComponent& operator[](int group) { return groups[group]; }
  const VarianceComponent& operator[](int group) const {
    return groups[group];
  }
  auto begin() const { return groups.begin(); }
  auto end() const { return groups.end(); }
};

// The Laplace approximation of the log evidence at the MAP the components
// were estimated at, up to a constant no scale changes (MacKay 1992):
//
//   log Z = -1/2 sum_g (r_g^T r_g + n_g log s_g) - 1/2 log det H,
//
// s_g the variance factor the rows of group g are whitened with
// (`log_row_scales`, log s_g; 0 where a scale is not on the rows, such as
// feature weights whose kernel variance lives in the features). Its
// stationary points in s_g are the fixed points s_g = r_g^T r_g /
// redundancy_g above, the derivative of log det H giving the trace.
double LaplaceLogEvidence(
    const VarianceComponents& components,
    const std::array<double, kNumVarianceGroups>& log_row_scales);

// What calls on problems of one structure (a learning's rounds) share: the
// sparse factorisation's analysis, and the probes, which depend only on the
// number of columns, the probes and the seed.
struct VarianceComponentCache {
  SparseAnalysis analysis;
  std::vector<signed char> signs;  // Probe after probe, `columns` each.
  Eigen::Index columns = -1;
  int probes = 0;
  unsigned seed = 0;
};

// The factors at the problem's current values (call at a MAP). Fails when
// the problem cannot be evaluated or its Hessian is not positive definite.
// `cache`, when given, keeps what the next call on a problem of the same
// structure can use again.
bool EstimateVarianceComponents(SlamProblem* problem,
                                const VarianceComponentOptions& options,
                                VarianceComponents* components,
                                std::string* error,
                                VarianceComponentCache* cache = nullptr);

// The residuals and Jacobian of `blocks` (in that order, through their
// robust losses) at the problem's current values; the Jacobian's columns are
// the parameter blocks `columns` in that order (empty: the problem's order).
bool Linearize(ceres::Problem* problem,
               const std::vector<ceres::ResidualBlockId>& blocks, double* cost,
               Eigen::VectorXd* residuals,
               Eigen::SparseMatrix<double, Eigen::RowMajor>* jacobian,
               std::string* error, const std::vector<double*>& columns = {});

// kappa above, for a block of k rows under `loss` whose residuals have
// `variance` (in (0, 1]) of a row's: 1 without a loss.
double RobustConsistency(const ceres::LossFunction& loss, int k,
                         double variance = 1.0);

// "range", "bearing", "odometry", "trajectory position", ... for reports.
const char* VarianceGroupName(VarianceGroup group);

}  // namespace rff

#endif  // RFF_CERES_VARIANCE_COMPONENTS_H_
