#include "rff_ceres/metrics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>

#include "rff_ceres/io/output_file.h"
#include "rff_ceres/io/text_parser.h"

namespace rff {
namespace {

constexpr double kDegreesPerRadian = 180.0 / M_PI;

std::string Span(double begin, double end) {
  return "[" + FormatNumber(begin) + ", " + FormatNumber(end) + "]";
}

ErrorSummary ToDegrees(ErrorSummary summary) {
  summary.rms *= kDegreesPerRadian;
  summary.mean *= kDegreesPerRadian;
  summary.median *= kDegreesPerRadian;
  summary.max *= kDegreesPerRadian;
  return summary;
}

// `"key": {summary}` or `"key": null, "key_reason": "..."`.
void WriteJsonSummary(const std::string& key, const ErrorSummary& summary,
                      std::ostream* output) {
  *output << "  " << JsonString(key) << ": ";
  if (!summary.available) {
    *output << "null,\n  " << JsonString(key + "_reason") << ": "
            << JsonString(summary.reason);
    return;
  }
  *output << "{\"rms\": " << FormatNumber(summary.rms)
          << ", \"mean\": " << FormatNumber(summary.mean)
          << ", \"median\": " << FormatNumber(summary.median)
          << ", \"max\": " << FormatNumber(summary.max)
          << ", \"count\": " << summary.count << "}";
}

// A table cell 12 wide: fixed point while it fits, else exponent form.
std::string Cell(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer),
                std::abs(value) < 1e5 ? " %12.6f" : " %12.6g", value);
  return buffer;
}

void PrintRow(const std::string& name, const ErrorSummary& summary,
              std::ostream* output) {
  char buffer[256];
  const int width = std::snprintf(buffer, 64, "%-20s", name.c_str());
  if (!summary.available) {
    *output << buffer << "  n/a (" << summary.reason << ")\n";
    return;
  }
  std::snprintf(buffer + width, sizeof(buffer) - width, "%s%s%s%s %7d\n",
                Cell(summary.rms).c_str(), Cell(summary.mean).c_str(),
                Cell(summary.median).c_str(), Cell(summary.max).c_str(),
                summary.count);
  *output << buffer;
}

}  // namespace

bool InterpolateTrajectory(const std::vector<TimedPose>& trajectory,
                           const std::vector<double>& times,
                           std::vector<TimedPose>* poses, std::string* error,
                           const std::string& what) {
  poses->clear();
  if (trajectory.empty()) {
    *error = "cannot interpolate an empty trajectory";
    return false;
  }
  for (std::size_t i = 1; i < trajectory.size(); ++i) {
    if (!(trajectory[i].t > trajectory[i - 1].t)) {
      *error = "trajectory times must strictly increase: " +
               FormatNumber(trajectory[i].t) + " follows " +
               FormatNumber(trajectory[i - 1].t);
      return false;
    }
  }
  const double begin = trajectory.front().t;
  const double end = trajectory.back().t;
  int before = 0;
  int after = 0;
  for (const double t : times) {
    if (t < begin - kTimeToleranceSeconds) ++before;
    if (t > end + kTimeToleranceSeconds) ++after;
  }
  if (before + after > 0) {
    const auto [lowest, highest] =
        std::minmax_element(times.begin(), times.end());
    *error =
        std::to_string(before + after) + " of " + std::to_string(times.size()) +
        " " + what + " times (span " + Span(*lowest, *highest) +
        ") lie outside the trajectory's time span " + Span(begin, end) + " (" +
        std::to_string(before) + " before, " + std::to_string(after) +
        " after, tolerance " + FormatNumber(kTimeToleranceSeconds) +
        " s); poses are not extrapolated";
    return false;
  }
  poses->reserve(times.size());
  for (const double t : times) poses->push_back(PoseAtTime(trajectory, t));
  return true;
}

bool AlignPositions(const std::vector<Pose2>& source,
                    const std::vector<Pose2>& target, Pose2* transform,
                    std::string* error) {
  if (source.size() != target.size() || source.empty()) {
    *error = "alignment needs equally many source and target positions, got " +
             std::to_string(source.size()) + " and " +
             std::to_string(target.size());
    return false;
  }
  const double n = static_cast<double>(source.size());
  double sx = 0.0, sy = 0.0, tx = 0.0, ty = 0.0;
  for (std::size_t i = 0; i < source.size(); ++i) {
    sx += source[i].x;
    sy += source[i].y;
    tx += target[i].x;
    ty += target[i].y;
  }
  sx /= n;
  sy /= n;
  tx /= n;
  ty /= n;
  // The rotation maximising sum t_i . R s_i (centred) is the angle of
  // sum (s_i . t_i, s_i x t_i).
  double dot = 0.0, cross = 0.0, source_spread = 0.0, target_spread = 0.0;
  for (std::size_t i = 0; i < source.size(); ++i) {
    const double ax = source[i].x - sx, ay = source[i].y - sy;
    const double bx = target[i].x - tx, by = target[i].y - ty;
    dot += ax * bx + ay * by;
    cross += ax * by - ay * bx;
    source_spread += ax * ax + ay * ay;
    target_spread += bx * bx + by * by;
  }
  if (!(source_spread > 0.0) || !(target_spread > 0.0)) {
    *error = "alignment is undetermined: the " +
             std::string(source_spread > 0.0 ? "target" : "source") +
             " positions are all equal (need at least 2 distinct positions)";
    return false;
  }
  const double angle = std::atan2(cross, dot);
  const double c = std::cos(angle), s = std::sin(angle);
  *transform = {tx - (c * sx - s * sy), ty - (s * sx + c * sy),
                WrapAngle(angle)};
  return true;
}

