#include "rff_ceres/priors/feature_prior.h"

#include "rff_ceres/data_stretches.h"

namespace rff {

bool FeaturePrior::CheckOptions(const SlamOptions& options,
                                std::string* error) const {
  return FeatureTrajectory::Create(options.trajectory, UnitWindowMean(), 0.0,
                                   1.0, error) != nullptr;
}

std::unique_ptr<TrajectoryModel> FeaturePrior::CreateModel(
    const Dataset& dataset, const SlamOptions& options,
    const std::string& /*mean_name*/, std::shared_ptr<const MeanFunction> mean,
    std::string* error) const {
  return FeatureTrajectory::Create(options.trajectory, std::move(mean),
                                   DataTimesOf(dataset), error);
}

double* FeaturePrior::PositionScale(SlamOptions* options) const {
  return &options->trajectory.position_kernel.variance;
}

double* FeaturePrior::HeadingScale(SlamOptions* options) const {
  return &options->trajectory.heading_kernel.variance;
}

void FeaturePrior::PrintModel(const SlamResult& result,
                              std::ostream* out) const {
  const FeatureTrajectoryOptions& t = result.trajectory_options;
  *out << "  model        " << t.family << " features, "
       << t.position_kernel.name << " kernel, D = " << t.num_position_features
       << " (x, y), " << t.num_heading_features << " (theta), "
       << result.prior_mean << " mean";
  if (result.prior_mean == "wnoa") {
    *out << " (a WNOA solve, " << result.mean_seconds << " s)";
  }
  *out << "\n";
  *out << "  kernels      lengthscale " << t.position_kernel.lengthscale
       << " s, variance " << t.position_kernel.variance
       << " (x, y); lengthscale " << t.heading_kernel.lengthscale
       << " s, variance " << t.heading_kernel.variance << " (theta)";
  if (t.segment_length > 0.0) {
    *out << "; segments of " << t.segment_length << " s blended over "
         << t.segment_overlap << " s";
  }
  *out << "\n";
  if (result.learning.evaluations > 0) {
    *out << "  learned      by the evidence (data linearised in poses) on "
            "the first "
         << result.learning.window_end - result.trajectory.front().t
         << " s: log evidence " << result.learning.log_evidence << ", "
         << result.learning.evaluations << " evaluations, "
         << result.learning.seconds << " s\n";
  }
}

}  // namespace rff
