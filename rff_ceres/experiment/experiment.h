// The experiment grid of the paper's evaluation (methods x datasets x
// settings): the simulated Table I and Figure 1, the real and KITTI-scale
// Table II, the Figure 2 trajectory plots and a linear-solver / feature-family
// comparison. Every run becomes one RunRow; the writers turn rows into CSV,
// Markdown tables and SVG plots. The library never reads flags: where a
// method's SlamOptions come from is the caller's OptionsCallback.
#ifndef RFF_CERES_EXPERIMENT_EXPERIMENT_H_
#define RFF_CERES_EXPERIMENT_EXPERIMENT_H_

#include <functional>
#include <limits>
#include <ostream>
#include <string>
#include <vector>

#include "rff_ceres/slam_solver.h"
#include "rff_ceres/types.h"

namespace rff {

// A solver configuration under comparison. `flagfile_pattern` tells the app
// where the method's options live: "{configs}" and "{family}" in it are
// replaced by the configs directory and the dataset family.
struct Method {
  std::string name;
  std::string flagfile_pattern;
};

// Parses a comma list of methods: "rff" ({configs}/{family}.flags), "wnoa"
// ({configs}/{family}_wnoa.flags) or "name=pattern" for any other. Fails on
// an empty list, an empty name or pattern, an unknown bare name or a name
// given twice.
bool ParseMethods(const std::string& list, std::vector<Method>* methods,
                  std::string* error);

// The flagfile of `method` for `family`: its pattern with {configs} and
// {family} substituted.
std::string MethodFlagfile(const Method& method, const std::string& family,
                           const std::string& configs_dir);

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

// Per-time translation errors |p_true(t) - p_est(t)| at the ground-truth
// times (the estimate interpolated, not aligned), the terms of APE-trans.
bool TranslationErrors(const std::vector<TimedPose>& ground_truth,
                       const std::vector<TimedPose>& estimate,
                       std::vector<double>* errors, std::string* error);

// Median and mean of the finite values (NaN for none).
struct Spread {
  int count = 0;
  double median = RunRow::kNone;
  double mean = RunRow::kNone;
};
Spread SpreadOf(const std::vector<double>& values);

// Runs of one (method, family, landmarks, noise, variant) over seeds.
struct SeedAggregate {
  std::string method;
  std::string family;
  std::string kind;
  int landmarks = 0;
  double noise = 0.0;
  std::string noise_unit;
  std::string variant;
  int runs = 0;
  int failed = 0;
  Spread ape_translation;  // Over the successful runs.
  Spread ape_rotation_deg;
  Spread rpe_translation;
  Spread rpe_rotation_deg;
  Spread landmark_rms;
  Spread dead_reckoning_ape_translation;
  Spread solve_seconds;
};

// Groups `rows` by (method, family, landmarks, noise, variant), in order of
// first appearance.
std::vector<SeedAggregate> AggregateOverSeeds(const std::vector<RunRow>& rows);

// A table of text cells, written as CSV or as Markdown.
struct Table {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
};

// RFC 4180: a field with a comma, quote, CR or LF is quoted, quotes doubled.
std::string CsvField(const std::string& field);
std::string ToCsv(const Table& table);
// A GitHub Markdown table; '|' in cells is escaped.
std::string ToMarkdown(const Table& table);

// Number for Markdown: 3 significant digits (fixed notation, 0.000412 to
// 999; integers from 1000 up), "-" for NaN.
std::string FormatSignificant(double value);
// Number for CSV: the shortest exact form, "" for NaN.
std::string FormatCsvNumber(double value);

// Every column of every row (runs.csv).
Table RunsCsvTable(const std::vector<RunRow>& rows);
// Table I: seed aggregates; CSV with median and mean of every metric, the
// Markdown with "median / mean" cells.
Table Table1CsvTable(const std::vector<SeedAggregate>& aggregates);
Table Table1MarkdownTable(const std::vector<SeedAggregate>& aggregates);
// Table II: one row per run.
Table Table2CsvTable(const std::vector<RunRow>& rows);
Table Table2MarkdownTable(const std::vector<RunRow>& rows);
// Solver comparison: one row per run.
Table SolversCsvTable(const std::vector<RunRow>& rows);
Table SolversMarkdownTable(const std::vector<RunRow>& rows);

// The grids. `quick` is the preset that runs in a few minutes.
std::vector<DatasetSpec> Table1Datasets(bool quick);
std::vector<DatasetSpec> Figure1Datasets(bool quick);
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