ErrorSummary Summarize(std::vector<double> values,
                       const std::string& reason_if_empty) {
  ErrorSummary summary;
  if (values.empty()) {
    summary.reason = reason_if_empty;
    return summary;
  }
  summary.available = true;
  summary.count = static_cast<int>(values.size());
  for (const double v : values) summary.max = std::max(summary.max, v);
  // Scaled by the largest, so that errors near the double range neither
  // overflow their squares nor their sum.
  const double n = static_cast<double>(values.size());
  const double scale = summary.max > 0.0 ? summary.max : 1.0;
  double mean = 0.0, mean_square = 0.0;
  for (const double v : values) {
    mean += (v / scale) / n;
    mean_square += (v / scale) * (v / scale) / n;
  }
  summary.mean = scale * mean;
  summary.rms = scale * std::sqrt(mean_square);
  std::sort(values.begin(), values.end());
  const std::size_t middle = values.size() / 2;
  summary.median = values.size() % 2 == 1
                       ? values[middle]
                       : 0.5 * values[middle - 1] + 0.5 * values[middle];
  return summary;
}

namespace {

// Errors between finite poses can still overflow (poses 1e308 apart).
bool CheckFiniteErrors(const std::vector<double>& values, const char* what,
                       std::string* error) {
  for (const double v : values) {
    if (!std::isfinite(v)) {
      *error = std::string(what) +
               " overflows double precision: the estimate is too far from "
               "the ground truth";
      return false;
    }
  }
  return true;
}

}  // namespace

