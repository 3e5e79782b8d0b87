// "wnoa": the LTV-SDE prior of Barfoot et al. (white noise on acceleration),
// a pose and velocity state at the data's times (WnoaTrajectory); its scales
// are the diffusions Q_c of position and heading.
#ifndef RFF_CERES_PRIORS_WNOA_PRIOR_H_
#define RFF_CERES_PRIORS_WNOA_PRIOR_H_

#include "rff_ceres/priors/trajectory_prior.h"

namespace rff {

class WnoaPrior : public TrajectoryPrior {
 public:
  static constexpr char kName[] = "wnoa";

  const char* name() const override { return kName; }
  bool has_features() const override { return false; }
  bool CheckOptions(const SlamOptions& options,
                    std::string* error) const override;
  std::unique_ptr<TrajectoryModel> CreateModel(
      const Dataset& dataset, const SlamOptions& options,
      const std::string& mean_name, std::shared_ptr<const MeanFunction> mean,
      std::string* error) const override;
  double* PositionScale(SlamOptions* options) const override;
  double* HeadingScale(SlamOptions* options) const override;
  const char* scales_name() const override { return "Q_c"; }
  void PrintModel(const SlamResult& result, std::ostream* out) const override;
};

}  // namespace rff

#endif  // RFF_CERES_PRIORS_WNOA_PRIOR_H_
