#include "rff_ceres/experiment/experiment.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <tuple>

#include "rff_ceres/convert/mrclam.h"
#include "rff_ceres/dead_reckoning.h"
#include "rff_ceres/io/dataset_io.h"
#include "rff_ceres/io/output_file.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/metrics.h"
#include "rff_ceres/option_error.h"
#include "rff_ceres/plot/svg_plot.h"
#include "rff_ceres/simulate.h"
#include "rff_ceres/statistics.h"

namespace rff {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;
constexpr double kNaN = RunRow::kNone;

// Figure 1: the noise sweep runs at this many landmarks.
constexpr int kFigure1NoiseLandmarks = 50;
constexpr int kFigure1NoiseLandmarksQuick = 25;
// Plotted lines are thinned to at most this many points (the SVG stays
// small; the eye cannot tell more apart at 720 pixels).
constexpr std::size_t kMaxPlotPoints = 2000;

std::string Replace(std::string text, const std::string& from,
                    const std::string& to) {
  for (std::size_t at = text.find(from); at != std::string::npos;
       at = text.find(from, at + to.size())) {
    text.replace(at, from.size(), to);
  }
  return text;
}

std::vector<std::string> Split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::string part;
  std::istringstream stream(text);
  while (std::getline(stream, part, separator)) parts.push_back(part);
  if (!text.empty() && text.back() == separator) parts.push_back("");
  return parts;
}

std::string Trim(const std::string& text) {
  const std::size_t begin = text.find_first_not_of(" \t");
  if (begin == std::string::npos) return "";
  const std::size_t end = text.find_last_not_of(" \t");
  return text.substr(begin, end - begin + 1);
}

std::string ShortKind(const std::string& kind) {
  return kind == "range_bearing" ? "rb" : kind;
}

std::string Int(int value) { return std::to_string(value); }

// Settings columns: 0 landmarks and seed -1 mean "not a setting".
std::string LandmarksCell(int landmarks) {
  return landmarks > 0 ? Int(landmarks) : "";
}
std::string SeedCell(int seed) { return seed >= 0 ? Int(seed) : ""; }

double ValueOr(const ErrorSummary& summary, double scale) {
  return summary.available ? summary.rms * scale : kNaN;
}

// The simulated paper set (PaperOptions) of `kind` with `landmarks` and the
// observation sigmas times `noise`.
DatasetSpec PaperSpec(const std::string& kind, int landmarks, double noise,
                      int seed) {
  DatasetSpec spec;
  spec.name = "s" + Int(seed) + "_" + ShortKind(kind) + "_L" + Int(landmarks) +
              "_" + NoiseLabel(noise, "x");
  spec.family = SyntheticFamily(kind);
  spec.kind = kind;
  spec.landmarks = landmarks;
  spec.noise = noise;
  spec.noise_unit = "x";
  spec.seed = seed;
  spec.make = [kind, landmarks, noise, seed](Dataset* dataset,
                                             std::string* error) {
    SimulationOptions options = PaperOptions(seed);
    if (!ParseMeasurementKind(kind, &options.kind, error)) return false;
    options.num_landmarks = landmarks;
    options.sigma_range *= noise;
    options.sigma_bearing *= noise;
    return Simulate(options, dataset, error);
  };
  return spec;
}

DatasetSpec FileSpec(const std::string& name, const std::string& family,
                     const std::string& kind, const std::string& path) {
  DatasetSpec spec;
  spec.name = name;
  spec.family = family;
  spec.kind = kind;
  spec.make = [path](Dataset* dataset, std::string* error) {
    return ReadDataset(path, dataset, error);
  };
  return spec;
}

// MRCLAM Dataset 6 robot `robot` converted as data/mrclam6_robot1.rffd was
// (rff_convert --format=mrclam --mrclam_odometry_interval=1).
DatasetSpec MrclamSpec(const std::string& directory, int robot) {
  DatasetSpec spec;
  spec.name = "mrclam6_robot" + Int(robot);
  spec.family = "mrclam";
  spec.kind = "range_bearing";
  spec.make = [directory, robot](Dataset* dataset, std::string* error) {
    MrclamOptions options;
    options.robot = robot;
    options.odometry_interval = 1.0;
    MrclamSummary summary;
    return ConvertMrclam(directory, options, dataset, &summary, error);
  };
  return spec;
}

// The KITTI-projected bearing-only set with bearing sigma `sigma_deg`; the
// quick preset drives a fifth of the distance among a fifth of the
// landmarks.
DatasetSpec KittiSpec(bool quick, double sigma_deg, int seed) {
  DatasetSpec spec;
  spec.name = std::string(quick ? "kitti_scale_short" : "kitti_scale") + "_s" +
              Int(seed) + "_b" + FormatNumber(sigma_deg) + "deg";
  spec.family = "kitti_bearing";
  spec.kind = "bearing";
  spec.noise = sigma_deg;
  spec.noise_unit = "deg";
  spec.seed = seed;
  spec.make = [quick, sigma_deg, seed](Dataset* dataset, std::string* error) {
    SimulationOptions options = KittiScaleOptions(seed);
    options.sigma_bearing = sigma_deg * M_PI / 180.0;
    if (quick) {
      options.num_steps /= 5;
      options.num_landmarks /= 5;
    }
    return Simulate(options, dataset, error);
  };
  return spec;
}

// Status of a run whose variant does not apply; such rows are dropped.
constexpr char kNotApplicable[] = "not applicable";

void FailRow(const std::string& why, RunRow* row) {
  row->status = "failed: " + why;
  row->ape_translation = row->ape_rotation_deg = kNaN;
  row->rpe_translation = row->rpe_rotation_deg = kNaN;
  row->landmark_rms = kNaN;
  row->trajectory.clear();
  row->estimated_landmarks.clear();
}

