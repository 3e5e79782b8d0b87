#include "rff_ceres/heading_winding.h"

#include <algorithm>
#include <cmath>

#include "costs/angle.h"
#include "rff_ceres/batch_solver.h"
#include "rff_ceres/convert/pose_graph.h"
#include "rff_ceres/initialization.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/mean_rotation.h"

namespace rff {

std::vector<HeadingWinding> FindHeadingWindings(const Dataset& dataset,
                                                const TrajectoryModel& model,
                                                double turn_scale) {
  std::vector<const Odometry*> records;
  for (const Odometry& o : dataset.odometry) records.push_back(&o);
  std::stable_sort(
      records.begin(), records.end(),
      [](const Odometry* a, const Odometry* b) { return a->t0 < b->t0; });
  std::vector<HeadingWinding> windings;
  HeadingWinding run;
  double total = 0.0;  // Of the run's excess.
  auto close = [&] {
    if (std::abs(total) > M_PI) {
      run.turns = static_cast<int>(std::lround(total / (2.0 * M_PI)));
      if (run.turns == 0) run.turns = total > 0.0 ? 1 : -1;
      windings.push_back(run);
    }
    run = HeadingWinding();
    total = 0.0;
  };
  for (const Odometry* o : records) {
    // The disagreement the odometry residual sees (wrapped: a record that
    // turns by more than pi is recorded wrapped), in the estimate's units.
    const double d =
        WrapAngle(turn_scale * (model.Pose(o->t1).z() - model.Pose(o->t0).z()) -
                  o->dtheta) /
        turn_scale;
    const bool outlier =
        std::isfinite(d) &&
        std::abs(turn_scale * d) > kWindingSigmas * o->sigma_theta;
    // Consecutive: one sign, the record starting where the run's last ended.
    const bool continues =
        !run.steps.empty() && (d > 0.0) == (total > 0.0) &&
        std::abs(o->t0 - run.t1()) <= 1e-12 * std::max(1.0, std::abs(o->t0));
    if (!outlier || !continues) close();
    if (!outlier) continue;
    run.steps.push_back({o->t0, o->t1, d});
    total += d;
  }
  close();
  return windings;
}

std::string DescribeWinding(const HeadingWinding& winding) {
  return "t = " + FormatNumber(winding.t0()) + " to " +
         FormatNumber(winding.t1()) + ": " + (winding.turns > 0 ? "+" : "") +
         std::to_string(winding.turns) +
         (std::abs(winding.turns) == 1 ? " turn" : " turns");
}

std::vector<TimedPose> UnwindHeadings(
    const std::vector<HeadingWinding>& windings, std::vector<TimedPose> poses) {
  for (const HeadingWinding& w : windings) {
    const double whole = 2.0 * M_PI * w.turns;
    double total = 0.0;
    for (const HeadingWinding::Step& step : w.steps) total += step.excess;
    for (TimedPose& p : poses) {
      if (p.t >= w.t1()) {
        p.theta -= whole;
        continue;
      }
      double taken = 0.0;  // Excess of the run up to p.t.
      for (const HeadingWinding::Step& step : w.steps) {
        if (p.t <= step.t0) break;
        taken += p.t >= step.t1
                     ? step.excess
                     : step.excess * (p.t - step.t0) / (step.t1 - step.t0);
      }
      p.theta -= whole * taken / total;
    }
  }
  return poses;
}

void UnwindAndSolveAgain(const Dataset& dataset, const SlamOptions& options,
                         const ceres::Solver::Options& ceres_options,
                         TrajectoryModel* model,
                         std::map<LandmarkId, Eigen::Vector2d>* landmarks,
                         double initial_extent,
                         std::unique_ptr<SlamProblem>* problem,
                         SlamResult* result) {
  // Nothing to wind against; or a model whose mean a solve turns or
  // refits (an unknown start heading, spline rounds), which going back
  // could not undo: the final check still reports a winding.
  if (!options.problem.use_odometry || options.mean.outer_rounds > 0 ||
      dynamic_cast<const MeanRotationTrajectory*>(model) != nullptr) {
    return;
  }
  const std::vector<HeadingWinding> windings =
      FindHeadingWindings(dataset, *model, result->odometry_calibration[1]);
  if (windings.empty()) return;
  // The model's poses at every time a state, residual or output sits at.
  std::vector<double> times = PoseVertexTimes(dataset);
  for (const double t : OutputTimes(dataset)) times.push_back(t);
  std::sort(times.begin(), times.end());
  std::vector<TimedPose> poses;
  for (std::size_t k = 0; k < times.size(); ++k) {
    if (k > 0 && times[k] == times[k - 1]) continue;
    const Eigen::Vector3d p = model->Pose(times[k]);
    poses.push_back({times[k], p.x(), p.y(), p.z()});
  }
  const std::vector<double> blocks = ModelBlocks(*model);
  const std::map<LandmarkId, Eigen::Vector2d> solved_landmarks = *landmarks;
  const SlamResult solved = *result;
  // A start it cannot fit or a solve that fails from it (diverges) leaves
  // the first solution as it was.
  std::string why;
  const bool solved_again =
      FitModelToPoses(UnwindHeadings(windings, poses), model, &why) &&
      SolveBatch(dataset, options, ceres_options, model, landmarks,
                 initial_extent, problem, result, &why,
                 /*reuse_problem=*/true);
  if (solved_again && result->summary.final_cost < solved.summary.final_cost) {
    for (const HeadingWinding& w : windings) {
      result->heading_windings_unwound.push_back(DescribeWinding(w));
    }
    return;
  }
  // The spin was the better fit: back to it (the iterations counted).
  const int iterations = result->total_iterations;
  SetModelBlocks(blocks, model);
  for (const auto& [id, position] : solved_landmarks) {
    Eigen::Map<Eigen::Vector2d>((*problem)->landmark_block(id)) = position;
  }
  (*problem)->set_range_calibration(solved.range_calibration);
  (*problem)->set_odometry_calibration(solved.odometry_calibration);
  *landmarks = solved_landmarks;
  *result = solved;
  result->total_iterations = iterations;
}

}  // namespace rff
