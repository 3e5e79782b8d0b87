// Dense exact-GP MAP reference for small runs without odometry: the
// estimate that the weight-space (feature) trajectory approximates, computed
// without any approximation of the kernel.
//
// Unknowns: f_d = (f_d(t_1), ..., f_d(t_N)) for d in {x, y, theta} at every
// distinct observation, ground-truth and PRIOR_POSE time, and the landmarks.
// Prior: f_d ~ N(m_d, K_d), K_d,ij = k_d(t_i - t_j) + jitter variance
// delta_ij (x and y share the position kernel). Whitened (Rasmussen &
// Williams 2006, 3.4.3 / A.2), f_d = m_d + L_d w_d with K_d = L_d L_d^T and
// w_d ~ N(0, I), the MAP minimises
//
//   C = 1/2 sum_d |w_d|^2 + 1/2 sum_obs |r_obs(f(t_obs), l)|^2
//       + 1/2 sum_priors |r_prior|^2,
//
// with the range, bearing and range-bearing residuals of costs/ (the same
// functions the RFF problem uses), the PRIOR_POSE and PRIOR_LANDMARK
// residuals. Levenberg-Marquardt on the dense normal equations
// (J^T J + lambda diag(J^T J)) delta = -J^T r, factorised by Eigen's LDLT;
// J^T J = I + L^T H_f L in the whitened block, H_f the per-time 3 x 3
// Gauss-Newton blocks of the measurements. O((3N + 2M)^3) per iteration:
// a few hundred poses take well under a second, 900 a few seconds.
#ifndef RFF_TEST_EXACT_GP_EXACT_GP_MAP_H_
#define RFF_TEST_EXACT_GP_EXACT_GP_MAP_H_

#include <map>
#include <string>
#include <vector>

#include "Eigen/Core"
#include "rff_ceres/kernels/kernel.h"
#include "rff_ceres/metrics.h"
#include "rff_ceres/types.h"

namespace rff {

struct ExactGpOptions {
  KernelOptions position_kernel;  // x and y
  KernelOptions heading_kernel;   // theta
  // Prior mean: "zero" (the model gp_draw samples from) or "constant" (the
  // earliest PRIOR_POSE at every time, as SlamOptions::prior_mean
  // "constant", for comparing with the feature trajectory under one model).
  std::string mean = "zero";
  // Diagonal jitter relative to each kernel's variance (as the simulator's).
  double jitter = 1e-9;
  int max_iterations = 100;
  // Converged when the largest entry of the gradient J^T r (whitened units)
  // is below this.
  double gradient_tolerance = 1e-6;
  // Laplace posterior covariance of every pose (inverse Gauss-Newton
  // Hessian mapped through f = m + L w): O((3N + 2M)^3) more.
  bool compute_covariance = false;
};

struct ExactGpResult {
  // Poses at every unknown time (headings wrapped), landmarks by id.
  std::vector<TimedPose> trajectory;
  std::vector<Landmark> landmarks;
  // With compute_covariance: Cov(x, y, theta) at each trajectory time.
  std::vector<Eigen::Matrix3d> pose_covariances;
  double initial_cost = 0.0;
  double cost = 0.0;               // C at the returned estimate.
  double gradient_max_norm = 0.0;  // max |J^T r| there.
  int iterations = 0;
  bool converged = false;  // gradient_max_norm <= gradient_tolerance.
};

// Starting point from the ground truth: GT poses interpolated at `times`
// (headings unwrapped along time, so that the GP sees a continuous
// heading) and the GT landmarks. A reference solver may start there: the
// MAP it is after is the mode nearest the truth, and the caller checks
// convergence by the gradient norm.
bool InitialGuessFromGroundTruth(const Dataset& dataset,
                                 const std::vector<double>& times,
                                 std::vector<Eigen::Vector3d>* poses,
                                 std::map<LandmarkId, Eigen::Vector2d>* landmarks,
                                 std::string* error);

// The unknown times of `dataset`: every distinct observation, GT_POSE and
// PRIOR_POSE time, ascending.
std::vector<double> ExactGpTimes(const Dataset& dataset);

// Solves from `initial_poses` (one per ExactGpTimes entry) and
// `initial_landmarks` (every observed or prior landmark). Fails on
// odometry (not modelled), a landmark without an initial value, a kernel
// that CreateKernel rejects, or a factorisation that fails.
bool SolveExactGpMap(const Dataset& dataset, const ExactGpOptions& options,
                     const std::vector<Eigen::Vector3d>& initial_poses,
                     const std::map<LandmarkId, Eigen::Vector2d>& initial_landmarks,
                     ExactGpResult* result, std::string* error);

// Mean over the poses of the position NEES e^T Sigma^-1 e (e the 2D
// position error against the GT at the same time, Sigma the xy block of the
// pose covariance); about 2 for a consistent estimate. Needs the result of
// a solve with compute_covariance and GT at every trajectory time.
bool PositionNees(const Dataset& dataset, const ExactGpResult& result,
                  double* nees, std::string* error);

// The kernels of a gp_draw dataset's "# truth:" metadata (ParseGpDrawTruth)
// into `options`. False and `error` where it has none or it does not parse.
bool SetTruthKernels(const Dataset& dataset, ExactGpOptions* options,
                     std::string* error);

// Both together: starts from the ground truth, solves, and evaluates the
// estimate against the ground truth (unaligned, as rff_evaluate by default).
bool SolveExactGpMapFromGroundTruth(const Dataset& dataset,
                                    const ExactGpOptions& options,
                                    ExactGpResult* result,
                                    Evaluation* evaluation, std::string* error);

}  // namespace rff

#endif  // RFF_TEST_EXACT_GP_EXACT_GP_MAP_H_