// APE-trans of dead reckoning against the ground truth; NaN when the
// dataset has no odometry or it does not cover every ground-truth time.
double DeadReckoningApe(const Dataset& dataset, std::vector<TimedPose>* poses) {
  DeadReckoningOptions options;
  options.hold_through_gaps = true;
  DeadReckoningResult result;
  std::string error;
  if (!DeadReckon(dataset, options, &result, &error)) return kNaN;
  Evaluation evaluation;
  if (!Evaluate(dataset.ground_truth, dataset.ground_truth_landmarks,
                result.poses, nullptr, EvaluationOptions(), &evaluation,
                &error)) {
    return kNaN;
  }
  if (poses != nullptr) *poses = result.poses;
  return ValueOr(evaluation.ape_translation, 1.0);
}

// Solves `dataset` with `base` (the method's options) changed by `variant`
// and fills the row; the row's status says why when it fails.
void SolveAndEvaluate(const Dataset& dataset, const SlamOptions& base,
                      const OptionsVariant* variant, bool keep_solution,
                      RunRow* row) {
  SlamOptions options = base;
  std::string error;
  if (variant != nullptr && variant->apply && !variant->apply(&options)) {
    row->status = kNotApplicable;
    return;
  }
  row->linear_solver = options.solver.linear_solver;
  if (options.prior == "rff") {
    row->features = options.trajectory.family;
    row->num_features = options.trajectory.num_position_features;
  } else {
    // A prior without features (wnoa): its states are the model.
    row->features = options.prior;
    if (variant != nullptr)
      row->variant = row->linear_solver + " " + row->features;
  }

  SlamResult result;
  if (!RunSlam(dataset, options, &result, &error)) {
    FailRow("solve: " + error, row);
    return;
  }
  // What "auto" settled on, not what was asked for.
  row->linear_solver = result.linear_solver;
  if (options.prior == "rff") {
    row->num_features = result.trajectory_options.num_position_features;
  }
  row->iterations = result.total_iterations;
  row->final_cost = result.summary.final_cost;
  row->solve_seconds = result.solve_seconds;

  Evaluation evaluation;
  if (!Evaluate(dataset.ground_truth, dataset.ground_truth_landmarks,
                result.trajectory, &result.landmarks, EvaluationOptions(),
                &evaluation, &error)) {
    FailRow("evaluation: " + error, row);
    return;
  }
  row->ape_translation = ValueOr(evaluation.ape_translation, 1.0);
  row->ape_rotation_deg = ValueOr(evaluation.ape_rotation, kRadToDeg);
  row->rpe_translation = ValueOr(evaluation.rpe_translation, 1.0);
  row->rpe_rotation_deg = ValueOr(evaluation.rpe_rotation, kRadToDeg);
  row->landmark_rms = ValueOr(evaluation.landmarks.distance, 1.0);
  if (!std::isfinite(row->ape_translation)) {
    FailRow("evaluation: APE-trans not available: " +
                evaluation.ape_translation.reason,
            row);
    return;
  }
  if (keep_solution) {
    row->trajectory = std::move(result.trajectory);
    row->estimated_landmarks = std::move(result.landmarks);
  }
}

// ---------------------------------------------------------------------------
// Writers.

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

std::string MedianMean(const Spread& spread) {
  if (spread.count == 0) return "-";
  return FormatSignificant(spread.median) + " / " +
         FormatSignificant(spread.mean);
}

// The failed runs under a Markdown table, so that a "failed" count or
// status is explained where it is read.
std::string FailureList(const std::vector<RunRow>& rows) {
  std::string text;
  int listed = 0, failed = 0;
  constexpr int kMaxListed = 10;
  for (const RunRow& row : rows) {
    if (row.ok()) continue;
    ++failed;
    if (listed == kMaxListed) continue;
    ++listed;
    text += "- " + row.method + " on " + row.dataset +
            (row.variant.empty() ? "" : " (" + row.variant + ")") + ": " +
            row.status.substr(row.status.find(':') + 2) + "\n";
  }
  if (failed == 0) return "";
  if (failed > listed) {
    text += "- ... and " + Int(failed - listed) + " more (runs.csv)\n";
  }
  return "\nFailed runs (" + Int(failed) + "):\n\n" + text;
}

std::string MarkdownDocument(const std::string& title,
                             const std::string& description, const Table& table,
                             const std::vector<RunRow>& rows) {
  return "# " + title + "\n\n" + description + "\n\n" + ToMarkdown(table) +
         FailureList(rows);
}

std::string MethodList(const std::vector<Method>& methods) {
  std::string text;
  for (const Method& m : methods) text += (text.empty() ? "" : ", ") + m.name;
  return text;
}

template <typename T>
std::vector<T> Thin(const std::vector<T>& values) {
  if (values.size() <= kMaxPlotPoints) return values;
  std::vector<T> thinned;
  const double stride =
      static_cast<double>(values.size() - 1) / (kMaxPlotPoints - 1);
  for (std::size_t i = 0; i < kMaxPlotPoints; ++i) {
    thinned.push_back(values[static_cast<std::size_t>(std::round(i * stride))]);
  }
  return thinned;
}

PlotSeries TrajectorySeries(const std::string& label,
                            const std::vector<TimedPose>& poses,
                            const std::string& color, double width) {
  PlotSeries series;
  series.label = label;
  series.color = color;
  series.line_width = width;
  for (const TimedPose& p : Thin(poses)) {
    series.x.push_back(p.x);
    series.y.push_back(p.y);
  }
  return series;
}

PlotSeries LandmarkSeries(const std::string& label,
                          const std::vector<Landmark>& landmarks,
                          const std::string& color, double radius) {
  PlotSeries series;
  series.label = label;
  series.color = color;
  series.line = false;
  series.markers = true;
  series.marker_radius = radius;
  for (const Landmark& l : landmarks) {
    series.x.push_back(l.x);
    series.y.push_back(l.y);
  }
  return series;
}

