#include "rff_ceres/experiment/experiment.h"

#include <algorithm>
#include <filesystem>
#include <set>
#include <utility>

#include "rff_ceres/io/output_file.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/option_error.h"
#include "rff_ceres/plot/svg_plot.h"

namespace rff {
namespace {

bool WriteText(const std::string& path, const std::string& text,
               ExperimentSummary* summary, std::string* error) {
  if (!WriteOutputFile(
          path, [&](std::ostream* out) { *out << text; }, error)) {
    return false;
  }
  if (std::find(summary->files.begin(), summary->files.end(), path) ==
      summary->files.end()) {
    summary->files.push_back(path);
  }
  return true;
}

// Renders and writes each plot in turn, so that a failure leaves the ones
// before it written and listed.
bool WritePlots(const std::string& out_dir, const std::vector<NamedPlot>& plots,
                ExperimentSummary* summary, std::string* error) {
  std::string svg;
  for (const NamedPlot& named : plots) {
    if (!RenderSvg(named.plot, &svg, error) ||
        !WriteText(out_dir + "/" + named.file_name, svg, summary, error)) {
      return false;
    }
  }
  return true;
}

std::vector<RunRow> WithoutSolutions(std::vector<RunRow> rows) {
  for (RunRow& row : rows) {
    row.trajectory.clear();
    row.trajectory.shrink_to_fit();
    row.estimated_landmarks.clear();
    row.estimated_landmarks.shrink_to_fit();
  }
  return rows;
}

// The known names of config.experiments, or an --experiments error.
bool SelectExperiments(const ExperimentConfig& config,
                       std::set<std::string>* selected, std::string* error) {
  // The flag's value as given, comma-separated.
  std::string experiment_list;
  for (const std::string& name : config.experiments) {
    experiment_list += (experiment_list.empty() ? "" : ",") + name;
  }
  const std::string allowed =
      "a comma list of " + JoinAlternatives(AllExperimentNames());
  for (const std::string& name : config.experiments) {
    const auto& all = AllExperimentNames();
    if (std::find(all.begin(), all.end(), name) == all.end()) {
      *error = OptionError("experiments", experiment_list,
                           "unknown experiment " + name, allowed);
      return false;
    }
    selected->insert(name);
  }
  if (selected->empty()) {
    *error =
        OptionError("experiments", experiment_list, "no experiment", allowed);
    return false;
  }
  return true;
}

// The dataset Figure 2 shows: config.figure2_dataset among the Table II and
// Table I datasets.
bool FindFigure2Dataset(const ExperimentConfig& config, DatasetSpec* spec,
                        std::string* error) {
  std::vector<DatasetSpec> candidates =
      Table2Datasets(config.quick, config.data_dir, config.shared_dir);
  for (const DatasetSpec& s : Table1Datasets(config.quick)) {
    candidates.push_back(s);
  }
  std::string names;
  for (const DatasetSpec& s : candidates) {
    if (s.name == config.figure2_dataset) *spec = s;
    if (names.size() < 400) names += (names.empty() ? "" : ", ") + s.name;
  }
  if (spec->name.empty()) {
    *error = OptionError("figure2_dataset", config.figure2_dataset,
                         "not a dataset of the grids", names);
    return false;
  }
  return true;
}

// The grids of the `selected` experiments, in the order of
// AllExperimentNames; figure2 also sets `figure2_spec`.
bool BuildExperiments(const ExperimentConfig& config,
                      const std::set<std::string>& selected,
                      std::vector<Experiment>* experiments,
                      DatasetSpec* figure2_spec, std::string* error) {
  for (const std::string& name : AllExperimentNames()) {
    if (selected.count(name) == 0) continue;
    Experiment experiment;
    experiment.name = name;
    if (name == "table1") {
      experiment.datasets = Table1Datasets(config.quick);
    } else if (name == "figure1") {
      experiment.datasets = Figure1Datasets(config.quick);
    } else if (name == "table2") {
      experiment.datasets =
          Table2Datasets(config.quick, config.data_dir, config.shared_dir);
    } else if (name == "figure2") {
      if (!FindFigure2Dataset(config, figure2_spec, error)) return false;
      experiment.datasets = {*figure2_spec};
      experiment.keep_solutions = true;
    } else {
      experiment.datasets = SolverDatasets(config.quick, config.data_dir);
      experiment.variants = SolverVariants(config.quick);
    }
    experiments->push_back(experiment);
  }
  return true;
}

// The tables or figures of `experiment` from its rows.
bool WriteExperimentOutputs(const Experiment& experiment,
                            const std::vector<RunRow>& rows,
                            const ExperimentConfig& config,
                            const DatasetSpec& figure2_spec,
                            ExperimentSummary* summary, std::string* error) {
  const std::string& out = config.out_dir;
  const std::string methods = MethodNames(config.methods);
  const std::string& name = experiment.name;
  if (name == "table1") {
    const std::vector<SeedAggregate> aggregates = AggregateOverSeeds(rows);
    return WriteText(out + "/table1.csv", ToCsv(Table1CsvTable(aggregates)),
                     summary, error) &&
           WriteText(out + "/table1.md",
                     Table1MarkdownDocument(aggregates, rows, methods), summary,
                     error);
  }
  if (name == "figure1") {
    return WritePlots(out, Figure1Plots(rows, config.methods, config.quick),
                      summary, error);
  }
  if (name == "table2") {
    return WriteText(out + "/table2.csv", ToCsv(Table2CsvTable(rows)), summary,
                     error) &&
           WriteText(out + "/table2.md",
                     Table2MarkdownDocument(rows, methods, config.quick),
                     summary, error);
  }
  if (name == "figure2") {
    return WritePlots(out, Figure2Plots(figure2_spec, rows), summary, error);
  }
  return WriteText(out + "/solvers.csv", ToCsv(SolversCsvTable(rows)), summary,
                   error) &&
         WriteText(out + "/solvers.md", SolversMarkdownDocument(rows, methods),
                   summary, error);
}

}  // namespace

bool RunExperiments(const ExperimentConfig& config,
                    const OptionsCallback& options_callback,
                    ExperimentSummary* summary, std::string* error) {
  *summary = ExperimentSummary();
  if (config.methods.empty()) {
    *error = "no method to run";
    return false;
  }
  if (config.out_dir.empty()) {
    *error = "no output directory";
    return false;
  }
  std::set<std::string> selected;
  if (!SelectExperiments(config, &selected, error)) return false;

  // Build every grid first: the progress lines count against the total.
  std::vector<Experiment> experiments;
  DatasetSpec figure2_spec;
  if (!BuildExperiments(config, selected, &experiments, &figure2_spec, error)) {
    return false;
  }
  int total = 0;
  for (const Experiment& e : experiments) {
    total += CountRuns(e, static_cast<int>(config.methods.size()));
  }

  std::error_code filesystem_error;
  std::filesystem::create_directories(config.out_dir, filesystem_error);
  if (filesystem_error) {
    *error = config.out_dir +
             ": cannot create the directory: " + filesystem_error.message();
    return false;
  }
  Progress progress(config.progress, total);
  for (const Experiment& experiment : experiments) {
    std::vector<RunRow> rows =
        RunExperiment(experiment, config.methods, options_callback, &progress);
    if (!WriteExperimentOutputs(experiment, rows, config, figure2_spec, summary,
                                error)) {
      return false;
    }
    for (RunRow& row : WithoutSolutions(std::move(rows))) {
      summary->rows.push_back(std::move(row));
    }
    // Rewritten after every experiment, so a long grid stopped midway keeps
    // the rows it has.
    if (!WriteText(config.out_dir + "/runs.csv",
                   ToCsv(RunsCsvTable(summary->rows)), summary, error)) {
      return false;
    }
  }
  return true;
}

}  // namespace rff
