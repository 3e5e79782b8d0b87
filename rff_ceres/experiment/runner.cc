#include "rff_ceres/experiment/runner.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <utility>

#include "rff_ceres/dead_reckoning.h"
#include "rff_ceres/metrics.h"
#include "rff_ceres/priors/trajectory_prior.h"

namespace rff {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;
constexpr double kNaN = RunRow::kNone;

// Status of a run whose variant does not apply; such rows are dropped.
constexpr char kNotApplicable[] = "not applicable";

double ValueOr(const ErrorSummary& summary, double scale) {
  return summary.available ? summary.rms * scale : kNaN;
}

void FailRow(const std::string& why, RunRow* row) {
  row->status = "failed: " + why;
  row->ape_translation = row->ape_rotation_deg = kNaN;
  row->rpe_translation = row->rpe_rotation_deg = kNaN;
  row->landmark_rms = kNaN;
  row->trajectory.clear();
  row->estimated_landmarks.clear();
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
  const TrajectoryPrior* prior = FindPrior(options.prior);
  const bool has_features = prior != nullptr && prior->has_features();
  if (has_features) {
    row->features = options.features.family;
    row->num_features = options.features.num_position_features;
  } else {
    // A prior without features: its states are the model.
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
  if (has_features) {
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

}  // namespace

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
    // Each method's options once per dataset, checked before the dataset is
    // made or read; a method without them is one failed row for all the
    // variants.
    std::vector<SlamOptions> method_options(methods.size());
    std::vector<std::string> option_errors(methods.size());
    bool any_options = false;
    for (std::size_t m = 0; m < methods.size(); ++m) {
      std::string& why = option_errors[m];
      if (!options_callback(methods[m].name, spec.family, &method_options[m],
                            &why)) {
        if (why.empty()) why = "no options for method " + methods[m].name;
      } else {
        why.clear();
        any_options = true;
      }
    }
    Dataset dataset;
    std::string dataset_error;
    bool made = any_options && spec.make && spec.make(&dataset, &dataset_error);
    if (!spec.make) dataset_error = "no way to make the dataset";
    if (made && dataset.ground_truth.empty()) {
      made = false;
      dataset_error = "no ground truth (GT_POSE) to evaluate against";
    }
    const double dead_reckoning_ape =
        made ? DeadReckoningApe(dataset, nullptr) : kNaN;

    const std::size_t num_variants =
        std::max<std::size_t>(1, experiment.variants.size());
    for (std::size_t m = 0; m < methods.size(); ++m) {
      const Method& method = methods[m];
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

      const SlamOptions& base = method_options[m];
      std::string why = option_errors[m];
      if (why.empty() && !made) {
        why = "dataset " + spec.name + ": " + dataset_error;
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

}  // namespace rff
