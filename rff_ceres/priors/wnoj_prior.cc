// "wnoj": the white-noise-on-jerk prior (Tang et al. 2019), a pose, velocity
// and acceleration state at the data's times (WnojTrajectory); its scales
// are the diffusions Q_c of position and heading.
#include <utility>
#include <vector>

#include "rff_ceres/priors/trajectory_prior.h"
#include "rff_ceres/wnoj_trajectory.h"

namespace rff {
namespace {

class WnojPriorImpl : public TrajectoryPrior {
 public:
  const char* name() const override { return "wnoj"; }
  bool has_features() const override { return false; }

  bool CheckOptions(const SlamOptions& options,
                    std::string* error) const override {
    return WnojTrajectory::Create(options.wnoj, options.wnoa, UnitWindowMean(),
                                  {0.0}, error) != nullptr;
  }

  std::unique_ptr<TrajectoryModel> CreateModel(
      const Dataset& dataset, const SlamOptions& options,
      const std::string& mean_name, std::shared_ptr<const MeanFunction> mean,
      std::string* error) const override {
    std::vector<double> times;
    if (!StateTimes(dataset, options, mean_name, &times, error)) {
      return nullptr;
    }
    return WnojTrajectory::Create(options.wnoj, options.wnoa, std::move(mean),
                                  std::move(times), error);
  }

  double* PositionScale(SlamOptions* options) const override {
    return &options->wnoj.position_qc;
  }
  double* HeadingScale(SlamOptions* options) const override {
    return &options->wnoj.heading_qc;
  }
  const char* scales_name() const override { return "Q_c"; }
  std::vector<std::string> scale_flags() const override {
    return {"wnoj_position_qc", "wnoj_heading_qc"};
  }

  void PrintModel(const SlamResult& result, std::ostream* out) const override {
    *out << "  model        WNOJ (white noise on jerk) prior, Q_c = "
         << result.wnoj_options.position_qc << " (x, y), "
         << result.wnoj_options.heading_qc << " (theta), " << result.prior_mean
         << " mean\n";
  }
};

}  // namespace

const TrajectoryPrior& WnojPrior() {
  static const auto* prior = new WnojPriorImpl;
  return *prior;
}

}  // namespace rff