// Colours of the methods in the figures (ground truth is black, dead
// reckoning grey).
const char* MethodColor(std::size_t index) {
  static const char* kColors[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e",
                                  "#9467bd", "#8c564b", "#e377c2", "#17becf"};
  return kColors[index % (sizeof(kColors) / sizeof(kColors[0]))];
}

bool HasFinitePoint(const PlotSeries& series) {
  for (std::size_t i = 0; i < series.x.size(); ++i) {
    if (std::isfinite(series.x[i]) && std::isfinite(series.y[i])) return true;
  }
  return false;
}

// One curve per (method, kind) of the median APE-trans over seeds against
// `x_of` of the aggregates that `select` keeps.
Plot Figure1Plot(const std::vector<SeedAggregate>& aggregates,
                 const std::vector<Method>& methods,
                 const std::function<bool(const SeedAggregate&)>& select,
                 const std::function<double(const SeedAggregate&)>& x_of) {
  Plot plot;
  plot.log_x = true;
  plot.y_from_zero = true;
  plot.y_label = "APE-trans RMS, median over seeds [m]";
  const std::vector<std::string> kinds = {"range_bearing", "range", "bearing"};
  const std::vector<std::string> dashes = {"", "6,3", "2,2"};
  for (std::size_t m = 0; m < methods.size(); ++m) {
    for (const std::string& kind : kinds) {
      PlotSeries series;
      series.label = methods[m].name + ", " + kind;
      series.color = MethodColor(3 * m + (&kind - &kinds[0]));
      series.markers = true;
      std::vector<std::pair<double, double>> points;
      bool any = false;
      for (const SeedAggregate& a : aggregates) {
        if (a.method != methods[m].name || a.kind != kind || !select(a)) {
          continue;
        }
        any = true;
        points.emplace_back(x_of(a), a.ape_translation.median);
      }
      if (!any) continue;
      std::sort(points.begin(), points.end());
      for (const auto& [x, y] : points) {
        series.x.push_back(x);
        series.y.push_back(y);
      }
      if (!HasFinitePoint(series)) series.label += " (all runs failed)";
      plot.series.push_back(series);
    }
  }
  return plot;
}

bool WriteFigure1(const std::vector<RunRow>& rows,
                  const std::vector<Method>& methods, bool quick,
                  const std::string& out_dir, ExperimentSummary* summary,
                  std::string* error) {
  const std::vector<SeedAggregate> aggregates = AggregateOverSeeds(rows);
  const int noise_landmarks =
      quick ? kFigure1NoiseLandmarksQuick : kFigure1NoiseLandmarks;
  int seeds = 0;
  for (const SeedAggregate& a : aggregates) seeds = std::max(seeds, a.runs);

  Plot noise = Figure1Plot(
      aggregates, methods,
      [&](const SeedAggregate& a) { return a.landmarks == noise_landmarks; },
      [](const SeedAggregate& a) { return a.noise; });
  noise.title = "APE-trans vs observation noise (" + Int(noise_landmarks) +
                " landmarks, " + Int(seeds) + " seeds)";
  noise.x_label =
      "observation noise [multiple of sigma_r = 1 m, sigma_b = 2 deg]";
  Plot landmarks = Figure1Plot(
      aggregates, methods,
      [](const SeedAggregate& a) { return a.noise == 1.0; },
      [](const SeedAggregate& a) { return a.landmarks; });
  landmarks.title = "APE-trans vs number of landmarks (paper noise, " +
                    Int(seeds) + " seeds)";
  landmarks.x_label = "landmarks [count]";

  std::string svg;
  for (const auto& [plot, name] :
       {std::make_pair(&noise, "figure1_noise.svg"),
        std::make_pair(&landmarks, "figure1_landmarks.svg")}) {
    if (!RenderSvg(*plot, &svg, error)) return false;
    if (!WriteText(out_dir + "/" + name, svg, summary, error)) return false;
  }
  return true;
}

bool WriteFigure2(const DatasetSpec& spec, const std::vector<RunRow>& rows,
                  const std::string& out_dir, ExperimentSummary* summary,
                  std::string* error) {
  Dataset dataset;
  std::string make_error;
  if (!spec.make(&dataset, &make_error)) dataset = Dataset();
  std::vector<TimedPose> dead_reckoning;
  DeadReckoningApe(dataset, &dead_reckoning);

  Plot map;
  map.title = "Estimated vs true trajectory and landmarks: " + spec.name;
  map.x_label = "x [m]";
  map.y_label = "y [m]";
  map.equal_scale = true;
  map.height = 640;
  map.series.push_back(
      TrajectorySeries("ground truth", dataset.ground_truth, "#000000", 2.0));
  if (!dead_reckoning.empty()) {
    map.series.push_back(
        TrajectorySeries("dead reckoning", dead_reckoning, "#aaaaaa", 1.0));
  }
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (!rows[i].ok()) continue;
    map.series.push_back(TrajectorySeries(
        rows[i].method + " estimate", rows[i].trajectory, MethodColor(i), 1.2));
  }
  map.series.push_back(LandmarkSeries(
      "true landmarks", dataset.ground_truth_landmarks, "#000000", 4.0));
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (!rows[i].ok()) continue;
    map.series.push_back(LandmarkSeries(rows[i].method + " landmarks",
                                        rows[i].estimated_landmarks,
                                        MethodColor(i), 2.5));
  }

  Plot ape;
  ape.title = "Translation error along the trajectory: " + spec.name;
  ape.x_label = "time since start [s]";
  ape.y_label = "translation error [m]";
  ape.y_from_zero = true;
  const double t0 =
      dataset.ground_truth.empty() ? 0.0 : dataset.ground_truth.front().t;
  auto error_series = [&](const std::string& label,
                          const std::vector<TimedPose>& estimate,
                          const std::string& color) {
    PlotSeries series;
    series.label = label;
    series.color = color;
    std::vector<double> errors;
    std::string ignored;
    if (!TranslationErrors(dataset.ground_truth, estimate, &errors, &ignored)) {
      return;
    }
    std::vector<std::size_t> indices(errors.size());
    for (std::size_t i = 0; i < indices.size(); ++i) indices[i] = i;
    for (std::size_t i : Thin(indices)) {
      series.x.push_back(dataset.ground_truth[i].t - t0);
      series.y.push_back(errors[i]);
    }
    ape.series.push_back(series);
  };
  if (!dead_reckoning.empty()) {
    error_series("dead reckoning", dead_reckoning, "#aaaaaa");
  }
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (rows[i].ok()) {
      error_series(rows[i].method, rows[i].trajectory, MethodColor(i));
    }
  }

  std::string svg;
  if (!RenderSvg(map, &svg, error) ||
      !WriteText(out_dir + "/figure2_trajectory.svg", svg, summary, error) ||
      !RenderSvg(ape, &svg, error) ||
      !WriteText(out_dir + "/figure2_ape.svg", svg, summary, error)) {
    return false;
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

}  // namespace

