#include "rff_ceres/experiment/experiment.h"

#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "rff_ceres/simulate.h"
#include "test/test_files.h"

namespace rff {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::Not;
using ::testing::StartsWith;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream stream(text);
  for (std::string line; std::getline(stream, line);) lines.push_back(line);
  return lines;
}

// Splits one CSV line without quoted commas (the test data has none there).
std::vector<std::string> Cells(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  std::istringstream stream(line + ",");
  while (std::getline(stream, cell, ',')) cells.push_back(cell);
  return cells;
}

TEST(ParseMethodsTest, BuiltInAndPatternMethods) {
  std::vector<Method> methods;
  std::string error;
  ASSERT_TRUE(
      ParseMethods("rff, wnoa,d12=cfg/{family}_d12.flags", &methods, &error))
      << error;
  ASSERT_EQ(methods.size(), 3u);
  EXPECT_EQ(methods[0].name, "rff");
  EXPECT_EQ(methods[0].flagfile_pattern, "{configs}/{family}.flags");
  EXPECT_EQ(methods[1].flagfile_pattern, "{configs}/{family}_wnoa.flags");
  EXPECT_EQ(methods[2].name, "d12");
  EXPECT_EQ(methods[2].flagfile_pattern, "cfg/{family}_d12.flags");
}

TEST(ParseMethodsTest, RejectsUnknownEmptyAndDuplicateMethods) {
  std::vector<Method> methods;
  std::string error;
  EXPECT_FALSE(ParseMethods("rff,gpslam", &methods, &error));
  EXPECT_EQ(error,
            "--methods=rff,gpslam: unknown method gpslam; allowed a comma "
            "list of rff, wnoa or name=flagfile-pattern (e.g. "
            "mine=configs/{family}_mine.flags)");
  EXPECT_FALSE(ParseMethods("rff,rff", &methods, &error));
  EXPECT_EQ(error,
            "--methods=rff,rff: method rff is given twice; allowed each "
            "method once");
  EXPECT_FALSE(ParseMethods("=x.flags", &methods, &error));
  EXPECT_EQ(error,
            "--methods==x.flags: a method has an empty name; allowed a comma "
            "list of rff, wnoa or name=flagfile-pattern (e.g. "
            "mine=configs/{family}_mine.flags)");
  EXPECT_FALSE(ParseMethods("a=", &methods, &error));
  EXPECT_EQ(error,
            "--methods=a=: method a has an empty flagfile pattern; allowed a "
            "comma list of rff, wnoa or name=flagfile-pattern (e.g. "
            "mine=configs/{family}_mine.flags)");
  EXPECT_FALSE(ParseMethods("", &methods, &error));
  EXPECT_EQ(error,
            "--methods=: no method; allowed a comma list of rff, wnoa or "
            "name=flagfile-pattern (e.g. mine=configs/{family}_mine.flags)");
}

TEST(MethodFlagfileTest, SubstitutesTheConfigsDirAndTheFamily) {
  const std::string configs = std::string(RFF_SOURCE_DIR) + "/configs";
  const Method rff{"rff", "{configs}/{family}.flags"};
  EXPECT_EQ(MethodFlagfile(rff, "plaza", configs), configs + "/plaza.flags");
  EXPECT_EQ(MethodFlagfile(rff, "kitti_bearing", configs),
            configs + "/kitti_bearing.flags");
  const Method other{"x", "/nowhere/{family}_x.flags"};
  EXPECT_EQ(MethodFlagfile(other, "mrclam", configs),
            "/nowhere/mrclam_x.flags");
}

