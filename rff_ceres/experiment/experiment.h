// The experiment grid of the paper's evaluation (methods x datasets x
// settings): the simulated Table I and Figure 1, the real and KITTI-scale
// Table II, the Figure 2 trajectory plots and a linear-solver / feature-family
// comparison. RunExperiments runs the selected ones and writes their files;
// this header also brings in the parts it is made of:
//   methods.h      the methods compared and where their options live,
//   grid.h         the datasets and option variants of each experiment,
//   runner.h       one RunRow per run, failures included,
//   aggregation.h  statistics over seeds,
//   tables.h       CSV and Markdown tables,
//   figures.h      SVG figures.
#ifndef RFF_CERES_EXPERIMENT_EXPERIMENT_H_
#define RFF_CERES_EXPERIMENT_EXPERIMENT_H_

#include <ostream>
#include <string>
#include <vector>

#include "rff_ceres/experiment/aggregation.h"
#include "rff_ceres/experiment/figures.h"
#include "rff_ceres/experiment/grid.h"
#include "rff_ceres/experiment/methods.h"
#include "rff_ceres/experiment/runner.h"
#include "rff_ceres/experiment/tables.h"

namespace rff {

inline const std::vector<std::string>& AllExperimentNames() {
  static const std::vector<std::string> names = {"table1", "figure1", "table2",
                                                 "figure2", "solvers"};
  return names;
}

struct ExperimentConfig {
  std::string out_dir;
  bool quick = false;
  std::vector<Method> methods;
  std::vector<std::string> experiments = AllExperimentNames();
  std::string data_dir;    // Holds plaza1.rffd and mrclam6_robot1.rffd.
  std::string shared_dir;  // Optional; "" or missing skips the raw robots.
  std::string figure2_dataset = "plaza1";  // A Table II dataset name.
  std::ostream* progress = nullptr;
};

// What RunExperiments wrote.
struct ExperimentSummary {
  std::vector<RunRow> rows;
  std::vector<std::string> files;  // Paths written, in order.
};

// Runs the selected experiments and writes into out_dir: table1.csv/.md,
// figure1_noise.svg, figure1_landmarks.svg, table2.csv/.md,
// figure2_trajectory.svg, figure2_ape.svg, solvers.csv/.md and runs.csv.
// Fails only on a bad config (unknown experiment or figure-2 dataset, no
// method) or an output that cannot be written; failed runs are rows.
bool RunExperiments(const ExperimentConfig& config,
                    const OptionsCallback& options_callback,
                    ExperimentSummary* summary, std::string* error);

}  // namespace rff

#endif  // RFF_CERES_EXPERIMENT_EXPERIMENT_H_