// ---------------------------------------------------------------------------
// Methods and datasets.

// The values of --methods, for its messages.
constexpr char kAllowedMethods[] =
    "a comma list of rff, wnoa or name=flagfile-pattern (e.g. "
    "mine=configs/{family}_mine.flags)";

bool ParseMethods(const std::string& list, std::vector<Method>* methods,
                  std::string* error) {
  methods->clear();
  std::set<std::string> seen;
  for (const std::string& raw : Split(list, ',')) {
    const std::string item = Trim(raw);
    Method method;
    const std::size_t equals = item.find('=');
    if (equals == std::string::npos) {
      method.name = item;
      if (item == "rff") {
        method.flagfile_pattern = "{configs}/{family}.flags";
      } else if (item == "wnoa") {
        method.flagfile_pattern = "{configs}/{family}_wnoa.flags";
      } else if (!item.empty()) {
        *error = OptionError("methods", list, "unknown method " + item,
                             kAllowedMethods);
        return false;
      }
    } else {
      method.name = Trim(item.substr(0, equals));
      method.flagfile_pattern = Trim(item.substr(equals + 1));
      if (method.flagfile_pattern.empty()) {
        *error = OptionError(
            "methods", list,
            "method " + method.name + " has an empty flagfile pattern",
            kAllowedMethods);
        return false;
      }
    }
    if (method.name.empty()) {
      *error = OptionError("methods", list, "a method has an empty name",
                           kAllowedMethods);
      return false;
    }
    if (!seen.insert(method.name).second) {
      *error = OptionError("methods", list,
                           "method " + method.name + " is given twice",
                           "each method once");
      return false;
    }
    methods->push_back(method);
  }
  if (methods->empty()) {
    *error = OptionError("methods", list, "no method", kAllowedMethods);
    return false;
  }
  return true;
}

std::string MethodFlagfile(const Method& method, const std::string& family,
                           const std::string& configs_dir) {
  return Replace(Replace(method.flagfile_pattern, "{configs}", configs_dir),
                 "{family}", family);
}

std::string SyntheticFamily(const std::string& kind) {
  return "synthetic_" + kind;
}

std::string NoiseLabel(double noise, const std::string& unit) {
  if (noise == 0.0 || unit.empty()) return "";
  if (unit == "x") return "x" + FormatNumber(noise);
  return FormatNumber(noise) + " " + unit;
}

std::vector<DatasetSpec> Table1Datasets(bool quick) {
  const std::vector<int> landmarks =
      quick ? std::vector<int>{10, 50} : std::vector<int>{5, 10, 25, 50, 100};
  const int seeds = quick ? 2 : 10;
  std::vector<DatasetSpec> specs;
  for (const std::string kind : {"range_bearing", "range", "bearing"}) {
    for (int l : landmarks) {
      for (int seed = 1; seed <= seeds; ++seed) {
        specs.push_back(PaperSpec(kind, l, 1.0, seed));
      }
    }
  }
  return specs;
}

std::vector<DatasetSpec> Figure1Datasets(bool quick) {
  const std::vector<int> landmarks = quick
                                         ? std::vector<int>{10, 25, 50}
                                         : std::vector<int>{5, 10, 25, 50, 100};
  const std::vector<double> noises =
      quick ? std::vector<double>{0.5, 1.0, 2.0}
            : std::vector<double>{0.5, 1.0, 2.0, 4.0};
  const int noise_landmarks =
      quick ? kFigure1NoiseLandmarksQuick : kFigure1NoiseLandmarks;
  const int seeds = quick ? 2 : 10;
  std::vector<DatasetSpec> specs;
  for (const std::string kind : {"range_bearing", "range", "bearing"}) {
    // The landmark sweep at the paper's noise, then the noise sweep (its
    // x1 point is already in the landmark sweep).
    std::vector<std::pair<int, double>> settings;
    for (int l : landmarks) settings.emplace_back(l, 1.0);
    for (double n : noises) {
      if (n != 1.0) settings.emplace_back(noise_landmarks, n);
    }
    for (const auto& [l, n] : settings) {
      for (int seed = 1; seed <= seeds; ++seed) {
        specs.push_back(PaperSpec(kind, l, n, seed));
      }
    }
  }
  return specs;
}

std::vector<DatasetSpec> Table2Datasets(bool quick, const std::string& data_dir,
                                        const std::string& shared_dir) {
  std::vector<DatasetSpec> specs;
  specs.push_back(
      FileSpec("plaza1", "plaza", "range", data_dir + "/plaza1.rffd"));
  specs.push_back(FileSpec("mrclam6_robot1", "mrclam", "range_bearing",
                           data_dir + "/mrclam6_robot1.rffd"));
  const std::string mrclam_dir = shared_dir + "/data/mrclam6";
  if (!quick && !shared_dir.empty()) {
    for (int robot = 2; robot <= 5; ++robot) {
      const std::string odometry =
          mrclam_dir + "/Robot" + Int(robot) + "_Odometry.dat";
      if (std::filesystem::exists(odometry)) {
        specs.push_back(MrclamSpec(mrclam_dir, robot));
      }
    }
  }
  for (double sigma_deg : {1.0, 3.0, 5.0}) {
    specs.push_back(KittiSpec(quick, sigma_deg, 1));
  }
  return specs;
}

