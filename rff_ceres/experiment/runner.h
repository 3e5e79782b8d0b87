// Running the grid: every (dataset, method, variant) becomes one RunRow with
// its errors against ground truth, and a run that fails is a row that says
// why, so that the grid goes on. The library never reads flags: where a
// method's SlamOptions come from is the caller's OptionsCallback.
#ifndef RFF_CERES_EXPERIMENT_RUNNER_H_
#define RFF_CERES_EXPERIMENT_RUNNER_H_

#include <functional>
#include <limits>
#include <ostream>
#include <string>
#include <vector>

#include "rff_ceres/experiment/grid.h"
#include "rff_ceres/experiment/methods.h"
#include "rff_ceres/slam_solver.h"
#include "rff_ceres/types.h"

namespace rff {

// Fills the SlamOptions of `method` for a dataset of `family`; false (with
// a message) when the method cannot run on it, e.g. its config is missing.
using OptionsCallback =
    std::function<bool(const std::string& method, const std::string& family,
                       SlamOptions* options, std::string* error)>;

// One run: its settings, the solver it used, and its errors against ground
// truth. Numbers that were not computed are NaN (written as "" / "-").
struct RunRow {
  static constexpr double kNone = std::numeric_limits<double>::quiet_NaN();

  std::string experiment;
  std::string method;
  std::string dataset;
  std::string family;
  std::string kind;
  int landmarks = 0;
  double noise = 0.0;
  std::string noise_unit;
  int seed = -1;
  std::string variant;
  std::string linear_solver;
  std::string features;
  int num_features = 0;

  std::string status = "ok";                      // Or "failed: <why>".
  double ape_translation = kNone;                 // RMS, m.
  double ape_rotation_deg = kNone;                // RMS, deg.
  double rpe_translation = kNone;                 // RMS, m.
  double rpe_rotation_deg = kNone;                // RMS, deg.
  double landmark_rms = kNone;                    // m.
  double dead_reckoning_ape_translation = kNone;  // m, for reference.
  int iterations = 0;
  double final_cost = kNone;
  double solve_seconds = kNone;

  // With Experiment::keep_solutions, on success.
  std::vector<TimedPose> trajectory;
  std::vector<Landmark> estimated_landmarks;

  bool ok() const { return status == "ok"; }
};

// Counts runs and prints one line per run ("[12/240] rff ...: APE 0.41 m,
// 0.12 s") to `output` when it is not null.
class Progress {
 public:
  Progress(std::ostream* output, int total) : output_(output), total_(total) {}
  void Report(const RunRow& row);
  // A run of the total that turned out not to apply.
  void Skip() { --total_; }
  int done() const { return done_; }
  int total() const { return total_; }

 private:
  std::ostream* output_;
  int total_;
  int done_ = 0;
};

// Number of runs RunExperiment makes (at most, with variants).
int CountRuns(const Experiment& experiment, int num_methods);

// Runs every (dataset, method, variant) of `experiment`. Each dataset is
// made and each method's options asked for once per dataset; a dataset that
// cannot be made or a method without options gives one row with status
// "failed: ..." (for all its variants), a failed solve or evaluation one
// such row per variant, and the grid goes on.
std::vector<RunRow> RunExperiment(const Experiment& experiment,
                                  const std::vector<Method>& methods,
                                  const OptionsCallback& options_callback,
                                  Progress* progress);

// APE-trans of dead reckoning against the ground truth; NaN when the
// dataset has no odometry or it does not cover every ground-truth time.
// `poses` (if not null) gets the dead-reckoned trajectory on success.
double DeadReckoningApe(const Dataset& dataset, std::vector<TimedPose>* poses);

}  // namespace rff

#endif  // RFF_CERES_EXPERIMENT_RUNNER_H_
