// rff_slam: continuous-time 2D SLAM with a weight-space GP trajectory prior.
//
//   rff_slam --dataset=IN.rffd --output_trajectory=OUT.tum
//            --output_landmarks=OUT.landmarks [--summary_json=OUT.json]
//            [--flagfile=configs/NAME.flags] [--kernel=rbf ...]
//
// Reads the dataset, solves, writes the trajectory at every observation and
// ground-truth time, and prints the summary (and the metrics when the
// dataset carries ground truth).
#include <iostream>
#include <string>

#include "gflags/gflags.h"
#include "glog/logging.h"
#include "rff_ceres/allocator.h"
#include "rff_ceres/features/feature_map.h"
#include "rff_ceres/io/dataset_io.h"
#include "rff_ceres/io/output_file.h"
#include "rff_ceres/metrics.h"
#include "rff_ceres/slam_report.h"
#include "rff_ceres/slam_solver.h"
#include "slam_flags.h"
#include "tool_flags.h"

DEFINE_string(dataset, "", "Input dataset (.rffd).");
DEFINE_string(output_trajectory, "", "Write the trajectory here (TUM).");
DEFINE_string(output_landmarks, "", "Write the landmarks here (.landmarks).");
DEFINE_string(output_covariance, "",
              "Write the covariance of each output pose here (t sxx sxy sxt "
              "syy syt stt per line); the landmarks file then carries "
              "sxx sxy syy. At most 10000 landmarks.");
DEFINE_string(summary_json, "", "Write the solve summary here (JSON).");
DEFINE_bool(fail_on_suspect, false,
            "Exit with status 3 when the quality verdict is 'suspect' (the "
            "outputs are still written, for inspection).");
DEFINE_bool(evaluate, true,
            "Print APE/RPE/landmark errors when the dataset has ground truth.");

namespace {

int Fail(const std::string& message) {
  std::cerr << "rff_slam: error: " << message << "\n";
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  rff::RetainFreedMemory();
  FLAGS_logtostderr = true;
  gflags::SetUsageMessage(
      "rff_slam --dataset=IN.rffd --output_trajectory=OUT.tum "
      "--output_landmarks=OUT.landmarks [--summary_json=OUT.json] "
      "[--flagfile=configs/NAME.flags]");
  std::string error;
  if (!rff::ParseToolFlags(&argc, &argv, &error)) return Fail(error);
  google::InitGoogleLogging(argv[0]);
  if (FLAGS_dataset.empty()) return Fail("--dataset is required");

  rff::SlamOptions options = rff::SlamOptionsFromFlags();
  options.output.covariance = !FLAGS_output_covariance.empty();
  if (!rff::ValidateSlamOptions(options, &error)) return Fail(error);
  const rff::SlamOutputPaths outputs = {
      FLAGS_output_trajectory, FLAGS_output_landmarks, FLAGS_output_covariance,
      FLAGS_summary_json};
  if (!rff::CheckOutputPaths(rff::WithFlagfiles({{"--dataset", FLAGS_dataset}}),
                             {{"--output_trajectory", outputs.trajectory},
                              {"--output_landmarks", outputs.landmarks},
                              {"--output_covariance", outputs.covariance},
                              {"--summary_json", outputs.summary_json}},
                             &error)) {
    return Fail(error);
  }
  rff::Dataset dataset;
  if (!rff::ReadDataset(FLAGS_dataset, &dataset, &error)) return Fail(error);
  rff::SlamResult result;
  if (!rff::RunSlam(dataset, options, &result, &error)) {
    return Fail(FLAGS_dataset + ": " + error);
  }

  std::cout << "rff_slam: " << FLAGS_dataset << "\n";
  rff::PrintSlamSummary(options, result, &std::cout);

  if (!rff::WriteSlamOutputs(options, result, outputs, &error)) {
    return Fail(error);
  }
  if (FLAGS_evaluate && !dataset.ground_truth.empty()) {
    rff::Evaluation evaluation;
    if (!rff::Evaluate(dataset.ground_truth, dataset.ground_truth_landmarks,
                       result.trajectory, &result.landmarks,
                       rff::EvaluationOptions(), &evaluation, &error)) {
      return Fail("evaluation: " + error);
    }
    rff::PrintEvaluation(evaluation, &std::cout);
  }
  std::cerr << "rff_slam: quality " << rff::QualityLine(result.quality) << "\n";
  return FLAGS_fail_on_suspect && result.quality.suspect() ? 3 : 0;
}