std::vector<DatasetSpec> SolverDatasets(bool /*quick*/,
                                        const std::string& data_dir) {
  return {PaperSpec("range_bearing", 50, 1.0, 1),
          FileSpec("plaza1", "plaza", "range", data_dir + "/plaza1.rffd")};
}

std::vector<OptionsVariant> SolverVariants(bool quick) {
  const std::vector<int> sizes =
      quick ? std::vector<int>{12, 24} : std::vector<int>{12, 24, 48};
  std::vector<OptionsVariant> variants;
  for (const std::string solver :
       {"DENSE_SCHUR", "SPARSE_SCHUR", "ITERATIVE_SCHUR",
        "SPARSE_NORMAL_CHOLESKY"}) {
    for (const std::string family :
         {"hilbert", "rff", "qmc", "gauss_hermite"}) {
      for (int d : sizes) {
        OptionsVariant variant;
        variant.name = solver + " " + family + " D=" + Int(d);
        const bool first_features = family == "hilbert" && d == sizes[0];
        variant.apply = [solver, family, d,
                         first_features](SlamOptions* options) {
          // Priors without features run once, with the sparse Cholesky:
          // eliminating landmarks seen from the whole run first leaves the
          // WNOA states in one dense system (Plaza: 21000 unknowns, hours).
          if (options->prior != "rff" &&
              (!first_features || solver != "SPARSE_NORMAL_CHOLESKY")) {
            return false;
          }
          options->solver.linear_solver = solver;
          options->trajectory.family = family;
          options->trajectory.num_position_features = d;
          options->trajectory.num_heading_features = d;
          return true;
        };
        variants.push_back(variant);
      }
    }
  }
  return variants;
}

// ---------------------------------------------------------------------------
// Running.

void Progress::Report(const RunRow& row) {
  ++done_;
  if (output_ == nullptr) return;
  std::ostringstream line;
  line << "[" << done_ << "/" << total_ << "] " << row.method << " "
       << row.family;
  if (row.landmarks > 0) line << " L=" << row.landmarks;
  if (!NoiseLabel(row.noise, row.noise_unit).empty()) {
    line << " noise=" << NoiseLabel(row.noise, row.noise_unit);
  }
  if (row.seed >= 0) line << " seed=" << row.seed;
  if (row.seed < 0 || row.noise_unit == "deg") line << " " << row.dataset;
  if (!row.variant.empty()) line << " " << row.variant;
  line << ": ";
  if (row.ok()) {
    char numbers[96];
    std::snprintf(numbers, sizeof(numbers), "APE %.3g m, %.2f s",
                  row.ape_translation, row.solve_seconds);
    line << numbers;
  } else {
    line << row.status;
  }
  *output_ << line.str() << std::endl;
}

int CountRuns(const Experiment& experiment, int num_methods) {
  return static_cast<int>(experiment.datasets.size()) * num_methods *
         static_cast<int>(std::max<std::size_t>(1, experiment.variants.size()));
}

std::vector<RunRow> RunExperiment(const Experiment& experiment,
                                  const std::vector<Method>& methods,
                                  const OptionsCallback& options_callback,
                                  Progress* progress) {
  std::vector<RunRow> rows;
  for (const DatasetSpec& spec : experiment.datasets) {
    Dataset dataset;
    std::string dataset_error;
    bool made = spec.make && spec.make(&dataset, &dataset_error);
    if (!spec.make) dataset_error = "no way to make the dataset";
    if (made && dataset.ground_truth.empty()) {
      made = false;
      dataset_error = "no ground truth (GT_POSE) to evaluate against";
    }
    const double dead_reckoning_ape =
        made ? DeadReckoningApe(dataset, nullptr) : kNaN;

    const std::size_t num_variants =
        std::max<std::size_t>(1, experiment.variants.size());
    for (const Method& method : methods) {
      RunRow base_row;
      base_row.experiment = experiment.name;
      base_row.method = method.name;
      base_row.dataset = spec.name;
      base_row.family = spec.family;
      base_row.kind = spec.kind;
      base_row.landmarks = spec.landmarks;
      base_row.noise = spec.noise;
      base_row.noise_unit = spec.noise_unit;
      base_row.seed = spec.seed;
      base_row.dead_reckoning_ape_translation = dead_reckoning_ape;

      // The method's options once per dataset; when there are none, one
      // failed row stands for all the variants.
      SlamOptions base;
      std::string why;
      if (!made) {
        why = "dataset " + spec.name + ": " + dataset_error;
      } else if (!options_callback(method.name, spec.family, &base, &why)) {
        if (why.empty()) why = "no options for method " + method.name;
      } else {
        why.clear();
      }
      if (!why.empty()) {
        FailRow(why, &base_row);
        for (std::size_t v = 1; v < num_variants && progress; ++v) {
          progress->Skip();
        }
        if (progress != nullptr) progress->Report(base_row);
        rows.push_back(std::move(base_row));
        continue;
      }
      for (std::size_t v = 0; v < num_variants; ++v) {
        const OptionsVariant* variant =
            experiment.variants.empty() ? nullptr : &experiment.variants[v];
        RunRow row = base_row;
        if (variant != nullptr) row.variant = variant->name;
        SolveAndEvaluate(dataset, base, variant, experiment.keep_solutions,
                         &row);
        if (row.status == kNotApplicable) {
          if (progress != nullptr) progress->Skip();
          continue;
        }
        if (progress != nullptr) progress->Report(row);
        rows.push_back(std::move(row));
      }
    }
  }
  return rows;
}

