// The experiment's SVG figures: Figure 1 (median APE-trans over seeds
// against noise and against the number of landmarks) and Figure 2 (the
// estimates of one dataset over its ground truth, and their error in time).
#ifndef RFF_CERES_EXPERIMENT_FIGURES_H_
#define RFF_CERES_EXPERIMENT_FIGURES_H_

#include <string>
#include <vector>

#include "rff_ceres/experiment/grid.h"
#include "rff_ceres/experiment/methods.h"
#include "rff_ceres/experiment/runner.h"
#include "rff_ceres/plot/svg_plot.h"
#include "rff_ceres/types.h"

namespace rff {

// A plot and the file name it is written to in the output directory.
struct NamedPlot {
  std::string file_name;
  Plot plot;
};

// Figure 1 from the runs of the figure1 grid: figure1_noise.svg and
// figure1_landmarks.svg, one curve per (method, kind).
std::vector<NamedPlot> Figure1Plots(const std::vector<RunRow>& rows,
                                    const std::vector<Method>& methods,
                                    bool quick);

// Figure 2 of `spec` (made again for its ground truth and dead reckoning)
// from its runs kept with solutions: figure2_trajectory.svg, the map, and
// figure2_ape.svg, the translation error along the trajectory.
std::vector<NamedPlot> Figure2Plots(const DatasetSpec& spec,
                                    const std::vector<RunRow>& rows);

// Per-time translation errors |p_true(t) - p_est(t)| at the ground-truth
// times (the estimate interpolated, not aligned), the terms of APE-trans.
bool TranslationErrors(const std::vector<TimedPose>& ground_truth,
                       const std::vector<TimedPose>& estimate,
                       std::vector<double>* errors, std::string* error);

}  // namespace rff

#endif  // RFF_CERES_EXPERIMENT_FIGURES_H_