TEST(FormatTest, SignificantDigitsAndCsvNumbers) {
  EXPECT_EQ(FormatSignificant(0.41234), "0.412");
  EXPECT_EQ(FormatSignificant(1.23456), "1.23");
  EXPECT_EQ(FormatSignificant(12.345), "12.3");
  EXPECT_EQ(FormatSignificant(196.2), "196");
  EXPECT_EQ(FormatSignificant(1960.78), "1961");
  EXPECT_EQ(FormatSignificant(0.000412345), "0.000412");
  EXPECT_EQ(FormatSignificant(-2.5), "-2.50");
  EXPECT_EQ(FormatSignificant(0.0), "0");
  EXPECT_EQ(FormatSignificant(kNaN), "-");
  EXPECT_EQ(FormatCsvNumber(0.1), "0.1");
  EXPECT_EQ(FormatCsvNumber(kNaN), "");
  EXPECT_EQ(NoiseLabel(0.5, "x"), "x0.5");
  EXPECT_EQ(NoiseLabel(3.0, "deg"), "3 deg");
  EXPECT_EQ(NoiseLabel(0.0, "x"), "");
}

TEST(TableTest, CsvQuotesPerRfc4180) {
  EXPECT_EQ(CsvField("plain"), "plain");
  EXPECT_EQ(CsvField("a,b"), "\"a,b\"");
  EXPECT_EQ(CsvField("say \"hi\""), "\"say \"\"hi\"\"\"");
  EXPECT_EQ(CsvField("two\nlines"), "\"two\nlines\"");
  Table table;
  table.header = {"name", "value"};
  table.rows = {{"x", "1"}, {"failed: a, b", ""}};
  EXPECT_EQ(ToCsv(table), "name,value\nx,1\n\"failed: a, b\",\n");
}

TEST(TableTest, MarkdownEscapesPipesAndFillsEmptyCells) {
  Table table;
  table.header = {"a", "b"};
  table.rows = {{"x|y", ""}};
  EXPECT_EQ(ToMarkdown(table), "| a | b |\n| --- | --- |\n| x\\|y | - |\n");
}

RunRow Row(const std::string& method, int landmarks, int seed, double ape,
           const std::string& status = "ok") {
  RunRow row;
  row.experiment = "table1";
  row.method = method;
  row.family = "synthetic_range";
  row.kind = "range";
  row.landmarks = landmarks;
  row.noise = 1.0;
  row.noise_unit = "x";
  row.seed = seed;
  row.status = status;
  row.ape_translation = ape;
  row.solve_seconds = 0.5;
  row.dead_reckoning_ape_translation = 10.0 * seed;
  return row;
}

TEST(AggregateOverSeedsTest, MedianAndMeanOverTheSuccessfulSeeds) {
  const std::vector<RunRow> rows = {
      Row("rff", 10, 1, 0.4),
      Row("rff", 10, 2, 0.1),
      Row("rff", 50, 1, 2.0),
      Row("rff", 10, 3, 1.0),
      Row("rff", 10, 4, kNaN, "failed: diverged"),
      Row("wnoa", 10, 1, kNaN, "failed: no config"),
  };
  const std::vector<SeedAggregate> a = AggregateOverSeeds(rows);
  ASSERT_EQ(a.size(), 3u);  // (rff, 10), (rff, 50), (wnoa, 10) in order.
  EXPECT_EQ(a[0].method, "rff");
  EXPECT_EQ(a[0].landmarks, 10);
  EXPECT_EQ(a[0].runs, 4);
  EXPECT_EQ(a[0].failed, 1);
  EXPECT_EQ(a[0].ape_translation.count, 3);
  EXPECT_DOUBLE_EQ(a[0].ape_translation.median, 0.4);
  EXPECT_DOUBLE_EQ(a[0].ape_translation.mean, 0.5);  // (0.4 + 0.1 + 1) / 3.
  // Dead reckoning counts every seed made: 10, 20, 30, 40.
  EXPECT_DOUBLE_EQ(a[0].dead_reckoning_ape_translation.median, 25.0);
  EXPECT_EQ(a[1].landmarks, 50);
  EXPECT_DOUBLE_EQ(a[1].ape_translation.median, 2.0);
  EXPECT_EQ(a[2].method, "wnoa");
  EXPECT_EQ(a[2].failed, 1);
  EXPECT_EQ(a[2].ape_translation.count, 0);
  EXPECT_TRUE(std::isnan(a[2].ape_translation.median));

  const Table markdown = Table1MarkdownTable(a);
  EXPECT_THAT(markdown.rows[0],
              ElementsAre("rff", "range", "10", "x1", "3 / 4", "0.400 / 0.500",
                          "-", "-", "-", "-", "25.0", "0.500"));
  EXPECT_EQ(markdown.rows[2][5], "-");
  const Table csv = Table1CsvTable(a);
  ASSERT_EQ(csv.header.size(), 8u + 2u * 7u);
  EXPECT_EQ(csv.header[8], "ape_trans_m_median");
  EXPECT_EQ(csv.rows[0][8], "0.4");
  EXPECT_EQ(csv.rows[0][9], "0.5");
}