bool TranslationErrors(const std::vector<TimedPose>& ground_truth,
                       const std::vector<TimedPose>& estimate,
                       std::vector<double>* errors, std::string* error) {
  std::vector<double> times;
  times.reserve(ground_truth.size());
  for (const TimedPose& p : ground_truth) times.push_back(p.t);
  std::vector<TimedPose> poses;
  if (!InterpolateTrajectory(estimate, times, &poses, error, "ground-truth")) {
    return false;
  }
  errors->resize(poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    (*errors)[i] = std::hypot(poses[i].x - ground_truth[i].x,
                              poses[i].y - ground_truth[i].y);
  }
  return true;
}

Spread SpreadOf(const std::vector<double>& values) {
  std::vector<double> finite;
  for (double v : values) {
    if (std::isfinite(v)) finite.push_back(v);
  }
  Spread spread;
  spread.count = static_cast<int>(finite.size());
  if (finite.empty()) return spread;
  spread.median = Median(finite);
  double sum = 0.0;
  for (double v : finite) sum += v;
  spread.mean = sum / finite.size();
  return spread;
}

std::vector<SeedAggregate> AggregateOverSeeds(const std::vector<RunRow>& rows) {
  using Key = std::tuple<std::string, std::string, int, double, std::string,
                         std::string>;
  std::map<Key, std::size_t> index;
  std::vector<SeedAggregate> aggregates;
  std::vector<std::vector<const RunRow*>> members;
  for (const RunRow& row : rows) {
    const Key key{row.method, row.family,     row.landmarks,
                  row.noise,  row.noise_unit, row.variant};
    auto [it, inserted] = index.emplace(key, aggregates.size());
    if (inserted) {
      SeedAggregate a;
      a.method = row.method;
      a.family = row.family;
      a.kind = row.kind;
      a.landmarks = row.landmarks;
      a.noise = row.noise;
      a.noise_unit = row.noise_unit;
      a.variant = row.variant;
      aggregates.push_back(a);
      members.emplace_back();
    }
    members[it->second].push_back(&row);
  }
  for (std::size_t i = 0; i < aggregates.size(); ++i) {
    SeedAggregate& a = aggregates[i];
    auto spread = [&](double RunRow::*field) {
      std::vector<double> values;
      for (const RunRow* row : members[i]) {
        if (row->ok()) values.push_back(row->*field);
      }
      return SpreadOf(values);
    };
    a.runs = static_cast<int>(members[i].size());
    for (const RunRow* row : members[i]) a.failed += row->ok() ? 0 : 1;
    a.ape_translation = spread(&RunRow::ape_translation);
    a.ape_rotation_deg = spread(&RunRow::ape_rotation_deg);
    a.rpe_translation = spread(&RunRow::rpe_translation);
    a.rpe_rotation_deg = spread(&RunRow::rpe_rotation_deg);
    a.landmark_rms = spread(&RunRow::landmark_rms);
    a.solve_seconds = spread(&RunRow::solve_seconds);
    // Dead reckoning does not depend on the solve: over every run made.
    std::vector<double> dead_reckoning;
    for (const RunRow* row : members[i]) {
      dead_reckoning.push_back(row->dead_reckoning_ape_translation);
    }
    a.dead_reckoning_ape_translation = SpreadOf(dead_reckoning);
  }
  return aggregates;
}

// ---------------------------------------------------------------------------
// Tables.

std::string CsvField(const std::string& field) {
  if (field.find_first_of(",\"\r\n") == std::string::npos) return field;
  return "\"" + Replace(field, "\"", "\"\"") + "\"";
}

std::string ToCsv(const Table& table) {
  std::string text;
  auto line = [&](const std::vector<std::string>& cells) {
    for (std::size_t i = 0; i < cells.size(); ++i) {
      text += (i > 0 ? "," : "") + CsvField(cells[i]);
    }
    text += "\n";
  };
  line(table.header);
  for (const auto& row : table.rows) line(row);
  return text;
}

std::string ToMarkdown(const Table& table) {
  std::string text;
  auto line = [&](const std::vector<std::string>& cells) {
    text += "|";
    for (const std::string& cell : cells) {
      std::string escaped = Replace(cell, "|", "\\|");
      escaped = Replace(escaped, "\n", " ");
      text += " " + (escaped.empty() ? std::string("-") : escaped) + " |";
    }
    text += "\n";
  };
  line(table.header);
  text += "|";
  for (std::size_t i = 0; i < table.header.size(); ++i) text += " --- |";
  text += "\n";
  for (const auto& row : table.rows) line(row);
  return text;
}

std::string FormatSignificant(double value) {
  if (!std::isfinite(value)) return "-";
  char buffer[64];
  const double magnitude = std::fabs(value);
  if (magnitude >= 1000.0) {
    std::snprintf(buffer, sizeof(buffer), "%.0f", value);
  } else if (magnitude == 0.0) {
    return "0";
  } else {
    const int decimals =
        std::max(0, 2 - static_cast<int>(std::floor(std::log10(magnitude))));
    std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, value);
  }
  return buffer;
}

std::string FormatCsvNumber(double value) {
  return std::isfinite(value) ? FormatNumber(value) : "";
}

Table RunsCsvTable(const std::vector<RunRow>& rows) {
  Table table;
  table.header = {"experiment",     "method",
                  "dataset",        "family",
                  "kind",           "landmarks",
                  "noise",          "noise_unit",
                  "seed",           "variant",
                  "linear_solver",  "features",
                  "num_features",   "status",
                  "ape_trans_m",    "ape_rot_deg",
                  "rpe_trans_m",    "rpe_rot_deg",
                  "landmark_rms_m", "dead_reckoning_ape_trans_m",
                  "iterations",     "final_cost",
                  "solve_seconds"};
  for (const RunRow& r : rows) {
    table.rows.push_back({r.experiment,
                          r.method,
                          r.dataset,
                          r.family,
                          r.kind,
                          LandmarksCell(r.landmarks),
                          r.noise != 0.0 ? FormatCsvNumber(r.noise) : "",
                          r.noise_unit,
                          SeedCell(r.seed),
                          r.variant,
                          r.linear_solver,
                          r.features,
                          r.num_features > 0 ? Int(r.num_features) : "",
                          r.status,
                          FormatCsvNumber(r.ape_translation),
                          FormatCsvNumber(r.ape_rotation_deg),
                          FormatCsvNumber(r.rpe_translation),
                          FormatCsvNumber(r.rpe_rotation_deg),
                          FormatCsvNumber(r.landmark_rms),
                          FormatCsvNumber(r.dead_reckoning_ape_translation),
                          r.ok() ? Int(r.iterations) : "",
                          FormatCsvNumber(r.final_cost),
                          FormatCsvNumber(r.solve_seconds)});
  }
  return table;
}

