#include "rff_ceres/experiment/figures.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <utility>

#include "rff_ceres/experiment/aggregation.h"
#include "rff_ceres/metrics.h"

namespace rff {
namespace {

// Plotted lines are thinned to at most this many points (the SVG stays
// small; the eye cannot tell more apart at 720 pixels).
constexpr std::size_t kMaxPlotPoints = 2000;

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

// Figure 2's map: ground truth, dead reckoning and each successful
// estimate, trajectories and landmarks.
Plot Figure2MapPlot(const std::string& name, const Dataset& dataset,
                    const std::vector<TimedPose>& dead_reckoning,
                    const std::vector<RunRow>& rows) {
  Plot map;
  map.title = "Estimated vs true trajectory and landmarks: " + name;
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
  return map;
}

// Figure 2's error curves: dead reckoning's and each successful estimate's
// translation error against the time since the start.
Plot Figure2ErrorPlot(const std::string& name, const Dataset& dataset,
                      const std::vector<TimedPose>& dead_reckoning,
                      const std::vector<RunRow>& rows) {
  Plot ape;
  ape.title = "Translation error along the trajectory: " + name;
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
  return ape;
}

}  // namespace

std::vector<NamedPlot> Figure1Plots(const std::vector<RunRow>& rows,
                                    const std::vector<Method>& methods,
                                    bool quick) {
  const std::vector<SeedAggregate> aggregates = AggregateOverSeeds(rows);
  const int noise_landmarks = Figure1NoiseLandmarks(quick);
  int seeds = 0;
  for (const SeedAggregate& a : aggregates) seeds = std::max(seeds, a.runs);

  Plot noise = Figure1Plot(
      aggregates, methods,
      [&](const SeedAggregate& a) { return a.landmarks == noise_landmarks; },
      [](const SeedAggregate& a) { return a.noise; });
  noise.title = "APE-trans vs observation noise (" +
                std::to_string(noise_landmarks) + " landmarks, " +
                std::to_string(seeds) + " seeds)";
  noise.x_label =
      "observation noise [multiple of sigma_r = 1 m, sigma_b = 2 deg]";
  Plot landmarks = Figure1Plot(
      aggregates, methods,
      [](const SeedAggregate& a) { return a.noise == 1.0; },
      [](const SeedAggregate& a) { return a.landmarks; });
  landmarks.title = "APE-trans vs number of landmarks (paper noise, " +
                    std::to_string(seeds) + " seeds)";
  landmarks.x_label = "landmarks [count]";
  return {{"figure1_noise.svg", noise}, {"figure1_landmarks.svg", landmarks}};
}

std::vector<NamedPlot> Figure2Plots(const DatasetSpec& spec,
                                    const std::vector<RunRow>& rows) {
  Dataset dataset;
  std::string make_error;
  if (!spec.make(&dataset, &make_error)) dataset = Dataset();
  std::vector<TimedPose> dead_reckoning;
  DeadReckoningApe(dataset, &dead_reckoning);
  return {{"figure2_trajectory.svg",
           Figure2MapPlot(spec.name, dataset, dead_reckoning, rows)},
          {"figure2_ape.svg",
           Figure2ErrorPlot(spec.name, dataset, dead_reckoning, rows)}};
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

}  // namespace rff
