#include "rff_ceres/perturb.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "rff_ceres/io/dataset_io.h"
#include "rff_ceres/io/output_file.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/option_error.h"
#include "rff_ceres/simulate.h"

namespace rff {
namespace {

constexpr double kDegree = M_PI / 180.0;

bool InRange(bool in_range, const char* flag, double value,
             const std::string& range, std::string* error) {
  if (in_range) return true;
  *error = OptionError(flag, FormatNumber(value), "", range);
  return false;
}

// "start_heading_offset_deg=90 start_heading_sigma=3.14 seed=7": the
// heading request, for the metadata line and the error messages alike.
std::string HeadingRequest(const PerturbOptions& options) {
  std::string request = "start_heading_offset_deg=" +
                        FormatNumber(options.start_heading_offset_deg);
  if (options.start_heading_sigma) {
    request +=
        " start_heading_sigma=" + FormatNumber(*options.start_heading_sigma);
  }
  return request + " seed=" + std::to_string(options.seed);
}

std::string LandmarkRequest(const PerturbOptions& options) {
  return "landmark_prior_offset=" +
         FormatNumber(options.landmark_prior_offset) +
         " seed=" + std::to_string(options.seed);
}

// Every prior mean moves by an independent draw per axis, in id order (the
// reader's order), x before y, so that a seed means the same offsets.
void OffsetLandmarkPriors(const PerturbOptions& options, Dataset* dataset) {
  const double offset = options.landmark_prior_offset;
  SimulationRandom random(options.seed);
  for (LandmarkPrior& prior : dataset->landmark_priors) {
    prior.x += offset * random.Normal();
    prior.y += offset * random.Normal();
    prior.sigma = std::max(prior.sigma, offset);
  }
  const std::string offset_text = FormatNumber(offset);
  dataset->metadata.emplace_back(
      "perturbation", LandmarkRequest(options) + ": " +
                          std::to_string(dataset->landmark_priors.size()) +
                          " PRIOR_LANDMARK means moved by N(0, " + offset_text +
                          "^2) per axis, sigmas raised to at least " +
                          offset_text);
}

// Every PRIOR_POSE at the earliest time is the start: one left as it was
// would hold the start heading the perturbation turned.
void RotateStartHeading(const PerturbOptions& options, Dataset* dataset) {
  const double t0 = EarliestPosePrior(*dataset).pose.t;
  std::string done;
  for (PosePrior& start : dataset->pose_priors) {
    if (start.pose.t != t0) continue;
    const double old_theta = start.pose.theta;
    const double old_sigma = start.sigma_theta;
    start.pose.theta =
        WrapAngle(old_theta + options.start_heading_offset_deg * kDegree);
    if (options.start_heading_sigma) {
      start.sigma_theta = *options.start_heading_sigma;
    }
    done += (done.empty() ? "" : "; ") + std::string("PRIOR_POSE at t=") +
            FormatNumber(start.pose.t) + " theta " + FormatNumber(old_theta) +
            " -> " + FormatNumber(start.pose.theta) + ", sigma_theta " +
            FormatNumber(old_sigma) + " -> " + FormatNumber(start.sigma_theta);
  }
  dataset->metadata.emplace_back("perturbation",
                                 HeadingRequest(options) + ": " + done);
}

}  // namespace

bool ValidatePerturbOptions(const PerturbOptions& o, std::string* error) {
  // Written as "inside" tests so that NaN fails every one of them.
  const double offset = o.landmark_prior_offset;
  const double heading = o.start_heading_offset_deg;
  const std::string largest = FormatNumber(kMaxPerturbMagnitude);
  return InRange(offset >= 0.0 && offset <= kMaxPerturbMagnitude,
                 "landmark_prior_offset", offset, "0 to " + largest + " m",
                 error) &&
         InRange(heading >= -360.0 && heading <= 360.0,
                 "start_heading_offset_deg", heading, "-360 to 360 degrees",
                 error) &&
         (!o.start_heading_sigma ||
          InRange(IsNormalPositive(*o.start_heading_sigma) &&
                      *o.start_heading_sigma <= kMaxPerturbMagnitude,
                  "start_heading_sigma", *o.start_heading_sigma,
                  "more than 0 up to " + largest + " rad", error));
}

bool ChangesLandmarkPriors(const PerturbOptions& options) {
  return options.landmark_prior_offset > 0.0;
}

bool ChangesStartHeading(const PerturbOptions& options) {
  return options.start_heading_offset_deg != 0.0 ||
         options.start_heading_sigma.has_value();
}

bool PerturbDataset(const PerturbOptions& options, Dataset* dataset,
                    std::string* error) {
  if (!ValidatePerturbOptions(options, error)) return false;
  if (ChangesStartHeading(options) && dataset->pose_priors.empty()) {
    *error = HeadingRequest(options) +
             " changes the start heading, but there is no PRIOR_POSE record";
    return false;
  }
  if (ChangesLandmarkPriors(options) && dataset->landmark_priors.empty()) {
    *error = LandmarkRequest(options) +
             " moves the landmark priors, but there is no PRIOR_LANDMARK "
             "record";
    return false;
  }
  if (ChangesLandmarkPriors(options)) OffsetLandmarkPriors(options, dataset);
  if (ChangesStartHeading(options)) RotateStartHeading(options, dataset);
  return true;
}

bool PerturbFile(const std::string& input, const std::string& output,
                 const PerturbOptions& options, std::string* error) {
  if (!ValidatePerturbOptions(options, error)) return false;
  // A copy under another name would pass for a perturbed file.
  if (!ChangesLandmarkPriors(options) && !ChangesStartHeading(options)) {
    *error =
        "nothing to perturb: give --landmark_prior_offset, "
        "--start_heading_offset_deg or --start_heading_sigma";
    return false;
  }
  if (SameFile(input, output)) {
    *error = OptionError("output", output,
                         "the same file as the input --input=" + input,
                         "another path");
    return false;
  }
  Dataset dataset;
  if (!ReadDataset(input, &dataset, error)) return false;
  if (!PerturbDataset(options, &dataset, error)) {
    *error = input + ": " + *error;
    return false;
  }
  return WriteDataset(dataset, output, error);
}

}  // namespace rff