// A small simulated set: 60 poses, range-bearing, 10 landmarks.
DatasetSpec SmallSpec(const std::string& name, int seed) {
  DatasetSpec spec;
  spec.name = name;
  spec.family = "synthetic_range_bearing";
  spec.kind = "range_bearing";
  spec.landmarks = 10;
  spec.noise = 1.0;
  spec.noise_unit = "x";
  spec.seed = seed;
  spec.make = [seed](Dataset* dataset, std::string* error) {
    SimulationOptions options = PaperOptions(seed);
    options.num_steps = 60;
    options.num_landmarks = 10;
    return Simulate(options, dataset, error);
  };
  return spec;
}

SlamOptions SmallOptions() {
  SlamOptions options;
  options.features.family = "hilbert";
  options.features.num_position_features = 24;
  options.features.num_heading_features = 24;
  options.features.position_kernel.lengthscale = 5.0;
  options.features.position_kernel.variance = 100.0;
  options.features.heading_kernel = options.features.position_kernel;
  options.features.heading_kernel.variance = 0.25;
  options.solver.num_threads = 1;
  return options;
}

TEST(RunExperimentTest, FailedMethodsAndDatasetsAreRowsAndTheGridGoesOn) {
  Experiment experiment;
  experiment.name = "table1";
  experiment.datasets = {SmallSpec("small_s1", 1), SmallSpec("small_s2", 2)};
  DatasetSpec broken;
  broken.name = "broken";
  broken.family = "plaza";
  broken.make = [](Dataset*, std::string* error) {
    *error = "missing.rffd: cannot open";
    return false;
  };
  experiment.datasets.push_back(broken);
  const std::vector<Method> methods = {{"good", ""}, {"noconfig", ""}};
  std::vector<std::string> asked;  // The families options were asked for.
  const OptionsCallback callback =
      [&](const std::string& method, const std::string& family,
          SlamOptions* options, std::string* error) {
        asked.push_back(family);
        if (method == "noconfig") {
          *error = "cfg/" + family + "_noconfig.flags: cannot read";
          return false;
        }
        *options = SmallOptions();
        return true;
      };
  std::ostringstream log;
  Progress progress(&log, CountRuns(experiment, 2));
  EXPECT_EQ(CountRuns(experiment, 2), 6);
  const std::vector<RunRow> rows =
      RunExperiment(experiment, methods, callback, &progress);
  ASSERT_EQ(rows.size(), 6u);
  // Options are settled before each dataset is made, the broken one too.
  EXPECT_EQ(asked, (std::vector<std::string>{
                       "synthetic_range_bearing", "synthetic_range_bearing",
                       "synthetic_range_bearing", "synthetic_range_bearing",
                       "plaza", "plaza"}));
  for (int i : {0, 2}) {
    const RunRow& row = rows[i];
    EXPECT_EQ(row.method, "good");
    EXPECT_TRUE(row.ok()) << row.status;
    EXPECT_EQ(row.features, "hilbert");
    EXPECT_EQ(row.num_features, 24);
    EXPECT_EQ(row.linear_solver, "BANDED_CHOLESKY");
    // 60 s of the paper protocol with 10 landmarks: well under a metre, and
    // far better than odometry alone.
    EXPECT_GT(row.ape_translation, 0.0);
    EXPECT_LT(row.ape_translation, 1.5);
    EXPECT_LT(row.ape_translation, row.dead_reckoning_ape_translation);
    EXPECT_GT(row.ape_rotation_deg, 0.0);
    EXPECT_TRUE(std::isfinite(row.rpe_translation));
    EXPECT_LT(row.landmark_rms, 5.0);
    EXPECT_GT(row.iterations, 0);
    EXPECT_TRUE(std::isfinite(row.final_cost));
    EXPECT_TRUE(row.trajectory.empty());  // keep_solutions is off.
  }
  EXPECT_EQ(rows[1].status,
            "failed: cfg/synthetic_range_bearing_noconfig.flags: cannot read");
  EXPECT_TRUE(std::isnan(rows[1].ape_translation));
  EXPECT_EQ(rows[4].dataset, "broken");
  EXPECT_EQ(rows[4].status,
            "failed: dataset broken: missing.rffd: cannot open");
  // A method without options fails on them, whatever the dataset.
  EXPECT_EQ(rows[5].status, "failed: cfg/plaza_noconfig.flags: cannot read");

  const std::vector<std::string> lines = Lines(log.str());
  ASSERT_EQ(lines.size(), 6u);
  EXPECT_THAT(lines[0], StartsWith("[1/6] good synthetic_range_bearing L=10 "
                                   "noise=x1 seed=1: APE "));
  EXPECT_THAT(lines[1], StartsWith("[2/6] noconfig synthetic_range_bearing "
                                   "L=10 noise=x1 seed=1: failed: cfg/"));
  EXPECT_EQ(lines[5],
            "[6/6] noconfig plaza broken: failed: cfg/plaza_noconfig.flags: "
            "cannot read");

  // The runs table: header, one line per row, the failure quoted (it has
  // no comma, so unquoted) and empty metric cells.
  const std::string csv = ToCsv(RunsCsvTable(rows));
  const std::vector<std::string> csv_lines = Lines(csv);
  ASSERT_EQ(csv_lines.size(), 7u);
  EXPECT_THAT(csv_lines[0],
              StartsWith("experiment,method,dataset,family,kind,landmarks,"
                         "noise,noise_unit,seed,variant,linear_solver,"
                         "features,num_features,status,ape_trans_m,"));
  const std::vector<std::string> failed = Cells(csv_lines[2]);
  EXPECT_EQ(failed[1], "noconfig");
  EXPECT_EQ(failed[14], "");  // ape_trans_m.
}

