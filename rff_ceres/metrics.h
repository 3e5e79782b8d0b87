// Trajectory and map error metrics (docs/metrics.md, FORMAT.md "Metrics"):
// APE and RPE of planar poses lifted to SE(3) (z = 0, roll = pitch = 0), and
// the RMS landmark distance. The estimate is interpolated at the ground-truth
// times; it is never extrapolated.
#ifndef RFF_CERES_METRICS_H_
#define RFF_CERES_METRICS_H_

#include <array>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "rff_ceres/se2.h"
#include "rff_ceres/types.h"

namespace rff {

// How far (seconds) a query time may lie outside a trajectory's time span and
// still be served (by the end pose): covers rounding of times written as text,
// ~4 ulp at Unix-epoch times.
inline constexpr double kTimeToleranceSeconds = 1e-6;

// Poses of `trajectory` (strictly increasing times) at `times`: linear in x
// and y, heading along the shorter arc. A time within kTimeToleranceSeconds
// of the span gets the end pose. Fails, without extrapolating, when any time
// lies further outside; the error says how many and gives both spans, naming
// the times as "<what> times".
bool InterpolateTrajectory(const std::vector<TimedPose>& trajectory,
                           const std::vector<double>& times,
                           std::vector<TimedPose>* poses, std::string* error,
                           const std::string& what = "query");

// Least-squares rigid transform (rotation and translation, no scale; the 2D
// Umeyama / Horn closed form) that maps the `source` positions onto the
// `target` positions: target_i ~ Compose(transform, source_i). Headings are
// ignored. Fails when the sizes differ or either set has no spread (all
// positions equal), where the rotation is undetermined.
bool AlignPositions(const std::vector<Pose2>& source,
                    const std::vector<Pose2>& target, Pose2* transform,
                    std::string* error);

// Statistics of a list of non-negative errors. `available` is false (with a
// reason) when the metric cannot be computed; the numbers are then zero.
struct ErrorSummary {
  bool available = false;
  std::string reason;
  int count = 0;
  double rms = 0.0;
  double mean = 0.0;
  double median = 0.0;  // Mean of the two middle values for an even count.
  double max = 0.0;
};

// Summary of `values`; unavailable with `reason_if_empty` when empty.
ErrorSummary Summarize(std::vector<double> values,
                       const std::string& reason_if_empty);

// Landmark errors. Ground-truth landmarks without an estimate are not an
// error (a solver cannot estimate a landmark it never saw); they are listed in
// `missing_ids` and left out of the RMS. Estimates without ground truth are
// counted in `unmatched_estimates`.
struct LandmarkEvaluation {
  bool evaluated = false;  // Whether estimated landmarks were given.
  int ground_truth_count = 0;
  int estimate_count = 0;
  int matched = 0;
  std::vector<LandmarkId> missing_ids;
  int unmatched_estimates = 0;
  ErrorSummary distance;  // Metres, over the matched landmarks.
};

// Consistency of pose covariances with the errors they claim: the
// normalised estimation error squared e^T P^-1 e per ground-truth pose
// (Bar-Shalom, Li & Kirubarajan 2001, 5.4), of the position (2 degrees of
// freedom, ideal mean 2) and of the heading (1, ideal mean 1), and the share
// of poses inside the regions that should hold 68.27%, 95% and 99% of them.
struct ConsistencySummary {
  bool evaluated = false;  // Whether covariances were given.
  int count = 0;
  double mean_position_nees = 0.0;
  double mean_heading_nees = 0.0;
  std::array<double, 3> position_coverage = {0.0, 0.0, 0.0};
  std::array<double, 3> heading_coverage = {0.0, 0.0, 0.0};
};
inline constexpr std::array<double, 3> kCoverageLevels = {0.6827, 0.95, 0.99};

struct EvaluationOptions {
  // Apply the least-squares SE(2) alignment of the estimated positions onto
  // the ground-truth positions before computing every error.
  bool align = false;
};

struct Evaluation {
  int ground_truth_poses = 0;
  double ground_truth_begin = 0.0;
  double ground_truth_end = 0.0;
  int estimated_poses = 0;
  bool aligned = false;
  Pose2 alignment;  // aligned estimate = Compose(alignment, estimate).
  ErrorSummary ape_translation;  // Metres.
  ErrorSummary ape_rotation;     // Radians (reports convert to degrees).
  ErrorSummary rpe_translation;  // Metres, consecutive ground-truth times.
  ErrorSummary rpe_rotation;     // Radians.
  LandmarkEvaluation landmarks;
  ConsistencySummary consistency;  // See EvaluateConsistency.
};

// Evaluates `estimate` (strictly increasing times) against `ground_truth`
// (sorted by time) and, when `estimated_landmarks` is not null, the landmarks
// against `ground_truth_landmarks`. Fails with a message when there is no
// ground-truth pose, the estimate is empty or does not cover a ground-truth
// time, or the alignment is undetermined.
bool Evaluate(const std::vector<TimedPose>& ground_truth,
              const std::vector<Landmark>& ground_truth_landmarks,
              const std::vector<TimedPose>& estimate,
              const std::vector<Landmark>* estimated_landmarks,
              const EvaluationOptions& options, Evaluation* evaluation,
              std::string* error);

// Human-readable table of `evaluation` (rotations in degrees).
void PrintEvaluation(const Evaluation& evaluation, std::ostream* output);

// The same numbers as a JSON object (rotations in degrees). A metric that was
// not computed is null, with its reason in "<name>_reason". `inputs` are
// (key, value) strings written first, e.g. the file names.
void WriteEvaluationJson(
    const Evaluation& evaluation,
    const std::vector<std::pair<std::string, std::string>>& inputs,
    std::ostream* output);
bool WriteEvaluationJson(
    const Evaluation& evaluation,
    const std::vector<std::pair<std::string, std::string>>& inputs,
    const std::string& path, std::string* error);

}  // namespace rff

#endif  // RFF_CERES_METRICS_H_