Table Table1CsvTable(const std::vector<SeedAggregate>& aggregates) {
  Table table;
  table.header = {"method", "family",     "kind", "landmarks",
                  "noise",  "noise_unit", "runs", "failed"};
  const std::vector<std::string> metrics = {
      "ape_trans_m",  "ape_rot_deg",    "rpe_trans_m",
      "rpe_rot_deg",  "landmark_rms_m", "dead_reckoning_ape_trans_m",
      "solve_seconds"};
  for (const std::string& m : metrics) {
    table.header.push_back(m + "_median");
    table.header.push_back(m + "_mean");
  }
  for (const SeedAggregate& a : aggregates) {
    std::vector<std::string> row = {a.method,
                                    a.family,
                                    a.kind,
                                    LandmarksCell(a.landmarks),
                                    FormatCsvNumber(a.noise),
                                    a.noise_unit,
                                    Int(a.runs),
                                    Int(a.failed)};
    for (const Spread* s :
         {&a.ape_translation, &a.ape_rotation_deg, &a.rpe_translation,
          &a.rpe_rotation_deg, &a.landmark_rms,
          &a.dead_reckoning_ape_translation, &a.solve_seconds}) {
      row.push_back(FormatCsvNumber(s->median));
      row.push_back(FormatCsvNumber(s->mean));
    }
    table.rows.push_back(row);
  }
  return table;
}

Table Table1MarkdownTable(const std::vector<SeedAggregate>& aggregates) {
  Table table;
  table.header = {"method",
                  "kind",
                  "landmarks",
                  "noise",
                  "ok / runs",
                  "APE-trans [m] median / mean",
                  "APE-rot [deg] median / mean",
                  "RPE-trans [m] median / mean",
                  "RPE-rot [deg] median / mean",
                  "landmarks [m] median / mean",
                  "dead reckoning APE-trans [m] median",
                  "time [s] mean"};
  for (const SeedAggregate& a : aggregates) {
    table.rows.push_back(
        {a.method, a.kind, LandmarksCell(a.landmarks),
         NoiseLabel(a.noise, a.noise_unit),
         Int(a.runs - a.failed) + " / " + Int(a.runs),
         MedianMean(a.ape_translation), MedianMean(a.ape_rotation_deg),
         MedianMean(a.rpe_translation), MedianMean(a.rpe_rotation_deg),
         MedianMean(a.landmark_rms),
         FormatSignificant(a.dead_reckoning_ape_translation.median),
         FormatSignificant(a.solve_seconds.mean)});
  }
  return table;
}

Table Table2CsvTable(const std::vector<RunRow>& rows) {
  Table table;
  table.header = {"method",
                  "dataset",
                  "family",
                  "noise",
                  "noise_unit",
                  "ape_trans_m",
                  "ape_rot_deg",
                  "rpe_trans_m",
                  "rpe_rot_deg",
                  "landmark_rms_m",
                  "dead_reckoning_ape_trans_m",
                  "iterations",
                  "final_cost",
                  "solve_seconds",
                  "status"};
  for (const RunRow& r : rows) {
    table.rows.push_back(
        {r.method, r.dataset, r.family,
         r.noise != 0.0 ? FormatCsvNumber(r.noise) : "", r.noise_unit,
         FormatCsvNumber(r.ape_translation),
         FormatCsvNumber(r.ape_rotation_deg),
         FormatCsvNumber(r.rpe_translation),
         FormatCsvNumber(r.rpe_rotation_deg), FormatCsvNumber(r.landmark_rms),
         FormatCsvNumber(r.dead_reckoning_ape_translation),
         r.ok() ? Int(r.iterations) : "", FormatCsvNumber(r.final_cost),
         FormatCsvNumber(r.solve_seconds), r.status});
  }
  return table;
}

Table Table2MarkdownTable(const std::vector<RunRow>& rows) {
  Table table;
  table.header = {"method",        "dataset",
                  "family",        "noise",
                  "APE-trans [m]", "APE-rot [deg]",
                  "RPE-trans [m]", "RPE-rot [deg]",
                  "landmarks [m]", "dead reckoning APE-trans [m]",
                  "iterations",    "final cost",
                  "time [s]",      "status"};
  for (const RunRow& r : rows) {
    table.rows.push_back(
        {r.method, r.dataset, r.family, NoiseLabel(r.noise, r.noise_unit),
         FormatSignificant(r.ape_translation),
         FormatSignificant(r.ape_rotation_deg),
         FormatSignificant(r.rpe_translation),
         FormatSignificant(r.rpe_rotation_deg),
         FormatSignificant(r.landmark_rms),
         FormatSignificant(r.dead_reckoning_ape_translation),
         r.ok() ? Int(r.iterations) : "-", FormatSignificant(r.final_cost),
         FormatSignificant(r.solve_seconds), r.ok() ? "ok" : "failed"});
  }
  return table;
}