TEST(RunExperimentTest, NoDatasetIsMadeWhenNoMethodHasValidOptions) {
  Experiment experiment;
  experiment.name = "table1";
  int made = 0;
  DatasetSpec spec = SmallSpec("small_s1", 1);
  spec.make = [&made](Dataset*, std::string*) {
    ++made;
    return true;
  };
  experiment.datasets = {spec};
  const OptionsCallback bad_value = [](const std::string&, const std::string&,
                                       SlamOptions*, std::string* error) {
    *error = "cfg/x.flags: --lengthscale=-1: allowed more than 0";
    return false;
  };
  const std::vector<RunRow> rows =
      RunExperiment(experiment, {{"bad", ""}}, bad_value, nullptr);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(made, 0);
  EXPECT_EQ(rows[0].status,
            "failed: cfg/x.flags: --lengthscale=-1: allowed more than 0");
}

TEST(RunExperimentTest, VariantsOverrideOptionsAndKeepSolutions) {
  Experiment experiment;
  experiment.name = "solvers";
  experiment.datasets = {SmallSpec("small_s3", 3)};
  experiment.keep_solutions = true;
  OptionsVariant sparse{"SPARSE_SCHUR qmc D=12", [](SlamOptions* options) {
                          options->solver.linear_solver = "SPARSE_SCHUR";
                          options->features.family = "qmc";
                          options->features.num_position_features = 12;
                          return true;
                        }};
  OptionsVariant skipped{"never", [](SlamOptions*) { return false; }};
  experiment.variants = {sparse, skipped};
  const OptionsCallback callback = [](const std::string&, const std::string&,
                                      SlamOptions* options, std::string*) {
    *options = SmallOptions();
    return true;
  };
  Progress progress(nullptr, CountRuns(experiment, 1));
  const std::vector<RunRow> rows =
      RunExperiment(experiment, {{"rff", ""}}, callback, &progress);
  ASSERT_EQ(rows.size(), 1u);  // The variant that does not apply: no row.
  EXPECT_EQ(progress.total(), 1);
  EXPECT_TRUE(rows[0].ok()) << rows[0].status;
  EXPECT_EQ(rows[0].variant, "SPARSE_SCHUR qmc D=12");
  EXPECT_EQ(rows[0].linear_solver, "SPARSE_SCHUR");
  EXPECT_EQ(rows[0].features, "qmc");
  EXPECT_EQ(rows[0].num_features, 12);
  EXPECT_FALSE(rows[0].trajectory.empty());
  EXPECT_FALSE(rows[0].estimated_landmarks.empty());
}

