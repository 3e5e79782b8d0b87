// "rff": the weight-space GP of the paper, x_k(t) = mu_k(t) + phi_k(t)^T b_k
// with b_k ~ N(0, I) over random Fourier features or a deterministic basis
// (FeatureTrajectory); its scales are the kernel variances.
#include "rff_ceres/data_stretches.h"
#include "rff_ceres/mean_rotation.h"
#include "rff_ceres/priors/trajectory_prior.h"

namespace rff {
namespace {

class FeaturePriorImpl : public TrajectoryPrior {
 public:
  const char* name() const override { return "rff"; }
  bool has_features() const override { return true; }

  bool CheckOptions(const SlamOptions& options,
                    std::string* error) const override {
    return FeatureTrajectory::CheckOptions(options.features, UnitWindowMean(),
                                           error);
  }

  std::unique_ptr<TrajectoryModel> CreateModel(
      const Dataset& dataset, const SlamOptions& options,
      const std::string& /*mean_name*/,
      std::shared_ptr<const MeanFunction> mean,
      std::string* error) const override {
    return FeatureTrajectory::Create(options.features, std::move(mean),
                                     DataTimesOf(dataset), error);
  }

  double* PositionScale(SlamOptions* options) const override {
    return &options->features.position_kernel.variance;
  }
  double* HeadingScale(SlamOptions* options) const override {
    return &options->features.heading_kernel.variance;
  }
  const char* scales_name() const override { return "variances"; }
  std::vector<std::string> scale_flags() const override {
    return {"lengthscale",         "kernel_variance",
            "heading_lengthscale", "heading_kernel_variance",
            "wnoa_position_qc",    "wnoa_heading_qc"};
  }

  void RecordModel(const TrajectoryModel& model,
                   SlamResult* result) const override {
    if (const auto* features =
            dynamic_cast<const FeatureTrajectory*>(InnerModel(&model))) {
      result->trajectory_options = features->options();
    }
  }

  void PrintModel(const SlamResult& result, std::ostream* out) const override {
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
};

}  // namespace

const TrajectoryPrior& FeaturePrior() {
  static const auto* prior = new FeaturePriorImpl;
  return *prior;
}

}  // namespace rff
