// exact_gp_reference: the dense exact-GP MAP (exact_gp_map.h) of small
// odometry-free .rffd files with the hyperparameters of their "# truth:"
// line (as rff_simulate --preset=gp_draw writes it), scored against their
// ground truth. One line per file; the reference of held-out tables.
//
//   exact_gp_reference [--mean=zero|constant] FILE.rffd...
#include <gflags/gflags.h>

#include <chrono>
#include <cstdio>
#include <sstream>
#include <string>

#include "rff_ceres/io/dataset_io.h"
#include "rff_ceres/metrics.h"
#include "rff_ceres/simulate_gp_draw.h"
#include "test/exact_gp/exact_gp_map.h"

DEFINE_string(mean, "zero",
              "Prior mean: zero (the model of gp_draw) or constant (the "
              "first PRIOR_POSE, as rff_slam --prior_mean=constant).");
DEFINE_double(gradient_tolerance, 1e-6,
              "Converged when max |J^T r| (whitened) is below this.");

namespace {

int Fail(const std::string& message) {
  std::fprintf(stderr, "exact_gp_reference: error: %s\n", message.c_str());
  return 1;
}

// shared/data/heldout's files spell the truth as "kernel matern52
// lengthscale 8 variance 25 heading_lengthscale 12 heading_variance 0.25":
// rewritten in the key=value form of rff_simulate.
std::string NormalizeTruth(const std::string& truth) {
  if (truth.find('=') != std::string::npos) return truth;
  std::istringstream tokens(truth);
  std::string key, value, normalized;
  while (tokens >> key >> value) {
    if (key == "variance") key = "kernel_variance";
    if (key == "heading_variance") key = "heading_kernel_variance";
    normalized += (normalized.empty() ? "" : " ") + key + "=" + value;
  }
  return normalized;
}

}  // namespace

int main(int argc, char** argv) {
  gflags::SetUsageMessage(
      "exact_gp_reference [--mean=zero|constant] FILE.rffd...");
  gflags::ParseCommandLineFlags(&argc, &argv, /*remove_flags=*/true);
  if (argc < 2) return Fail("give at least one .rffd file");
  int failures = 0;
  for (int a = 1; a < argc; ++a) {
    const std::string path = argv[a];
    rff::Dataset dataset;
    std::string error;
    if (!rff::ReadDataset(path, &dataset, &error)) return Fail(error);
    rff::ExactGpOptions options;
    options.mean = FLAGS_mean;
    options.gradient_tolerance = FLAGS_gradient_tolerance;
    options.compute_covariance = true;
    std::string truth;
    for (const auto& [key, value] : dataset.metadata) {
      if (key == "truth") truth = NormalizeTruth(value);
    }
    if (truth.empty()) return Fail(path + ": no '# truth:' line");
    if (!rff::ParseGpDrawTruth(truth, &options.position_kernel,
                               &options.heading_kernel, &error)) {
      return Fail(path + ": " + error);
    }
    const auto start = std::chrono::steady_clock::now();
    rff::ExactGpResult result;
    rff::Evaluation evaluation;
    if (!rff::SolveExactGpMapFromGroundTruth(dataset, options, &result,
                                             &evaluation, &error)) {
      return Fail(path + ": " + error);
    }
    const double seconds = std::chrono::duration<double>(
                               std::chrono::steady_clock::now() - start)
                               .count();
    double nees = 0.0;
    if (!rff::PositionNees(dataset, result, &nees, &error)) {
      return Fail(path + ": " + error);
    }
    if (!result.converged) ++failures;
    std::printf(
        "%s: %zu poses, %s; exact-GP MAP (mean %s) APE-trans RMS %.4f m, "
        "APE-rot RMS %.3f deg, landmarks RMS %.4f m, position NEES %.2f; "
        "%d iterations, "
        "|gradient| %.2e (%s), %.1f s\n",
        path.c_str(), result.trajectory.size(), truth.c_str(),
        options.mean.c_str(), evaluation.ape_translation.rms,
        evaluation.ape_rotation.rms * 180.0 / M_PI,
        evaluation.landmarks.distance.rms, nees, result.iterations,
        result.gradient_max_norm,
        result.converged ? "converged" : "NOT converged", seconds);
  }
  return failures == 0 ? 0 : 2;
}