TEST(TranslationErrorsTest, DistancesAtTheGroundTruthTimes) {
  const std::vector<TimedPose> truth = {{0, 0, 0, 0}, {1, 1, 0, 0}};
  // The estimate at t = 0.5 and 1.5 brackets t = 1 at (1, 2): error 2.
  const std::vector<TimedPose> estimate = {
      {0, 3, 4, 0}, {0.5, 1, 1, 0}, {1.5, 1, 3, 0}};
  std::vector<double> errors;
  std::string error;
  ASSERT_TRUE(TranslationErrors(truth, estimate, &errors, &error)) << error;
  EXPECT_THAT(errors, ElementsAre(5.0, 2.0));
  EXPECT_FALSE(TranslationErrors(truth, {{0.5, 0, 0, 0}, {2, 0, 0, 0}}, &errors,
                                 &error));
}

TEST(GridTest, QuickAndFullGridSizes) {
  EXPECT_EQ(Table1Datasets(true).size(), 3u * 2u * 2u);
  EXPECT_EQ(Table1Datasets(false).size(), 3u * 5u * 10u);
  // Landmark sweep (3) + noise sweep without its x1 point (2), x 2 seeds.
  EXPECT_EQ(Figure1Datasets(true).size(), 3u * 5u * 2u);
  EXPECT_EQ(Figure1Datasets(false).size(), 3u * 8u * 10u);
  EXPECT_EQ(SolverVariants(true).size(), 4u * 4u * 2u);
  EXPECT_EQ(SolverVariants(false).size(), 4u * 4u * 3u);
  const std::vector<DatasetSpec> table2 =
      Table2Datasets(true, "data", "/no/such/shared");
  ASSERT_EQ(table2.size(), 5u);
  EXPECT_EQ(table2[0].name, "plaza1");
  EXPECT_EQ(table2[1].name, "mrclam6_robot1");
  EXPECT_EQ(table2[4].name, "kitti_scale_short_s1_b5deg");
  EXPECT_EQ(table2[4].family, "kitti_bearing");
  EXPECT_EQ(Table1Datasets(true)[0].name, "s1_rb_L10_x1");
}

