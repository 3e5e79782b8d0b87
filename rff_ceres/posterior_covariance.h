// Posterior uncertainty of the MAP solution (Laplace approximation): the
// covariance of the trajectory blocks after landmark elimination, pushed
// through the affine pose map, Var x(t) = sum_ab Phi_a(t)^T Sigma_ab Phi_b(t),
// and the 2x2 covariance of every landmark. See docs/uncertainty.md.
//
// Sigma = (J^T J)^-1 with J the Jacobian of the whitened residuals at the
// current parameter values. Residuals with a robust loss enter through the
// robustified Jacobian (Ceres's Covariance convention), so down-weighted
// outliers count for less.
#ifndef RFF_CERES_POSTERIOR_COVARIANCE_H_
#define RFF_CERES_POSTERIOR_COVARIANCE_H_

#include <string>
#include <vector>

#include "Eigen/Core"
#include "ceres/types.h"
#include "rff_ceres/slam_problem.h"
#include "rff_ceres/trajectory_model.h"
#include "rff_ceres/types.h"

namespace rff {

// How the covariance was computed, the first that applies in this order.
enum class CovarianceMethod {
  // The inverse on the time-ordered envelope BANDED_CHOLESKY factorises
  // (EnvelopeMatrix::InvertOnEnvelope: the cost of one factorisation), for
  // banded states and for any model whose BANDED_CHOLESKY solve left its H
  // (rff_slam's convergence check takes that H first), where the envelope
  // holds every block needed and H's reciprocal condition is above 1e-14.
  kEnvelope,
  // The Schur form of J^T J (gauss_newton_system.h: linear in the
  // landmarks) where the trajectory has at most kMaxDenseReducedSystem
  // parameters.
  kSchur,
  // The inverse on the pattern of a sparse Cholesky factor of J^T J
  // (selected_inverse.h: linear in the length of a banded run, e.g. WNOA).
  kSelectedInverse,
  // ceres::Covariance with CovarianceOptions::algorithm.
  kCeres,
};

struct CovarianceOptions {
  bool use_envelope = true;
  bool use_schur = true;
  bool use_selected_inverse = true;
  // SPARSE_QR (SuiteSparseQR) scales to long runs but needs a full-rank
  // Jacobian; DENSE_SVD is O(n^3) in the number of parameters.
  ceres::CovarianceAlgorithmType algorithm = ceres::SPARSE_QR;
  // Threads of the column solves (Ceres parallelises over the columns of
  // the inverse it needs).
  int num_threads = 2;
};

// For a solved `problem` over `model`: fills `pose_covariances` (one per time
// of `times`) and the covariance fields of each entry of `landmarks` (matched
// by id to the problem's landmark blocks; has_covariance set). Returns false
// with a message when the information matrix is singular (naming the
// landmarks that the data leave unconstrained) or the result is not finite.
// `method`, when given, says how it was computed.
bool ComputePosteriorCovariance(SlamProblem* problem,
                                const TrajectoryModel& model,
                                const std::vector<double>& times,
                                const CovarianceOptions& options,
                                std::vector<Eigen::Matrix3d>* pose_covariances,
                                std::vector<Landmark>* landmarks,
                                std::string* error,
                                CovarianceMethod* method = nullptr);

// The same with the default CovarianceOptions.
bool ComputePosteriorCovariance(SlamProblem* problem,
                                const TrajectoryModel& model,
                                const std::vector<double>& times,
                                std::vector<Eigen::Matrix3d>* pose_covariances,
                                std::vector<Landmark>* landmarks,
                                std::string* error);

}  // namespace rff

#endif  // RFF_CERES_POSTERIOR_COVARIANCE_H_
