// The solves after the first batch MAP that settle what the options left
// open: "auto" losses judged on the residuals, and the scales of the prior
// and of the data's sigmas learned by variance components.
#ifndef RFF_CERES_SCALE_LEARNING_H_
#define RFF_CERES_SCALE_LEARNING_H_

#include <array>
#include <map>
#include <memory>
#include <string>

#include "Eigen/Core"
#include "ceres/solver.h"
#include "rff_ceres/mean/mean_function.h"
#include "rff_ceres/slam_problem.h"
#include "rff_ceres/slam_solver.h"
#include "rff_ceres/trajectory_model.h"
#include "rff_ceres/types.h"

namespace rff {

// The robust solve that judges "auto" losses stops at kPlacingTolerance: the
// judgement compares residuals with an outlier level of several sigma; the
// solve after it finishes.
ceres::Solver::Options JudgingOptions(const ProblemOptions& options,
                                      ceres::Solver::Options ceres_options);

// Settles "auto" losses (slam_problem.h) after the robust solve that judges
// them (JudgingOptions): a loss whose residual kinds all stay within the
// outlier level of their count becomes "none", the rest "cauchy". Returns
// whether any was "auto", so that the judging solve is to be finished.
bool SettleAutoLosses(SlamProblem* problem, ProblemOptions* options);

// log s_g of every group's rows as a problem over `model` whitens them at
// these scales (LaplaceLogEvidence): the prior's scales where they divide
// its rows, the squares of the noise factors, 0 for the fixed rows.
std::array<double, kNumVarianceGroups> LogRowScales(
    const TrajectoryModel& model, double position_scale, double heading_scale,
    const NoiseScales& noise);

// The information the data carry on the size of the scene about the start
// (the earliest pose prior, else the map priors' weighted centroid), per
// unit of s^2 where every position moves to start + (1 + s)(p - start): a
// range r moves by s r, an odometry step d by s d, a map or pose prior at
// offset o from the start by s o, a bearing not at all. So
//   I = sum r^2 / sigma_r^2 + sum (dx^2 / sigma_x^2 + dy^2 / sigma_y^2)
//       + sum |o|^2 / sigma^2
// over ranges, the odometry the problem uses, and map and pose priors, the
// sigmas times the options' noise factors. A sensor whose scale is estimated
// under a prior of sigma_s counts I / (1 + I sigma_s^2): its scale absorbs
// the scaling but for that prior.
double ScaleInformation(const Dataset& dataset, const ProblemOptions& options);

// Learns the scales of the trajectory prior (WNOA Q_c, RFF kernel
// variances) of x, y and theta and, where `noise`, the factors on the sigmas
// of range, bearing and odometry: after the first MAP, each round rescales
// the variances by their variance-component factors (variance_components.h,
// the fixed point of the Laplace evidence) and solves again from the current
// estimate, until every factor is within kScaleTolerance of one. The data's
// stated sigmas are often a guess: MRCLAM's bearings and odometry are
// several times tighter than stated (docs/heldout.md). `loose`: the problem
// was solved at kPlacingTolerance only. A correction to the mean whose
// factor is under 0.01 (its variance at zero, as far as the data tell)
// takes one tenfold step down and is learned no further. Where the data
// hold the trajectory's size too loosely for learned prior scales
// (ScaleInformation against the prior's pull: each round at face value,
// and where the rounds end at the noise levels learned), the prior's
// scales go back to the given ones and the rounds learn only the noise
// factors.
bool LearnScales(const Dataset& dataset,
                 std::shared_ptr<const MeanFunction> mean,
                 const ceres::Solver::Options& ceres_options,
                 double initial_extent, bool noise, bool loose,
                 SlamOptions* settled, std::unique_ptr<TrajectoryModel>* model,
                 std::map<LandmarkId, Eigen::Vector2d>* landmarks,
                 std::unique_ptr<SlamProblem>* problem, SlamResult* result,
                 std::string* error);

}  // namespace rff

#endif  // RFF_CERES_SCALE_LEARNING_H_