bool Evaluate(const std::vector<TimedPose>& ground_truth,
              const std::vector<Landmark>& ground_truth_landmarks,
              const std::vector<TimedPose>& estimate,
              const std::vector<Landmark>* estimated_landmarks,
              const EvaluationOptions& options, Evaluation* evaluation,
              std::string* error) {
  *evaluation = Evaluation();
  if (ground_truth.empty()) {
    *error = "no ground-truth poses (the dataset has no GT_POSE record)";
    return false;
  }
  if (estimate.empty()) {
    *error = "the estimated trajectory has no poses";
    return false;
  }
  evaluation->ground_truth_poses = static_cast<int>(ground_truth.size());
  evaluation->ground_truth_begin = ground_truth.front().t;
  evaluation->ground_truth_end = ground_truth.back().t;
  evaluation->estimated_poses = static_cast<int>(estimate.size());

  std::vector<double> times;
  for (const TimedPose& p : ground_truth) times.push_back(p.t);
  std::vector<TimedPose> at_ground_truth;
  if (!InterpolateTrajectory(estimate, times, &at_ground_truth, error,
                             "ground-truth")) {
    *error =
        "the estimated trajectory does not cover the ground truth: " + *error;
    return false;
  }
  std::vector<Pose2> truth(ground_truth.size());
  std::vector<Pose2> estimated(ground_truth.size());
  for (std::size_t i = 0; i < ground_truth.size(); ++i) {
    truth[i] = ToPose2(ground_truth[i]);
    estimated[i] = ToPose2(at_ground_truth[i]);
  }

  if (options.align) {
    if (!AlignPositions(estimated, truth, &evaluation->alignment, error)) {
      *error =
          "cannot align the estimate (source) onto the ground truth "
          "(target): " +
          *error;
      return false;
    }
    evaluation->aligned = true;
    for (Pose2& p : estimated) p = Compose(evaluation->alignment, p);
  }

  // With z = 0 and roll = pitch = 0 the SE(3) error is planar: its
  // translation norm and rotation angle are those of the SE(2) error.
  std::vector<double> ape_translation, ape_rotation;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const Pose2 e = Between(truth[i], estimated[i]);
    ape_translation.push_back(std::hypot(e.x, e.y));
    ape_rotation.push_back(std::abs(e.theta));
  }
  if (!CheckFiniteErrors(ape_translation, "the APE translation", error) ||
      !CheckFiniteErrors(ape_rotation, "the APE rotation", error)) {
    return false;
  }
  evaluation->ape_translation = Summarize(ape_translation, "");
  evaluation->ape_rotation = Summarize(ape_rotation, "");

  std::vector<double> rpe_translation, rpe_rotation;
  for (std::size_t i = 1; i < truth.size(); ++i) {
    const Pose2 e = Between(Between(truth[i - 1], truth[i]),
                            Between(estimated[i - 1], estimated[i]));
    rpe_translation.push_back(std::hypot(e.x, e.y));
    rpe_rotation.push_back(std::abs(e.theta));
  }
  const std::string rpe_reason =
      "RPE needs at least 2 ground-truth poses, got " +
      std::to_string(truth.size());
  if (!CheckFiniteErrors(rpe_translation, "the RPE translation", error) ||
      !CheckFiniteErrors(rpe_rotation, "the RPE rotation", error)) {
    return false;
  }
  evaluation->rpe_translation = Summarize(rpe_translation, rpe_reason);
  evaluation->rpe_rotation = Summarize(rpe_rotation, rpe_reason);

  LandmarkEvaluation& landmarks = evaluation->landmarks;
  landmarks.ground_truth_count =
      static_cast<int>(ground_truth_landmarks.size());
  if (estimated_landmarks == nullptr) {
    landmarks.distance.reason = "no estimated landmarks given";
    return true;
  }
  landmarks.evaluated = true;
  landmarks.estimate_count = static_cast<int>(estimated_landmarks->size());
  std::map<LandmarkId, Pose2> by_id;
  for (const Landmark& l : *estimated_landmarks) {
    Pose2 position{l.x, l.y, 0.0};
    if (evaluation->aligned)
      position = Compose(evaluation->alignment, position);
    if (!by_id.emplace(l.id, position).second) {
      *error = "duplicate estimated landmark id " + std::to_string(l.id);
      return false;
    }
  }
  std::vector<double> distances;
  std::set<LandmarkId> has_truth;
  for (const Landmark& truth_landmark : ground_truth_landmarks) {
    has_truth.insert(truth_landmark.id);
    const auto found = by_id.find(truth_landmark.id);
    if (found == by_id.end()) {
      landmarks.missing_ids.push_back(truth_landmark.id);
      continue;
    }
    distances.push_back(std::hypot(found->second.x - truth_landmark.x,
                                   found->second.y - truth_landmark.y));
  }
  if (!CheckFiniteErrors(distances, "the landmark error", error)) return false;
  landmarks.matched = static_cast<int>(distances.size());
  for (const auto& entry : by_id) {
    if (has_truth.count(entry.first) == 0) ++landmarks.unmatched_estimates;
  }
  landmarks.distance = Summarize(
      distances, ground_truth_landmarks.empty()
                     ? "the dataset has no GT_LANDMARK record"
                     : "no estimated landmark id matches a ground-truth id");
  return true;
}

void PrintEvaluation(const Evaluation& evaluation, std::ostream* output) {
  *output << "ground truth: " << evaluation.ground_truth_poses
          << " poses, t in "
          << Span(evaluation.ground_truth_begin, evaluation.ground_truth_end)
          << "; estimate: " << evaluation.estimated_poses << " poses\n";
  if (evaluation.aligned) {
    char buffer[160];
    std::snprintf(buffer, sizeof(buffer),
                  "alignment (SE(2), estimate -> ground truth): rotation "
                  "%.6f deg, translation (%.6f, %.6f) m\n",
                  evaluation.alignment.theta * kDegreesPerRadian,
                  evaluation.alignment.x, evaluation.alignment.y);
    *output << buffer;
  } else {
    *output << "alignment: none\n";
  }
  char header[160];
  std::snprintf(header, sizeof(header), "%-20s %12s %12s %12s %12s %7s\n",
                "metric", "rms", "mean", "median", "max", "count");
  *output << header;
  PrintRow("APE translation [m]", evaluation.ape_translation, output);
  PrintRow("APE rotation [deg]", ToDegrees(evaluation.ape_rotation), output);
  PrintRow("RPE translation [m]", evaluation.rpe_translation, output);
  PrintRow("RPE rotation [deg]", ToDegrees(evaluation.rpe_rotation), output);
  PrintRow("landmarks [m]", evaluation.landmarks.distance, output);
  const LandmarkEvaluation& landmarks = evaluation.landmarks;
  if (landmarks.evaluated) {
    *output << "landmarks: " << landmarks.matched << " of "
            << landmarks.ground_truth_count
            << " ground-truth landmarks matched by id; "
            << landmarks.missing_ids.size() << " without an estimate";
    if (!landmarks.missing_ids.empty()) {
      *output << " (ids";
      const std::size_t shown =
          std::min<std::size_t>(landmarks.missing_ids.size(), 20);
      for (std::size_t i = 0; i < shown; ++i) {
        *output << " " << landmarks.missing_ids[i];
      }
      if (shown < landmarks.missing_ids.size()) *output << " ...";
      *output << ")";
    }
    *output << "; " << landmarks.unmatched_estimates
            << " estimates without ground truth\n";
  }
  const ConsistencySummary& c = evaluation.consistency;
  if (c.evaluated) {
    char buffer[320];
    std::snprintf(buffer, sizeof(buffer),
                  "consistency: %d poses; position NEES mean %.3f (ideal 2), "
                  "inside the 68/95/99%% regions %.3f/%.3f/%.3f; heading "
                  "NEES mean %.3f (ideal 1), inside %.3f/%.3f/%.3f\n",
                  c.count, c.mean_position_nees, c.position_coverage[0],
                  c.position_coverage[1], c.position_coverage[2],
                  c.mean_heading_nees, c.heading_coverage[0],
                  c.heading_coverage[1], c.heading_coverage[2]);
    *output << buffer;
  }
}

