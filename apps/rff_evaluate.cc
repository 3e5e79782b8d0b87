// rff_evaluate: APE, RPE and landmark error of an estimated trajectory (TUM)
// and optional landmark file against the ground truth of a .rffd dataset.
//
//   rff_evaluate --dataset=IN.rffd --trajectory=EST.tum
//                [--landmarks=EST.landmarks] [--covariance=EST.cov] [--align]
//                [--json=OUT.json]
#include <iostream>
#include <string>
#include <vector>

#include "gflags/gflags.h"
#include "rff_ceres/consistency.h"
#include "rff_ceres/io/dataset_io.h"
#include "rff_ceres/io/landmarks_io.h"
#include "rff_ceres/io/output_file.h"
#include "rff_ceres/io/tum_io.h"
#include "rff_ceres/metrics.h"
#include "tool_flags.h"

DEFINE_string(dataset, "", "Dataset (.rffd) with GT_POSE (and GT_LANDMARK).");
DEFINE_string(trajectory, "", "Estimated trajectory (TUM).");
DEFINE_string(landmarks, "", "Estimated landmarks (.landmarks), optional.");
DEFINE_bool(align, false,
            "Align the estimate onto the ground truth (least-squares SE(2), "
            "positions) before computing the errors.");
DEFINE_string(json, "", "Also write the metrics as JSON to this file.");
DEFINE_string(covariance, "",
              "Pose covariances of the estimate (rff_slam "
              "--output_covariance), optional: adds the consistency (mean "
              "NEES of position and heading, coverage of the 68/95/99% "
              "regions).");

namespace {

int Fail(const std::string& message) {
  std::cerr << "rff_evaluate: error: " << message << "\n";
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  gflags::SetUsageMessage(
      "rff_evaluate --dataset=IN.rffd --trajectory=EST.tum "
      "[--landmarks=EST.landmarks] [--covariance=EST.cov] [--align] "
      "[--json=OUT.json]");
  std::string error;
  if (!rff::ParseToolFlags(&argc, &argv, &error)) return Fail(error);
  if (FLAGS_dataset.empty()) return Fail("--dataset is required");
  if (FLAGS_trajectory.empty()) return Fail("--trajectory is required");
  if (!rff::CheckOutputPaths(
          rff::WithFlagfiles({{"--dataset", FLAGS_dataset},
                              {"--trajectory", FLAGS_trajectory},
                              {"--landmarks", FLAGS_landmarks},
                              {"--covariance", FLAGS_covariance}}),
          {{"--json", FLAGS_json}}, &error)) {
    return Fail(error);
  }

  rff::Dataset dataset;
  if (!rff::ReadDataset(FLAGS_dataset, &dataset, &error)) return Fail(error);
  if (dataset.ground_truth.empty()) {
    return Fail(FLAGS_dataset +
                ": no GT_POSE record, nothing to evaluate against");
  }
  std::vector<rff::TimedPose> trajectory;
  if (!rff::ReadTum(FLAGS_trajectory, &trajectory, &error)) return Fail(error);
  std::vector<rff::Landmark> landmarks;
  if (!FLAGS_landmarks.empty() &&
      !rff::ReadLandmarks(FLAGS_landmarks, &landmarks, &error)) {
    return Fail(error);
  }

  std::vector<rff::PoseCovariance> covariances;
  if (!FLAGS_covariance.empty() &&
      !rff::ReadPoseCovariances(FLAGS_covariance, &covariances, &error)) {
    return Fail(error);
  }
  rff::EvaluationOptions options;
  options.align = FLAGS_align;
  rff::Evaluation evaluation;
  if (!rff::Evaluate(dataset.ground_truth, dataset.ground_truth_landmarks,
                     trajectory, FLAGS_landmarks.empty() ? nullptr : &landmarks,
                     options, &evaluation, &error)) {
    return Fail(FLAGS_trajectory + ": " + error);
  }
  if (!FLAGS_covariance.empty() &&
      !rff::EvaluateConsistency(dataset.ground_truth, trajectory, covariances,
                                &evaluation, &error)) {
    return Fail(FLAGS_covariance + ": " + error);
  }
  std::cout << "dataset: " << FLAGS_dataset
            << "\ntrajectory: " << FLAGS_trajectory << "\n";
  if (!FLAGS_landmarks.empty()) {
    std::cout << "landmarks: " << FLAGS_landmarks << "\n";
  }
  rff::PrintEvaluation(evaluation, &std::cout);

  if (!FLAGS_json.empty()) {
    std::vector<std::pair<std::string, std::string>> inputs = {
        {"dataset", FLAGS_dataset}, {"trajectory", FLAGS_trajectory}};
    if (!FLAGS_landmarks.empty())
      inputs.push_back({"landmarks", FLAGS_landmarks});
    if (!FLAGS_covariance.empty())
      inputs.push_back({"covariance", FLAGS_covariance});
    if (!rff::WriteEvaluationJson(evaluation, inputs, FLAGS_json, &error)) {
      return Fail(error);
    }
  }
  return 0;
}
