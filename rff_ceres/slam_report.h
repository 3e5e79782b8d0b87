// The solve's report for people (PrintSlamSummary) and for scripts
// (WriteSummaryJson): the settled model, the solver, costs, times and the
// quality verdict.
#ifndef RFF_CERES_SLAM_REPORT_H_
#define RFF_CERES_SLAM_REPORT_H_

#include <ostream>
#include <string>

#include "rff_ceres/slam_solver.h"

namespace rff {

// Prints the model, problem size, iterations, costs and times (and the
// incremental updates' times) for people.
void PrintSlamSummary(const SlamOptions& options, const SlamResult& result,
                      std::ostream* out);

// Writes the summary (options, costs, iterations, times) as JSON.
void WriteSummaryJson(const SlamOptions& options, const SlamResult& result,
                      std::ostream* output);
bool WriteSummaryJson(const SlamOptions& options, const SlamResult& result,
                      const std::string& path, std::string* error);

// The files of one solve; an empty path is not written.
struct SlamOutputPaths {
  std::string trajectory;  // TUM.
  std::string landmarks;   // .landmarks (with covariances when computed).
  std::string covariance;  // Pose covariances (pose_covariance_io.h).
  std::string summary_json;
};

// Writes every given output or none: each is staged in a temporary file,
// and the paths are replaced only once all are complete.
bool WriteSlamOutputs(const SlamOptions& options, const SlamResult& result,
                      const SlamOutputPaths& paths, std::string* error);

}  // namespace rff

#endif  // RFF_CERES_SLAM_REPORT_H_