// The quick preset through the app, as a user runs it: every output file,
// real numbers, and a method without configs as failed rows (and exit
// status 1).
TEST(RffExperimentAppTest, QuickPresetWritesEveryTableAndPlot) {
  const std::string dir = testing::TempDir("experiment_test");
  const std::string command =
      std::string(RFF_BINARY_DIR) + "/rff_experiment --quick --out_dir=" + dir +
      " --methods=rff,missing=" + dir +
      "/none/{family}.flags --num_threads=2 2> " + dir + "/stderr.txt";
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  ASSERT_EQ(WEXITSTATUS(status), 1) << testing::ReadFile(dir + "/stderr.txt");
  EXPECT_THAT(testing::ReadFile(dir + "/stderr.txt"),
              HasSubstr("rff_experiment: error: 50 of 162 runs failed (their "
                        "messages are in runs.csv)\n"));
  for (const char* name :
       {"table1.csv", "table1.md", "figure1_noise.svg", "figure1_landmarks.svg",
        "table2.csv", "table2.md", "figure2_trajectory.svg", "figure2_ape.svg",
        "solvers.csv", "solvers.md", "runs.csv"}) {
    EXPECT_TRUE(std::filesystem::exists(dir + "/" + name)) << name;
  }

  // Table I: (rff, missing) x 3 kinds x 2 landmark counts.
  const std::vector<std::string> table1 =
      Lines(testing::ReadFile(dir + "/table1.csv"));
  ASSERT_EQ(table1.size(), 1u + 2u * 3u * 2u);
  EXPECT_THAT(table1[0], StartsWith("method,family,kind,landmarks,noise,"
                                    "noise_unit,runs,failed,"
                                    "ape_trans_m_median,ape_trans_m_mean,"));
  int rff_rows = 0;
  for (std::size_t i = 1; i < table1.size(); ++i) {
    const std::vector<std::string> cells = Cells(table1[i]);
    ASSERT_GE(cells.size(), 10u);
    EXPECT_EQ(cells[6], "2");  // Two seeds.
    if (cells[0] == "missing") {
      EXPECT_EQ(cells[7], "2");
      EXPECT_EQ(cells[8], "");
      continue;
    }
    ++rff_rows;
    const double median = std::stod(cells[8]);
    // Measured 0.2 to 1.3 m; the paper protocol's odometry alone drifts
    // several metres.
    EXPECT_GT(median, 0.0) << table1[i];
    EXPECT_LT(median, 3.0) << table1[i];
  }
  EXPECT_EQ(rff_rows, 6);

  // Table II: Plaza to its measured 0.37 m, MRCLAM robot 1 to 0.15 m.
  const std::vector<std::string> table2 =
      Lines(testing::ReadFile(dir + "/table2.csv"));
  ASSERT_EQ(table2.size(), 1u + 2u * 5u);
  EXPECT_EQ(table2[0],
            "method,dataset,family,noise,noise_unit,ape_trans_m,ape_rot_deg,"
            "rpe_trans_m,rpe_rot_deg,landmark_rms_m,"
            "dead_reckoning_ape_trans_m,iterations,final_cost,solve_seconds,"
            "status");
  bool saw_plaza = false, saw_mrclam = false;
  for (const std::string& line : table2) {
    const std::vector<std::string> cells = Cells(line);
    if (cells[0] != "rff") continue;
    if (cells[1] == "plaza1") {
      saw_plaza = true;
      EXPECT_EQ(cells.back(), "ok");
      EXPECT_LT(std::stod(cells[5]), 0.6);
      EXPECT_GT(std::stod(cells[10]), 1.5);  // Dead reckoning: 1.97 m.
    }
    if (cells[1] == "mrclam6_robot1") {
      saw_mrclam = true;
      EXPECT_EQ(cells.back(), "ok");
      EXPECT_LT(std::stod(cells[5]), 0.4);
    }
  }
  EXPECT_TRUE(saw_plaza);
  EXPECT_TRUE(saw_mrclam);
  const std::string table2_md = testing::ReadFile(dir + "/table2.md");
  EXPECT_THAT(table2_md, HasSubstr("| rff | plaza1 | plaza | - | 0."));
  EXPECT_THAT(table2_md, HasSubstr("- missing on plaza1: " + dir +
                                   "/none/plaza.flags: cannot read the "
                                   "flagfile of method 'missing' for plaza"));

  // Solvers: rff x 2 datasets x 32 variants (4 solvers x 4 families x 2 D);
  // missing has no options, one failed row per dataset.
  const std::vector<std::string> solvers =
      Lines(testing::ReadFile(dir + "/solvers.csv"));
  EXPECT_EQ(solvers.size(), 1u + 2u * 32u + 2u);

  // runs.csv: every row of every experiment (figure 2 solves Plaza once per
  // method): table1 12, figure1 30, table2 5, figure2 1, solvers 64 (2).
  const std::vector<std::string> runs =
      Lines(testing::ReadFile(dir + "/runs.csv"));
  EXPECT_EQ(runs.size(), 1u + (12u + 30u + 5u + 1u) * 2u + 64u + 2u);

  const std::string noise = testing::ReadFile(dir + "/figure1_noise.svg");
  EXPECT_THAT(noise, StartsWith("<svg xmlns=\"http://www.w3.org/2000/svg\""));
  EXPECT_THAT(noise, HasSubstr("</svg>"));
  EXPECT_THAT(noise, HasSubstr(">rff, range_bearing</text>"));
  EXPECT_THAT(noise, HasSubstr(">missing, bearing (all runs failed)</text>"));
  EXPECT_EQ(testing::CountOccurrences(noise, "class=\"legend-entry\""), 6);
  EXPECT_THAT(noise, HasSubstr(">observation noise [multiple of sigma_r = 1 "
                               "m, sigma_b = 2 deg]</text>"));
  EXPECT_THAT(noise, HasSubstr(">APE-trans RMS, median over seeds [m]</text>"));
  const std::string landmarks =
      testing::ReadFile(dir + "/figure1_landmarks.svg");
  EXPECT_THAT(landmarks, HasSubstr(">landmarks [count]</text>"));
  const std::string trajectory =
      testing::ReadFile(dir + "/figure2_trajectory.svg");
  EXPECT_THAT(trajectory, HasSubstr(">x [m]</text>"));
  EXPECT_THAT(trajectory, HasSubstr(">rff estimate</text>"));
  EXPECT_THAT(trajectory, HasSubstr(">ground truth</text>"));
  const std::string ape = testing::ReadFile(dir + "/figure2_ape.svg");
  EXPECT_THAT(ape, HasSubstr(">time since start [s]</text>"));
  EXPECT_THAT(ape, HasSubstr(">dead reckoning</text>"));

  // One progress line per run.
  const std::string log = testing::ReadFile(dir + "/stderr.txt");
  EXPECT_THAT(log, HasSubstr("[1/"));
  // configs/plaza.flags: 0.289 m.
  EXPECT_THAT(log, HasSubstr("rff plaza plaza1: APE 0.28"));
}