Table SolversCsvTable(const std::vector<RunRow>& rows) {
  Table table;
  table.header = {"method",     "dataset",      "linear_solver",
                  "features",   "num_features", "solve_seconds",
                  "iterations", "final_cost",   "ape_trans_m",
                  "status"};
  for (const RunRow& r : rows) {
    table.rows.push_back({r.method, r.dataset, r.linear_solver, r.features,
                          r.num_features > 0 ? Int(r.num_features) : "",
                          FormatCsvNumber(r.solve_seconds),
                          r.ok() ? Int(r.iterations) : "",
                          FormatCsvNumber(r.final_cost),
                          FormatCsvNumber(r.ape_translation), r.status});
  }
  return table;
}

Table SolversMarkdownTable(const std::vector<RunRow>& rows) {
  Table table;
  table.header = {
      "method",   "dataset",    "linear solver", "features",      "D",
      "time [s]", "iterations", "final cost",    "APE-trans [m]", "status"};
  for (const RunRow& r : rows) {
    table.rows.push_back(
        {r.method, r.dataset, r.linear_solver, r.features,
         r.num_features > 0 ? Int(r.num_features) : "-",
         FormatSignificant(r.solve_seconds), r.ok() ? Int(r.iterations) : "-",
         FormatSignificant(r.final_cost), FormatSignificant(r.ape_translation),
         r.ok() ? "ok" : "failed"});
  }
  return table;
}

// ---------------------------------------------------------------------------
// The whole grid.

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
  // The flag's value as given, comma-separated.
  std::string experiment_list;
  for (const std::string& name : config.experiments) {
    experiment_list += (experiment_list.empty() ? "" : ",") + name;
  }
  const std::string allowed =
      "a comma list of " + JoinAlternatives(AllExperimentNames());
  std::set<std::string> selected;
  for (const std::string& name : config.experiments) {
    const auto& all = AllExperimentNames();
    if (std::find(all.begin(), all.end(), name) == all.end()) {
      *error = OptionError("experiments", experiment_list,
                           "unknown experiment " + name, allowed);
      return false;
    }
    selected.insert(name);
  }
  if (selected.empty()) {
    *error =
        OptionError("experiments", experiment_list, "no experiment", allowed);
    return false;
  }

  // Build every grid first: the progress lines count against the total.
  std::vector<Experiment> experiments;
  DatasetSpec figure2_spec;
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
      std::vector<DatasetSpec> candidates =
          Table2Datasets(config.quick, config.data_dir, config.shared_dir);
      for (const DatasetSpec& s : Table1Datasets(config.quick)) {
        candidates.push_back(s);
      }
      std::string names;
      for (const DatasetSpec& s : candidates) {
        if (s.name == config.figure2_dataset) figure2_spec = s;
        if (names.size() < 400) names += (names.empty() ? "" : ", ") + s.name;
      }
      if (figure2_spec.name.empty()) {
        *error = OptionError("figure2_dataset", config.figure2_dataset,
                             "not a dataset of the grids", names);
        return false;
      }
      experiment.datasets = {figure2_spec};
      experiment.keep_solutions = true;
    } else {
      experiment.datasets = SolverDatasets(config.quick, config.data_dir);
      experiment.variants = SolverVariants(config.quick);
    }
    experiments.push_back(experiment);
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
  const std::string& out = config.out_dir;
  const std::string methods = MethodList(config.methods);
  Progress progress(config.progress, total);
  for (const Experiment& experiment : experiments) {
    std::vector<RunRow> rows =
        RunExperiment(experiment, config.methods, options_callback, &progress);
    const std::string& name = experiment.name;
    bool written = true;
    if (name == "table1") {
      const std::vector<SeedAggregate> aggregates = AggregateOverSeeds(rows);
      written =
          WriteText(out + "/table1.csv", ToCsv(Table1CsvTable(aggregates)),
                    summary, error) &&
          WriteText(
              out + "/table1.md",
              MarkdownDocument(
                  "Table I: simulated sets (paper protocol)",
                  "Methods: " + methods +
                      ". 300 poses at 1 s, 4 landmarks observed per pose, "
                      "sigma_r = 1 m, sigma_b = 2 deg, odometry 0.05 m / "
                      "0.01 rad; median / mean over seeds of the RMS errors "
                      "(APE without alignment). Time: the whole solve.",
                  Table1MarkdownTable(aggregates), rows),
              summary, error);
    } else if (name == "figure1") {
      written =
          WriteFigure1(rows, config.methods, config.quick, out, summary, error);
    } else if (name == "table2") {
      written =
          WriteText(out + "/table2.csv", ToCsv(Table2CsvTable(rows)), summary,
                    error) &&
          WriteText(out + "/table2.md",
                    MarkdownDocument(
                        "Table II: real data and KITTI-scale bearing-only",
                        "Methods: " + methods +
                            ". CMU Plaza 1 (range-only), UTIAS MRCLAM 6 "
                            "(range-bearing) and the simulated KITTI-scale "
                            "bearing-only set with bearing sigma 1, 3 and 5 "
                            "deg" +
                            (config.quick ? " (quick: 600 poses)" : "") +
                            "; RMS errors, APE without alignment.",
                        Table2MarkdownTable(rows), rows),
                    summary, error);
    } else if (name == "figure2") {
      written = WriteFigure2(figure2_spec, rows, out, summary, error);
    } else {
      written =
          WriteText(out + "/solvers.csv", ToCsv(SolversCsvTable(rows)), summary,
                    error) &&
          WriteText(out + "/solvers.md",
                    MarkdownDocument(
                        "Linear solvers and feature families",
                        "Methods: " + methods +
                            ", each with its config and the linear solver, "
                            "feature family and D (features per coordinate) "
                            "overridden. Time: the whole solve.",
                        SolversMarkdownTable(rows), rows),
                    summary, error);
    }
    if (!written) return false;
    for (RunRow& row : WithoutSolutions(std::move(rows))) {
      summary->rows.push_back(std::move(row));
    }
    // Rewritten after every experiment, so a long grid stopped midway keeps
    // the rows it has.
    if (!WriteText(out + "/runs.csv", ToCsv(RunsCsvTable(summary->rows)),
                   summary, error)) {
      return false;
    }
  }
  return true;
}

}  // namespace rff
