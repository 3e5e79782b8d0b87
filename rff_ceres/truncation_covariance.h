// What a feature basis's truncation adds to the posterior covariance.
//
// The truth also moves in the modes the basis leaves out. With Psi(t) the
// next modes of every map (FeatureTrajectory::WithMoreModes) and their
// weights c ~ N(0, I), x(t) = mu(t) + Phi(t) b + Psi(t) c. The MAP of the
// truncated model follows what those modes do to the data; to first order
//
//   theta_hat - theta = H^-1 J^T e + G c,   G = H^-1 J_theta^T J_c,
//
// (theta: weights, landmarks, calibrations; H = J_theta^T J_theta; J_c the
// Jacobian of every residual in c, through its loss), so the error of the
// pose at t, Phi(t) (b_hat - b) - Psi(t) c, has the covariance
//
//   Phi S Phi^T + A(t) A(t)^T,   A(t) = Phi(t) G_b - Psi(t),
//
// and landmark l's error G_l G_l^T more. Where the data pin a pose the
// estimate follows the missed motion (Phi G ~ Psi) and little is added; in
// a gap nothing follows it and its whole prior variance is (the exact GP's
// Laplace covariance, against which
// test/exact_gp/truncation_covariance_test.cc checks it). FITC-like |Psi(t)|^2
// alone over-counts the first and misses what the landmarks absorb.
#ifndef RFF_CERES_TRUNCATION_COVARIANCE_H_
#define RFF_CERES_TRUNCATION_COVARIANCE_H_

#include <set>
#include <string>
#include <vector>

#include "Eigen/Core"
#include "rff_ceres/slam_problem.h"
#include "rff_ceres/trajectory_model.h"
#include "rff_ceres/types.h"

namespace rff {

// The modes the term counts: each map's next ones until the spectral mass
// it misses is under this fraction of what the basis misses (about 1.2 D
// for rbf, 1.8 D for Matern 5/2), at most this multiple of D.
inline constexpr double kTruncationTailFraction = 0.05;
inline constexpr int kTruncationMostModeMultiple = 4;
// Above this many multiply-adds (a dense Cholesky of H, its solves for the
// new modes, the poses through them), or entries of a dense matrix, the term
// is left out and `note` says so.
inline constexpr double kMaxTruncationWork = 4e10;
inline constexpr double kMaxTruncationEntries = 67108864.0;  // 512 MB.

// Adds the truncation term to `pose_covariances` (at `times`) and to every
// landmark's covariance in `landmarks`, for `problem`, solved over `model`
// with `options` from `dataset`, with the new modes of the prior's `scales`
// (position, heading): a scale the data left no variance (learned at zero)
// misses no motion either. `note` says what was added or why nothing was:
// no basis to extend (WNOA states, random features), no scale, too large,
// H singular to rounding, or an extended problem that does not reproduce
// the solved one (the covariance is then the truncated model's alone).
void AddTruncationCovariance(
    const Dataset& dataset, const ProblemOptions& options, SlamProblem* problem,
    const TrajectoryModel& model,
    const std::set<TrajectoryModel::PriorScale>& scales,
    const std::vector<double>& times,
    std::vector<Eigen::Matrix3d>* pose_covariances,
    std::vector<Landmark>* landmarks, std::string* note);

}  // namespace rff

#endif  // RFF_CERES_TRUNCATION_COVARIANCE_H_
