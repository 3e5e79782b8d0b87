// Whole extra turns of the estimated heading against the odometry. Every
// residual sees the heading wrapped, so a stretch where the estimate spins
// a full turn more than the odometry says costs only the odometry's rows
// there, each far beyond its sigma, which a robust loss caps: a local
// minimum no residual's size calls out (MRCLAM robot 3 from dead reckoning
// 120 degrees off: three stretches of 3 s, headings up to 177 degrees off
// while the positions stay within 0.1 m). Unwound after the learning, not
// before: a winding the rounds would remove is left to them. Over ODOM
// record k, with the estimate's heading theta(t) unwrapped,
//
//   d_k = wrap(theta(t1_k) - theta(t0_k) - dtheta_k),
//
// and a winding is a run of consecutive records whose d_k all exceed
// kWindingSigmas of their stated sigma with one sign and add up to more
// than half a turn.
#ifndef RFF_CERES_HEADING_WINDING_H_
#define RFF_CERES_HEADING_WINDING_H_

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "ceres/solver.h"
#include "rff_ceres/slam_problem.h"
#include "rff_ceres/slam_solver.h"
#include "rff_ceres/trajectory_model.h"
#include "rff_ceres/types.h"

namespace rff {

inline constexpr double kWindingSigmas = 3.0;

struct HeadingWinding {
  // One ODOM record of the run: its span and its d_k.
  struct Step {
    double t0, t1, excess;
  };
  std::vector<Step> steps;  // In time order, each starting where one ended.
  int turns = 0;            // Extra turns of the estimate, signed.
  double t0() const { return steps.front().t0; }
  double t1() const { return steps.back().t1; }
};

// The windings of `model`'s heading against `dataset`'s ODOM records, in
// time order, with the records' turns `turn_scale` times the true ones
// (an estimated odometry calibration; 1 without). d_k is taken wrapped, as
// the odometry residual sees it: a record that turns by more than pi is
// recorded wrapped, and no turn hides in it.
std::vector<HeadingWinding> FindHeadingWindings(const Dataset& dataset,
                                                const TrajectoryModel& model,
                                                double turn_scale = 1.0);

// "t = T0 to T1: +N turn(s)", for reports.
std::string DescribeWinding(const HeadingWinding& winding);

// `poses` (sorted by time) with the windings taken out: inside a run the
// heading loses the excess of the records so far (linear within a record),
// after it the run's whole turns, which no residual sees.
std::vector<TimedPose> UnwindHeadings(
    const std::vector<HeadingWinding>& windings, std::vector<TimedPose> poses);

// After the solve of `model` (RunSlam's last, the learning's included)
// that used the odometry, of a model whose mean the solve neither turns
// nor refits (MeanRotationTrajectory, spline rounds): where its heading
// winds against the odometry, starts again from the unwound poses and
// keeps that solve where it ends at a lower cost (else the values, the
// calibrations and the result as they were: a start it cannot fit or a
// solve that fails from it changes nothing either). result->
// heading_windings_unwound records what was taken out.
void UnwindAndSolveAgain(const Dataset& dataset, const SlamOptions& options,
                         const ceres::Solver::Options& ceres_options,
                         TrajectoryModel* model,
                         std::map<LandmarkId, Eigen::Vector2d>* landmarks,
                         double initial_extent,
                         std::unique_ptr<SlamProblem>* problem,
                         SlamResult* result);

}  // namespace rff

#endif  // RFF_CERES_HEADING_WINDING_H_
