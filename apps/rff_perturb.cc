// rff_perturb: writes a copy of a .rffd dataset with seeded perturbations of
// its priors (landmark priors moved, start heading rotated or made unknown),
// each recorded in a "# perturbation: ..." line. See docs/heldout.md.
//
//   rff_perturb --input=IN.rffd --output=OUT.rffd --landmark_prior_offset=1
//               --seed=101
//   rff_perturb --input=IN.rffd --output=OUT.rffd
//               --start_heading_offset_deg=90
//               --start_heading_sigma=3.141592653589793
#include <gflags/gflags.h>

#include <cstdio>
#include <string>

#include "rff_ceres/io/output_file.h"
#include "rff_ceres/perturb.h"
#include "tool_flags.h"

DEFINE_string(input, "", "Input .rffd path (required).");
DEFINE_string(output, "", "Output .rffd path (required; not the input file).");
DEFINE_double(landmark_prior_offset, 0.0,
              "Sigma (m) of the N(0, sigma^2) offset added to each axis of "
              "every PRIOR_LANDMARK mean; their sigmas become at least this. "
              "0 leaves them unchanged. 0 to 1e6.");
DEFINE_double(start_heading_offset_deg, 0.0,
              "Rotation (degrees) of the earliest PRIOR_POSEs' heading, -360 "
              "to 360.");
DEFINE_double(start_heading_sigma, 0.0,
              "New sigma_theta (rad) of the earliest PRIOR_POSEs; unchanged "
              "unless given (pi: the start heading is unknown). More than 0 "
              "up to 1e6.");
DEFINE_uint64(seed, 1, "Random seed; the same seed gives the same file.");

namespace {

int Fail(const std::string& message) {
  std::fprintf(stderr, "rff_perturb: error: %s\n", message.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  gflags::SetUsageMessage(
      "rff_perturb --input=IN.rffd --output=OUT.rffd "
      "[--landmark_prior_offset=M] [--start_heading_offset_deg=D] "
      "[--start_heading_sigma=RAD] [--seed=1]");
  std::string error;
  if (!rff::ParseToolFlags(&argc, &argv, &error)) return Fail(error);
  if (FLAGS_input.empty()) return Fail("--input is required");
  if (FLAGS_output.empty()) return Fail("--output is required");
  if (!rff::CheckOutputPaths(rff::WithFlagfiles({{"--input", FLAGS_input}}),
                             {{"--output", FLAGS_output}}, &error)) {
    return Fail(error);
  }

  rff::PerturbOptions options;
  options.landmark_prior_offset = FLAGS_landmark_prior_offset;
  options.start_heading_offset_deg = FLAGS_start_heading_offset_deg;
  // Given, not non-zero: an explicit 0 must reach the check and fail there.
  if (!gflags::GetCommandLineFlagInfoOrDie("start_heading_sigma").is_default) {
    options.start_heading_sigma = FLAGS_start_heading_sigma;
  }
  options.seed = FLAGS_seed;
  if (!rff::PerturbFile(FLAGS_input, FLAGS_output, options, &error)) {
    return Fail(error);
  }
  std::printf("wrote %s: %s perturbed (seed %llu)\n", FLAGS_output.c_str(),
              FLAGS_input.c_str(),
              static_cast<unsigned long long>(options.seed));
  return 0;
}
