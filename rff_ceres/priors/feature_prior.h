// "rff": the weight-space GP of the paper, x_k(t) = mu_k(t) + phi_k(t)^T b_k
// with b_k ~ N(0, I) over random Fourier features or a deterministic basis
// (FeatureTrajectory); its scales are the kernel variances.
#ifndef RFF_CERES_PRIORS_FEATURE_PRIOR_H_
#define RFF_CERES_PRIORS_FEATURE_PRIOR_H_

#include "rff_ceres/priors/trajectory_prior.h"

namespace rff {

class FeaturePrior : public TrajectoryPrior {
 public:
  static constexpr char kName[] = "rff";

  const char* name() const override { return kName; }
  bool has_features() const override { return true; }
  bool CheckOptions(const SlamOptions& options,
                    std::string* error) const override;
  std::unique_ptr<TrajectoryModel> CreateModel(
      const Dataset& dataset, const SlamOptions& options,
      const std::string& mean_name, std::shared_ptr<const MeanFunction> mean,
      std::string* error) const override;
  double* PositionScale(SlamOptions* options) const override;
  double* HeadingScale(SlamOptions* options) const override;
  const char* scales_name() const override { return "variances"; }
  void PrintModel(const SlamResult& result, std::ostream* out) const override;
};

}  // namespace rff

#endif  // RFF_CERES_PRIORS_FEATURE_PRIOR_H_
