// Seeded perturbations of a dataset's priors, for held-out checks that the
// data itself does not offer: map priors off by a known amount, a start
// heading that is wrong or unknown. Measurements, odometry and ground truth
// are never changed, and each perturbation is recorded in a
// "# perturbation: ..." metadata line (seed included), so that the output
// says exactly how it differs from its input. See docs/heldout.md.
#ifndef RFF_CERES_PERTURB_H_
#define RFF_CERES_PERTURB_H_

#include <cstdint>
#include <optional>
#include <string>

#include "rff_ceres/types.h"

namespace rff {

struct PerturbOptions {
  // Standard deviation (m) of the independent N(0, offset^2) draw added to
  // each axis of every PRIOR_LANDMARK mean; the prior's sigma becomes
  // max(sigma, offset), so that the prior stays honest. 0: unchanged.
  double landmark_prior_offset = 0.0;
  // Rotation (degrees) of the heading of every PRIOR_POSE at the earliest
  // time, wrapped to (-pi, pi] after it.
  double start_heading_offset_deg = 0.0;
  // New sigma_theta (rad) of those PRIOR_POSEs; unset: unchanged. pi says
  // "the start heading is unknown".
  std::optional<double> start_heading_sigma;
  // Seed of the landmark draws (SimulationRandom); the same seed gives the
  // same output bit for bit.
  std::uint64_t seed = 1;
};

// Largest landmark_prior_offset and start_heading_sigma accepted.
inline constexpr double kMaxPerturbMagnitude = 1e6;

// Checks every option; on failure `error` names the option, its value and
// the allowed range ("--landmark_prior_offset=-1: allowed 0 to 1e+06 m").
bool ValidatePerturbOptions(const PerturbOptions& options, std::string* error);

// Whether the options change the landmark priors or the start heading.
bool ChangesLandmarkPriors(const PerturbOptions& options);
bool ChangesStartHeading(const PerturbOptions& options);

// Applies `options` to `dataset` and appends one "perturbation" metadata
// pair per change. Fails, leaving `dataset` untouched, on invalid options,
// on a heading change without a PRIOR_POSE and on a landmark offset without
// a PRIOR_LANDMARK.
bool PerturbDataset(const PerturbOptions& options, Dataset* dataset,
                    std::string* error);

// Reads `input` (.rffd), perturbs it and writes `output`. Refuses options
// that change nothing and an output that is the input (the same path or the
// same file) before reading anything, and writes nothing on any error;
// errors about the dataset are prefixed with the input path.
bool PerturbFile(const std::string& input, const std::string& output,
                 const PerturbOptions& options, std::string* error);

}  // namespace rff

#endif  // RFF_CERES_PERTURB_H_
