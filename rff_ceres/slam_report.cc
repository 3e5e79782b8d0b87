#include "rff_ceres/slam_report.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "ceres/types.h"
#include "rff_ceres/io/landmarks_io.h"
#include "rff_ceres/io/output_file.h"
#include "rff_ceres/io/pose_covariance_io.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/io/tum_io.h"
#include "rff_ceres/priors/trajectory_prior.h"

namespace rff {
namespace {

// Mean and max of the incremental update times.
void UpdateTimes(const SlamResult& result, double* mean, double* max) {
  *mean = 0.0;
  *max = 0.0;
  for (const IncrementalUpdate& u : result.updates) {
    *mean += u.seconds;
    *max = std::max(*max, u.seconds);
  }
  if (!result.updates.empty()) *mean /= result.updates.size();
}

// ["a", "b"]
std::string JsonStringArray(const std::vector<std::string>& items) {
  std::string out = "[";
  for (std::size_t i = 0; i < items.size(); ++i) {
    out += (i == 0 ? "" : ", ") + JsonString(items[i]);
  }
  return out + "]";
}

// [-4678.9, -4645.1, ...]
std::string NumberList(const std::vector<double>& numbers) {
  std::string out = "[";
  for (std::size_t i = 0; i < numbers.size(); ++i) {
    out += (i == 0 ? "" : ", ") + FormatNumber(numbers[i]);
  }
  return out + "]";
}

// [{"kind": "range", "batches": 271, "ratio": 9.7, "drifts": true}, ...]
std::string DriftJson(const std::vector<ResidualDrift>& drifts) {
  std::string out = "[";
  for (std::size_t i = 0; i < drifts.size(); ++i) {
    const ResidualDrift& d = drifts[i];
    out += std::string(i == 0 ? "" : ", ") +
           "{\"kind\": " + JsonString(d.kind) +
           ", \"batches\": " + std::to_string(d.batches) +
           ", \"ratio\": " + FormatNumber(d.ratio) +
           ", \"drifts\": " + (d.drifts ? "true" : "false") + "}";
  }
  return out + "]";
}

// What a Markov prior's learning went back to where it kept its Q_c.
const char* KeptAs(const SlamResult& result, bool markov) {
  return markov && result.qc_from_odometry.windows > 0
             ? " kept at the odometry's: "
             : " kept as given: ";
}

// The Q_c the WNOA rounds started from, or null where not the odometry's.
std::string QcFromOdometryJson(const SlamResult& result) {
  const OdometryDiffusion& d = result.qc_from_odometry;
  if (d.windows == 0) return "null";
  return "{\"position\": " + FormatNumber(d.position_qc) +
         ", \"heading\": " + FormatNumber(d.heading_qc) +
         ", \"window_seconds\": " + FormatNumber(d.window_seconds) +
         ", \"windows\": " + std::to_string(d.windows) + "}";
}

}  // namespace

void PrintSlamSummary(const SlamOptions& options, const SlamResult& result,
                      std::ostream* out) {
  const ceres::Solver::Summary& s = result.summary;
  const TrajectoryPrior& prior = PriorOf(options);
  prior.PrintModel(result, out);
  if (result.learning_rounds > 0) {
    *out << "  scales       " << prior.scales_name();
    if (result.prior_scales_kept.empty()) {
      *out << " learned by variance components, ";
    } else {
      // A feature prior's rounds learn no noise: its mean's solve did.
      *out << KeptAs(result, !prior.has_features()) << result.prior_scales_kept
           << (prior.has_features() ? ", "
               : result.noise_learned.empty()
                   ? "; no noise factor learned either, "
                   : "; the noise factors learned by variance components, ");
    }
    *out << result.learning_rounds
         << (result.learning_rounds == 1 ? " round" : " rounds")
         << (result.learning_converged ? ""
             : result.learning_evidence_fell
                 ? " (ended at the round before the Laplace evidence fell)"
             : !result.scales_not_learned.empty()
                 ? " (stopped short: see the warning)"
                 : " (stopped at the round cap, the factors still moving)");
    const OdometryDiffusion& odometry = result.qc_from_odometry;
    if (prior.has_features()) {
      // The WNOA mean's start is its own solve's.
    } else if (odometry.windows > 0 && result.prior_scales_kept.empty()) {
      *out << "; from the odometry's " << odometry.position_qc << " (x, y), "
           << odometry.heading_qc << " (theta)";
    } else if (!result.qc_start_kept.empty()) {
      *out << "; started as given: " << result.qc_start_kept;
    }
    const char* separator = "; at zero, the data leave no variance to: ";
    for (const std::string& group : result.scales_at_boundary) {
      *out << separator << group;
      separator = ", ";
    }
    *out << "\n";
  }
  if (!result.heading_windings_unwound.empty()) {
    *out << "  heading      the solve wound whole turns against the "
            "odometry (";
    const char* separator = "";
    for (const std::string& winding : result.heading_windings_unwound) {
      *out << separator << winding;
      separator = "; ";
    }
    *out << "): solved again from it unwound\n";
  }
  if (!result.covariance_truncation.empty()) {
    *out << "  covariance   the basis's truncation term: "
         << result.covariance_truncation << "\n";
  }
  for (const ResidualDrift& drift : result.residual_drift) {
    if (!drift.drifts) continue;
    *out << "  covariance   optimistic: the " << drift.kind
         << " residuals drift together, their sums over " << kDriftBatch
         << " sightings of a landmark varying " << drift.ratio
         << " times as much as white errors' (the covariances assume white "
            "errors)\n";
  }
  if (options.output.covariance) {
    for (const std::string& kind : result.noise_unsettled) {
      *out << "  covariance   optimistic: the " << kind
           << " sigma was still falling when the learning rounds reached "
              "their cap ("
           << NoiseScale(result.noise, DataRowGroup(kind, 0))
           << " of the stated one): the evidence keeps rewarding a closer "
              "fit of these rows, so the sigma, and the covariances that "
              "follow it, sit where the rounds stopped\n";
    }
  }
  if (!result.noise_learned.empty()) {
    *out << "  noise        sigmas learned as the stated ones times:";
    const char* separator = " ";
    for (const std::string& kind : result.noise_learned) {
      *out << separator << kind << " "
           << NoiseScale(result.noise, DataRowGroup(kind, 0));
      separator = ", ";
    }
    // The RFF prior's sigmas come from its WNOA mean's rounds.
    if (result.noise_evidence_fell && !result.learning_evidence_fell) {
      *out << " (the WNOA mean's rounds ended at the round before the "
              "Laplace evidence fell)";
    }
    *out << "\n";
  }
  for (const std::string& kind : result.noise_kept) {
    *out << "  noise        " << kind
         << " sigma kept as stated: learning ran it towards 0, faster "
            "each round\n";
  }
  if (!result.scales_not_learned.empty()) {
    *out << "  warning: learning the scales stopped after "
         << result.learning_rounds << " rounds: " << result.scales_not_learned
         << "\n";
  }
  *out << "  problem      " << s.num_residual_blocks << " residual blocks, "
       << s.num_parameters << " parameters\n"
       << "  solver       " << options.solver.linear_solver << " -> "
       << result.linear_solver << " (" << result.linear_solver_reason << "), "
       << result.total_iterations << " iterations, "
       << ceres::TerminationTypeToString(s.termination_type) << "\n"
       << "  cost         " << s.initial_cost << " -> " << s.final_cost << "\n"
       << "  time         " << s.total_time_in_seconds
       << " s in the final solve, " << result.solve_seconds << " s total\n";
  *out << "  start        initial trajectory from the "
       << result.initial_trajectory;
  if (result.start_heading.resolved) {
    *out << "; start heading unknown, resolved to "
         << result.start_heading.heading << " rad (prior "
         << result.start_heading.prior_heading << ")";
  }
  if (!result.start_prior_scales_kept.empty()) {
    *out << "; its Q_c" << KeptAs(result, /*markov=*/true)
         << result.start_prior_scales_kept;
  }
  *out << "\n";
  const bool depth = result.range_bearing_ranges == "depth";
  if (depth) {
    *out << "  ranges       RANGE_BEARING ranges read as depths along the "
            "heading";
    if (result.range_reading_judged) {
      *out << " (auto: the first solve's range residuals follow -d (1 - cos "
              "b), slope "
           << result.depth_evidence.slope
           << ", t = " << result.depth_evidence.t_statistic << " > "
           << kMinDepthEvidence << ")";
    }
    *out << "\n";
  } else if (!result.range_reading_note.empty()) {
    *out << "  ranges       RANGE_BEARING ranges read as distances, "
         << result.range_reading_note << "\n";
  } else if (result.depth_rejected) {
    *out << "  ranges       RANGE_BEARING ranges read as distances: their "
            "residuals follow -d (1 - cos b) (t = "
         << result.depth_evidence.t_statistic
         << "), but read as depths the first solve's cost was no lower\n";
  }
  if (result.range_calibrated) {
    *out << "  range model  " << result.range_calibration[0]
         << (depth ? " * depth + " : " * distance + ")
         << result.range_calibration[1] << " m\n";
  }
  if (options.problem.odometry_calibration.estimate &&
      options.problem.use_odometry) {
    *out << "  odometry     scale " << result.odometry_calibration[0]
         << ", turn scale " << result.odometry_calibration[1] << "\n";
  }
  if (!result.updates.empty()) {
    double mean, max;
    UpdateTimes(result, &mean, &max);
    *out << "  incremental  " << result.updates.size() << " updates (every "
         << options.incremental.every << " measurements), " << mean * 1e3
         << " ms mean, " << max * 1e3 << " ms max per update";
    if (result.updates.back().folded_residuals > 0) {
      *out << "; " << result.updates.back().folded_residuals
           << " residuals of frozen blocks folded into a prior on the blocks "
              "they move";
    }
    *out << "\n";
  }
  *out << "  losses       observations " << options.problem.loss.name;
  if (result.loss != options.problem.loss.name) *out << " -> " << result.loss;
  *out << ", odometry " << options.problem.odometry_loss.name;
  if (result.odometry_loss != options.problem.odometry_loss.name) {
    *out << " -> " << result.odometry_loss;
  }
  *out << "\n  residuals   ";
  for (const ResidualKindQuality& q : result.quality.kinds) {
    *out << " " << q.kind << " chi2/n " << q.chi2_per_residual << " (inliers "
         << q.inlier_chi2_per_residual << ", " << 100.0 * q.share_beyond_3_sigma
         << "% > 3 sigma, largest " << q.largest << ");";
  }
  *out << "\n  quality      " << QualityLine(result.quality) << "\n";
  if (!result.converged) {
    *out << "  warning: the solver stopped before convergence: " << s.message
         << "\n";
  }
}

void WriteSummaryJson(const SlamOptions& options, const SlamResult& result,
                      std::ostream* output) {
  std::ostream& out = *output;
  const ceres::Solver::Summary& s = result.summary;
  const FeatureTrajectoryOptions& t = result.trajectory_options;
  double update_mean, update_max;
  UpdateTimes(result, &update_mean, &update_max);
  out << "{\n"
      << "  \"prior\": " << JsonString(options.prior) << ",\n"
      << "  \"prior_mean\": " << JsonString(result.prior_mean) << ",\n"
      << "  \"mean_seconds\": " << FormatNumber(result.mean_seconds) << ",\n"
      << "  \"kernel\": " << JsonString(t.position_kernel.name) << ",\n"
      << "  \"heading_kernel\": " << JsonString(t.heading_kernel.name) << ",\n"
      << "  \"lengthscale\": " << FormatNumber(t.position_kernel.lengthscale)
      << ",\n"
      << "  \"kernel_variance\": " << FormatNumber(t.position_kernel.variance)
      << ",\n"
      << "  \"heading_lengthscale\": "
      << FormatNumber(t.heading_kernel.lengthscale) << ",\n"
      << "  \"heading_kernel_variance\": "
      << FormatNumber(t.heading_kernel.variance) << ",\n"
      << "  \"segment_length\": " << FormatNumber(t.segment_length) << ",\n"
      << "  \"segment_overlap\": " << FormatNumber(t.segment_overlap) << ",\n"
      << "  \"learn_hyperparameters\": " << (result.learned ? "true" : "false")
      << ",\n"
      << "  \"log_evidence\": " << FormatNumber(result.learning.log_evidence)
      << ",\n"
      << "  \"learning_evaluations\": " << result.learning.evaluations << ",\n"
      << "  \"learned_level\": [" << FormatNumber(result.learning.level.x())
      << ", " << FormatNumber(result.learning.level.y()) << ", "
      << FormatNumber(result.learning.level.z()) << "],\n"
      << "  \"learning_rounds\": " << result.learning_rounds << ",\n"
      << "  \"learning_converged\": "
      << (result.learning_converged ? "true" : "false") << ",\n"
      << "  \"learning_evidence_fell\": "
      << (result.learning_evidence_fell ? "true" : "false") << ",\n"
      << "  \"model_log_evidence\": "
      << (std::isfinite(result.model_log_evidence)
              ? FormatNumber(result.model_log_evidence)
              : "null")
      << ",\n"
      << "  \"scale_log_evidence\": " << NumberList(result.scale_log_evidence)
      << ",\n"
      << "  \"noise_evidence_fell\": "
      << (result.noise_evidence_fell ? "true" : "false") << ",\n"
      << "  \"noise_unsettled\": " << JsonStringArray(result.noise_unsettled)
      << ",\n"
      << "  \"scales_not_learned\": " << JsonString(result.scales_not_learned)
      << ",\n"
      << "  \"prior_scales_kept\": " << JsonString(result.prior_scales_kept)
      << ",\n"
      << "  \"start_prior_scales_kept\": "
      << JsonString(result.start_prior_scales_kept) << ",\n"
      << "  \"qc_from_odometry\": " << QcFromOdometryJson(result) << ",\n"
      << "  \"qc_start_kept\": " << JsonString(result.qc_start_kept) << ",\n"
      << "  \"prior_scale_factors\": ["
      << FormatNumber(result.prior_scale_factors[0]) << ", "
      << FormatNumber(result.prior_scale_factors[1]) << "],\n"
      << "  \"noise_scale_range\": " << FormatNumber(result.noise.range)
      << ",\n"
      << "  \"noise_scale_bearing\": " << FormatNumber(result.noise.bearing)
      << ",\n"
      << "  \"noise_scale_odometry\": " << FormatNumber(result.noise.odometry)
      << ",\n"
      << "  \"scales_at_boundary\": "
      << JsonStringArray(result.scales_at_boundary) << ",\n"
      << "  \"heading_windings_unwound\": "
      << JsonStringArray(result.heading_windings_unwound) << ",\n"
      << "  \"heading_windings\": " << JsonStringArray(result.heading_windings)
      << ",\n"
      << "  \"covariance_truncation\": "
      << JsonString(result.covariance_truncation) << ",\n"
      << "  \"residual_drift\": " << DriftJson(result.residual_drift) << ",\n"
      << "  \"noise_scales_kept\": " << JsonStringArray(result.noise_kept)
      << ",\n"
      << "  \"noise_scales_learned\": " << JsonStringArray(result.noise_learned)
      << ",\n"
      << "  \"learning_seconds\": " << FormatNumber(result.learning.seconds)
      << ",\n"
      << "  \"features\": " << JsonString(t.family) << ",\n"
      << "  \"num_features\": " << t.num_position_features << ",\n"
      << "  \"num_heading_features\": " << t.num_heading_features << ",\n"
      << "  \"seed\": " << t.seed << ",\n"
      << "  \"wnoa_position_qc\": "
      << FormatNumber(result.wnoa_options.position_qc) << ",\n"
      << "  \"wnoa_heading_qc\": "
      << FormatNumber(result.wnoa_options.heading_qc) << ",\n"
      << "  \"wnoj_position_qc\": "
      << FormatNumber(result.wnoj_options.position_qc) << ",\n"
      << "  \"wnoj_heading_qc\": "
      << FormatNumber(result.wnoj_options.heading_qc) << ",\n"
      << "  \"loss\": " << JsonString(options.problem.loss.name) << ",\n"
      << "  \"loss_scale\": " << FormatNumber(options.problem.loss.scale)
      << ",\n"
      << "  \"odometry_loss\": "
      << JsonString(options.problem.odometry_loss.name) << ",\n"
      << "  \"odometry_loss_scale\": "
      << FormatNumber(options.problem.odometry_loss.scale) << ",\n"
      << "  \"loss_solved\": " << JsonString(result.loss) << ",\n"
      << "  \"odometry_loss_solved\": " << JsonString(result.odometry_loss)
      << ",\n"
      << "  \"linear_solver\": " << JsonString(result.linear_solver) << ",\n"
      << "  \"linear_solver_reason\": "
      << JsonString(result.linear_solver_reason) << ",\n"
      << "  \"termination\": "
      << JsonString(ceres::TerminationTypeToString(s.termination_type)) << ",\n"
      << "  \"converged\": " << (result.converged ? "true" : "false") << ",\n"
      << "  \"iterations\": " << result.total_iterations << ",\n"
      << "  \"outer_rounds\": " << options.mean.outer_rounds << ",\n"
      << "  \"initial_cost\": " << FormatNumber(s.initial_cost) << ",\n"
      << "  \"final_cost\": " << FormatNumber(s.final_cost) << ",\n"
      << "  \"num_residual_blocks\": " << s.num_residual_blocks << ",\n"
      << "  \"num_parameters\": " << s.num_parameters << ",\n"
      << "  \"ceres_seconds\": " << FormatNumber(s.total_time_in_seconds)
      << ",\n"
      << "  \"total_seconds\": " << FormatNumber(result.solve_seconds) << ",\n"
      << "  \"num_poses\": " << result.trajectory.size() << ",\n"
      << "  \"num_landmarks\": " << result.landmarks.size() << ",\n"
      << "  \"initial_trajectory\": " << JsonString(result.initial_trajectory)
      << ",\n"
      << "  \"start_heading_resolved\": "
      << (result.start_heading.resolved ? "true" : "false") << ",\n"
      << "  \"start_heading\": " << FormatNumber(result.start_heading.heading)
      << ",\n"
      << "  \"range_bearing_ranges\": "
      << JsonString(result.range_bearing_ranges) << ",\n"
      << "  \"range_reading_note\": " << JsonString(result.range_reading_note)
      << ",\n"
      << "  \"depth_evidence\": "
      << (result.range_reading_judged
              ? "{\"rows\": " + std::to_string(result.depth_evidence.rows) +
                    ", \"slope\": " +
                    FormatNumber(result.depth_evidence.slope) + ", \"t\": " +
                    FormatNumber(result.depth_evidence.t_statistic) +
                    ", \"rejected\": " +
                    (result.depth_rejected ? "true" : "false") + "}"
              : std::string("null"))
      << ",\n"
      << "  \"range_scale\": " << FormatNumber(result.range_calibration[0])
      << ",\n"
      << "  \"range_offset\": " << FormatNumber(result.range_calibration[1])
      << ",\n"
      << "  \"odometry_scale\": "
      << FormatNumber(result.odometry_calibration[0]) << ",\n"
      << "  \"odometry_turn_scale\": "
      << FormatNumber(result.odometry_calibration[1]) << ",\n"
      << "  \"quality\": " << JsonString(result.quality.verdict) << ",\n"
      << "  \"quality_reasons\": " << JsonStringArray(result.quality.reasons)
      << ",\n"
      // null where not known (SolveFacts::predicted_decrease).
      << "  \"predicted_decrease\": "
      << (std::isfinite(result.quality.predicted_decrease)
              ? FormatNumber(result.quality.predicted_decrease)
              : "null")
      << ",\n  \"residuals\": {";
  for (std::size_t i = 0; i < result.quality.kinds.size(); ++i) {
    const ResidualKindQuality& q = result.quality.kinds[i];
    out << (i == 0 ? "\n" : ",\n") << "    " << JsonString(q.kind)
        << ": {\"count\": " << q.residuals
        << ", \"chi2_per_residual\": " << FormatNumber(q.chi2_per_residual)
        << ", \"inlier_chi2_per_residual\": "
        << FormatNumber(q.inlier_chi2_per_residual)
        << ", \"share_beyond_3_sigma\": "
        << FormatNumber(q.share_beyond_3_sigma)
        << ", \"largest\": " << FormatNumber(q.largest) << "}";
  }
  out << "\n  },\n"
      << "  \"incremental_every\": " << options.incremental.every << ",\n"
      << "  \"incremental_updates\": " << result.updates.size() << ",\n"
      << "  \"update_seconds_mean\": " << FormatNumber(update_mean) << ",\n"
      << "  \"update_seconds_max\": " << FormatNumber(update_max) << ",\n"
      << "  \"folded_residuals\": "
      << (result.updates.empty() ? 0 : result.updates.back().folded_residuals)
      << "\n"
      << "}\n";
}

bool WriteSummaryJson(const SlamOptions& options, const SlamResult& result,
                      const std::string& path, std::string* error) {
  return WriteOutputFile(
      path, [&](std::ostream* out) { WriteSummaryJson(options, result, out); },
      error);
}

bool WriteSlamOutputs(const SlamOptions& options, const SlamResult& result,
                      const SlamOutputPaths& paths, std::string* error) {
  // Each output's path and writer (false with `error` on bad content).
  const std::vector<
      std::pair<std::string, std::function<bool(std::ostream*, std::string*)>>>
      outputs = {
          {paths.trajectory,
           [&](std::ostream* out, std::string*) {
             WriteTum(result.trajectory, out);
             return true;
           }},
          {paths.landmarks,
           [&](std::ostream* out, std::string*) {
             WriteLandmarks(result.landmarks, out);
             return true;
           }},
          {paths.covariance,
           [&](std::ostream* out, std::string* why) {
             return WritePoseCovariances(result.trajectory,
                                         result.pose_covariances, out, why);
           }},
          {paths.summary_json,
           [&](std::ostream* out, std::string*) {
             WriteSummaryJson(options, result, out);
             return true;
           }},
      };
  std::vector<std::unique_ptr<OutputFile>> staged;
  for (const auto& [path, write] : outputs) {
    if (path.empty()) continue;
    staged.push_back(std::make_unique<OutputFile>(path));
    OutputFile& file = *staged.back();
    if (!file.Open(error)) return false;
    if (!write(&file.stream(), error)) {
      *error = path + ": " + *error;
      return false;
    }
    if (!file.Close(error)) return false;
  }
  // Every file is complete before any replaces its path.
  for (const auto& file : staged) {
    if (!file->Commit(error)) return false;
  }
  return true;
}

}  // namespace rff
