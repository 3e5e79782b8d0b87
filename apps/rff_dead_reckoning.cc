// rff_dead_reckoning: integrates the ODOM records of a .rffd dataset from its
// earliest PRIOR_POSE and writes the trajectory as TUM, with poses at every
// odometry endpoint and at every observation and GT_POSE time in the span.
//
//   rff_dead_reckoning --dataset=IN.rffd --output_trajectory=OUT.tum
//                      [--hold_through_gaps]
#include <iostream>
#include <string>

#include "gflags/gflags.h"
#include "rff_ceres/dead_reckoning.h"
#include "rff_ceres/io/dataset_io.h"
#include "rff_ceres/io/output_file.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/io/tum_io.h"
#include "tool_flags.h"

DEFINE_string(dataset, "", "Dataset (.rffd) with PRIOR_POSE and ODOM records.");
DEFINE_string(output_trajectory, "", "Where to write the trajectory (TUM).");
DEFINE_bool(hold_through_gaps, false,
            "Hold the pose constant across intervals that no ODOM record "
            "covers instead of failing.");

namespace {

int Fail(const std::string& message) {
  std::cerr << "rff_dead_reckoning: error: " << message << "\n";
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  gflags::SetUsageMessage(
      "rff_dead_reckoning --dataset=IN.rffd --output_trajectory=OUT.tum "
      "[--hold_through_gaps]");
  std::string error;
  if (!rff::ParseToolFlags(&argc, &argv, &error)) return Fail(error);
  if (FLAGS_dataset.empty()) return Fail("--dataset is required");
  if (FLAGS_output_trajectory.empty()) {
    return Fail("--output_trajectory is required");
  }
  if (!rff::CheckOutputPaths(rff::WithFlagfiles({{"--dataset", FLAGS_dataset}}),
                             {{"--output_trajectory", FLAGS_output_trajectory}},
                             &error)) {
    return Fail(error);
  }

  rff::Dataset dataset;
  if (!rff::ReadDataset(FLAGS_dataset, &dataset, &error)) return Fail(error);
  rff::DeadReckoningOptions options;
  options.hold_through_gaps = FLAGS_hold_through_gaps;
  rff::DeadReckoningResult result;
  if (!rff::DeadReckon(dataset, options, &result, &error)) {
    return Fail(FLAGS_dataset + ": " + error);
  }
  if (!rff::WriteTum(result.poses, FLAGS_output_trajectory, &error)) {
    return Fail(error);
  }

  std::cout << "integrated " << result.odometry_records
            << " ODOM records from PRIOR_POSE at t="
            << rff::FormatNumber(result.start.t) << "; wrote "
            << result.poses.size() << " poses over ["
            << rff::FormatNumber(result.span_begin) << ", "
            << rff::FormatNumber(result.span_end) << "] to "
            << FLAGS_output_trajectory << "\n";
  if (result.times_outside_span > 0) {
    std::cerr << "rff_dead_reckoning: warning: " << result.times_outside_span
              << " observation/GT_POSE times lie outside the odometry span; "
                 "no pose written for them\n";
  }
  if (!result.gaps.empty()) {
    double total = 0.0;
    for (const rff::OdometryGap& gap : result.gaps)
      total += gap.end - gap.begin;
    std::cerr << "rff_dead_reckoning: warning: pose held through "
              << result.gaps.size() << " odometry gap(s), "
              << rff::FormatNumber(total) << " s in all; first ("
              << rff::FormatNumber(result.gaps.front().begin) << ", "
              << rff::FormatNumber(result.gaps.front().end) << ")\n";
  }
  return 0;
}
