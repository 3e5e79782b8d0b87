// The datasets and option variants of the experiment grid (methods x
// datasets x settings), full and quick presets: the simulated Table I and
// Figure 1 sweeps, the real and KITTI-scale Table II, and the linear-solver /
// feature-family comparison.
#ifndef RFF_CERES_EXPERIMENT_GRID_H_
#define RFF_CERES_EXPERIMENT_GRID_H_

#include <functional>
#include <string>
#include <vector>

#include "rff_ceres/slam_solver.h"
#include "rff_ceres/types.h"

namespace rff {

// Dataset families, each with its own config: synthetic_range,
// synthetic_bearing, synthetic_range_bearing, plaza, mrclam, kitti_bearing.
// The family of a simulated paper set of `kind` (range, bearing,
// range_bearing).
std::string SyntheticFamily(const std::string& kind);

// One dataset of the grid with the settings it was made with.
struct DatasetSpec {
  std::string name;    // Unique within an experiment, e.g. "s3_rb_L50_x1".
  std::string family;  // Selects the method's config.
  std::string kind;    // range, bearing or range_bearing ("" if mixed).
  int landmarks = 0;   // Number of landmarks (0: not a setting).
  // Observation noise: a multiplier of the paper's sigmas (noise_unit "x")
  // or the bearing sigma in degrees ("deg"); 0: not a setting.
  double noise = 0.0;
  std::string noise_unit;
  int seed = -1;  // Simulation seed (-1: not simulated).
  // Makes (simulates, reads or converts) the dataset; must give ground truth.
  std::function<bool(Dataset*, std::string*)> make;
};

// "x0.5", "3 deg", or "" when the spec has no noise setting.
std::string NoiseLabel(double noise, const std::string& unit);

// Options applied on top of a method's options (the solver comparison).
// `apply` returns false when the variant does not apply to those options
// (e.g. a feature family for a prior without features): no run, no row.
struct OptionsVariant {
  std::string name;
  std::function<bool(SlamOptions*)> apply;
};

struct Experiment {
  std::string name;  // table1, figure1, table2, figure2, solvers.
  std::vector<DatasetSpec> datasets;
  std::vector<OptionsVariant> variants;  // Empty: the method's options only.
  bool keep_solutions = false;  // Fill RunRow::trajectory and ::landmarks.
};

// The grids. `quick` is the preset that runs in a few minutes.
std::vector<DatasetSpec> Table1Datasets(bool quick);
std::vector<DatasetSpec> Figure1Datasets(bool quick);
// The number of landmarks at which Figure 1 sweeps the noise.
int Figure1NoiseLandmarks(bool quick);
// Plaza and MRCLAM robot 1 from data_dir, MRCLAM robots 2-5 converted from
// shared_dir/data/mrclam6 when present (not in quick), and the KITTI-scale
// bearing-only set with bearing sigma 1, 3 and 5 deg (shorter in quick).
std::vector<DatasetSpec> Table2Datasets(bool quick, const std::string& data_dir,
                                        const std::string& shared_dir);
// The simulated set of the solver comparison and Plaza.
std::vector<DatasetSpec> SolverDatasets(bool quick,
                                        const std::string& data_dir);
// Linear solver x feature family x D.
std::vector<OptionsVariant> SolverVariants(bool quick);

}  // namespace rff

#endif  // RFF_CERES_EXPERIMENT_GRID_H_
