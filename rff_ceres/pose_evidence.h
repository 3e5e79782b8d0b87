// The evidence of the trajectory prior's hyperparameters with the data
// linearised in pose space: the objective of hyperparameter learning.
//
// Linearising every whitened observation residual r about poses x* (one per
// distinct observation time; landmarks held at their estimate),
//
//   log p(data | x) ~ const - 1/2 (x - x*)^T H (x - x*) + g^T (x - x*),
//
// H = J^T J (3 x 3 per time: an observation sees one pose), g = -J^T r. With
// H_i = L_i L_i^T and x ~ GP(m, K), x, y and theta independent, the data are
// the GP regression y_i = L_i^T (x_i - m_i) + e_i, e ~ N(0, I), of
//
//   y_i = L_i^T (x*_i - m_i) + L_i^+ g_i,
//   log p(data | theta) = const - 1/2 y^T M^-1 y - 1/2 log |M|,
//   M = I + L^T K L
//
// (Rasmussen & Williams 2006, eq. 2.30, in whitened observations: stable
// where H is large against K^-1). The exact kernel, not its features:
// the learned values do not depend on the capacity the features get from
// them, and one evaluation is one dense Cholesky of size 3 x (times).
#ifndef RFF_CERES_POSE_EVIDENCE_H_
#define RFF_CERES_POSE_EVIDENCE_H_

#include <map>
#include <string>
#include <vector>

#include "Eigen/Core"
#include "rff_ceres/kernels/kernel.h"
#include "rff_ceres/mean/mean_function.h"
#include "rff_ceres/slam_problem.h"
#include "rff_ceres/types.h"

namespace rff {

// The data of a run as a Gaussian in the poses at its observation times.
struct PoseLikelihood {
  std::vector<double> times;
  std::vector<Eigen::Matrix3d> factors;   // L_i, L_i L_i^T = H_i.
  std::vector<Eigen::Vector3d> whitened;  // y_i.
};

// Linearises the observations of `dataset` (odometry and pose priors are
// not data of the motion here) about the poses of `estimate` (interpolated
// linearly in time, heading unwrapped) and the `landmarks`, with the loss
// and noise scales of `problem_options`, relative to the prior mean `mean`.
// At most `max_times` observation times, the earliest, are kept.
bool LinearizeInPoses(const Dataset& dataset,
                      const std::vector<TimedPose>& estimate,
                      const std::map<LandmarkId, Eigen::Vector2d>& landmarks,
                      const ProblemOptions& problem_options,
                      const MeanFunction& mean, int max_times,
                      PoseLikelihood* likelihood, std::string* error);

// log p(data | theta) up to a constant, for x and y under `position` and
// theta under `heading`, with an unknown constant offset of each (flat
// prior: the restricted likelihood, Rasmussen & Williams 2006, eq. 2.45),
// so that a stationary kernel is judged on the deviations from the data's
// own level, not from the mean's anchor (the first pose). -inf where the
// kernel matrix is not usable. `level`, if given, receives the offset's
// generalised least-squares estimate (zero where the data do not fix it).
double PoseLogEvidence(const PoseLikelihood& likelihood, const Kernel& position,
                       const Kernel& heading, Eigen::Vector3d* level = nullptr);

}  // namespace rff

#endif  // RFF_CERES_POSE_EVIDENCE_H_