void WriteEvaluationJson(
    const Evaluation& evaluation,
    const std::vector<std::pair<std::string, std::string>>& inputs,
    std::ostream* output) {
  *output << "{\n";
  for (const auto& [key, value] : inputs) {
    *output << "  " << JsonString(key) << ": " << JsonString(value) << ",\n";
  }
  *output << "  \"ground_truth_poses\": " << evaluation.ground_truth_poses
          << ",\n  \"ground_truth_begin\": "
          << FormatNumber(evaluation.ground_truth_begin)
          << ",\n  \"ground_truth_end\": "
          << FormatNumber(evaluation.ground_truth_end)
          << ",\n  \"estimated_poses\": " << evaluation.estimated_poses
          << ",\n  \"aligned\": " << (evaluation.aligned ? "true" : "false")
          << ",\n  \"alignment\": ";
  if (evaluation.aligned) {
    *output << "{\"x\": " << FormatNumber(evaluation.alignment.x)
            << ", \"y\": " << FormatNumber(evaluation.alignment.y)
            << ", \"theta_rad\": " << FormatNumber(evaluation.alignment.theta)
            << ", \"theta_deg\": "
            << FormatNumber(evaluation.alignment.theta * kDegreesPerRadian)
            << "}";
  } else {
    *output << "null";
  }
  *output << ",\n";
  WriteJsonSummary("ape_trans_m", evaluation.ape_translation, output);
  *output << ",\n";
  WriteJsonSummary("ape_rot_deg", ToDegrees(evaluation.ape_rotation), output);
  *output << ",\n";
  WriteJsonSummary("rpe_trans_m", evaluation.rpe_translation, output);
  *output << ",\n";
  WriteJsonSummary("rpe_rot_deg", ToDegrees(evaluation.rpe_rotation), output);
  *output << ",\n";
  WriteJsonSummary("landmark_error_m", evaluation.landmarks.distance, output);
  const LandmarkEvaluation& landmarks = evaluation.landmarks;
  *output << ",\n  \"landmark_ground_truth\": " << landmarks.ground_truth_count;
  if (landmarks.evaluated) {
    *output << ",\n  \"landmark_estimates\": " << landmarks.estimate_count
            << ",\n  \"landmark_matched\": " << landmarks.matched
            << ",\n  \"landmark_missing_ids\": [";
    for (std::size_t i = 0; i < landmarks.missing_ids.size(); ++i) {
      *output << (i > 0 ? ", " : "") << landmarks.missing_ids[i];
    }
    *output << "],\n  \"landmark_unmatched_estimates\": "
            << landmarks.unmatched_estimates;
  }
  const ConsistencySummary& c = evaluation.consistency;
  if (c.evaluated) {
    *output << ",\n  \"consistency_count\": " << c.count
            << ",\n  \"mean_position_nees\": "
            << FormatNumber(c.mean_position_nees)
            << ",\n  \"mean_heading_nees\": "
            << FormatNumber(c.mean_heading_nees);
    const char* levels[] = {"68", "95", "99"};
    for (int k = 0; k < 3; ++k) {
      *output << ",\n  \"position_coverage_" << levels[k]
              << "\": " << FormatNumber(c.position_coverage[k])
              << ",\n  \"heading_coverage_" << levels[k]
              << "\": " << FormatNumber(c.heading_coverage[k]);
    }
  }
  *output << "\n}\n";
}

bool WriteEvaluationJson(
    const Evaluation& evaluation,
    const std::vector<std::pair<std::string, std::string>>& inputs,
    const std::string& path, std::string* error) {
  return WriteOutputFile(
      path,
      [&](std::ostream* out) { WriteEvaluationJson(evaluation, inputs, out); },
      error);
}

}  // namespace rff