TEST(RffExperimentAppTest, BadFlagsExitWithAMessage) {
  const std::string dir = testing::TempDir("experiment_test");
  const std::string binary = std::string(RFF_BINARY_DIR) + "/rff_experiment";
  const std::string command = binary + " --out_dir=" + dir +
                              " --methods=rff --experiments=table3 2> " + dir +
                              "/err.txt";
  EXPECT_NE(std::system(command.c_str()), 0);
  EXPECT_EQ(
      testing::ReadFile(dir + "/err.txt")
          .substr(
              testing::ReadFile(dir + "/err.txt").find("rff_experiment: e")),
      "rff_experiment: error: --experiments=table3: unknown experiment "
      "table3; allowed a comma list of table1, figure1, table2, figure2 or "
      "solvers\n");
  const std::string bad_method =
      binary + " --out_dir=" + dir + " --methods=gpslam 2> " + dir + "/err.txt";
  EXPECT_NE(std::system(bad_method.c_str()), 0);
  EXPECT_THAT(testing::ReadFile(dir + "/err.txt"),
              HasSubstr("rff_experiment: error: --methods=gpslam: unknown "
                        "method gpslam; allowed a comma list of rff, wnoa or "
                        "name=flagfile-pattern (e.g. "
                        "mine=configs/{family}_mine.flags)\n"));
  // A solver option out of range stops the tool before the grid starts.
  const std::string bad_option = binary + " --out_dir=" + dir +
                                 " --num_features=30000 2> " + dir + "/err.txt";
  EXPECT_NE(std::system(bad_option.c_str()), 0);
  EXPECT_THAT(testing::ReadFile(dir + "/err.txt"),
              HasSubstr("rff_experiment: error: --num_features=30000: "));
  EXPECT_THAT(testing::ReadFile(dir + "/err.txt"), Not(HasSubstr("[1/")));
}

}  // namespace
}  // namespace rff
