// "wnoa": the LTV-SDE prior of Barfoot et al. (white noise on acceleration),
// a pose and velocity state at the data's times (WnoaTrajectory); its scales
// are the diffusions Q_c of position and heading.
#include <algorithm>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "rff_ceres/option_error.h"
#include "rff_ceres/priors/odometry_diffusion.h"
#include "rff_ceres/priors/trajectory_prior.h"
#include "rff_ceres/slam_problem.h"
#include "rff_ceres/wnoa_trajectory.h"

namespace rff {
namespace {

constexpr double kMaxStartRatio = 1e6;

// Every time the data constrain: the states reach both ends. Ground truth
// only asks for outputs, which beyond the states extrapolate at constant
// velocity or acceleration (the posterior mean there).
void TimeSpan(const Dataset& dataset, double* begin, double* end) {
  std::vector<double> times;
  for (const Observation& o : dataset.observations) times.push_back(o.t);
  for (const Odometry& o : dataset.odometry) {
    times.push_back(o.t0);
    times.push_back(o.t1);
  }
  for (const PosePrior& p : dataset.pose_priors) times.push_back(p.pose.t);
  const auto [lo, hi] = std::minmax_element(times.begin(), times.end());
  *begin = *lo;
  *end = *hi;
}

class WnoaPriorImpl : public TrajectoryPrior {
 public:
  const char* name() const override { return "wnoa"; }
  bool has_features() const override { return false; }

  bool CheckOptions(const SlamOptions& options,
                    std::string* error) const override {
    if (!CheckOneOf(options.wnoa.qc_start, "wnoa_qc_start", "",
                    {"odometry", "given"}, error)) {
      return false;
    }
    return WnoaTrajectory::Create(options.wnoa, UnitWindowMean(), {0.0},
                                  error) != nullptr;
  }

  std::unique_ptr<TrajectoryModel> CreateModel(
      const Dataset& dataset, const SlamOptions& options,
      const std::string& mean_name, std::shared_ptr<const MeanFunction> mean,
      std::string* error) const override {
    std::vector<double> times;
    if (!StateTimes(dataset, options, mean_name, &times, error)) {
      return nullptr;
    }
    return WnoaTrajectory::Create(options.wnoa, std::move(mean),
                                  std::move(times), error);
  }

  double* PositionScale(SlamOptions* options) const override {
    return &options->wnoa.position_qc;
  }
  double* HeadingScale(SlamOptions* options) const override {
    return &options->wnoa.heading_qc;
  }
  // A Q_c from the motion itself: the default 1 m^2/s^3 is 36 (Plaza) to
  // 25000 (MRCLAM) times what recordings learn, tenfold steps a round away.
  void StartLearnedScales(const Dataset& dataset, SlamOptions* options,
                          SlamResult* result) const override {
    if (options->wnoa.qc_start != "odometry" ||
        !options->problem.use_odometry || dataset.odometry.empty()) {
      return;
    }
    std::string& why = result->qc_start_kept;
    OdometryDiffusion d;
    if (options->problem.odometry_calibration.estimate) {
      // The scale absorbs what the odometry says of the motion's size: Q_c
      // learned from such a start shrank the map with the scale.
      why = "the odometry's scale is estimated";
      return;
    }
    if (!EstimateOdometryDiffusion(dataset.odometry, &d, &why)) return;
    // Six of the rounds' tenfold steps reach as far from the given values;
    // beyond, the odometry barely moves (a robot standing still), and a Q_c
    // near zero would leave the first solve no digits.
    const double position = d.position_qc / options->wnoa.position_qc;
    const double heading = d.heading_qc / options->wnoa.heading_qc;
    if (std::max({position, heading, 1.0 / position, 1.0 / heading}) >
        kMaxStartRatio) {
      std::ostringstream out;
      out << "the odometry's " << d.position_qc << " (x, y), " << d.heading_qc
          << " (theta) are over " << kMaxStartRatio
          << " times off the given values";
      why = out.str();
      return;
    }
    options->wnoa.position_qc = d.position_qc;
    options->wnoa.heading_qc = d.heading_qc;
    result->qc_from_odometry = d;
  }
  const char* scales_name() const override { return "Q_c"; }
  std::vector<std::string> scale_flags() const override {
    return {"wnoa_position_qc", "wnoa_heading_qc"};
  }

  void PrintModel(const SlamResult& result, std::ostream* out) const override {
    *out << "  model        WNOA (LTV-SDE) prior, Q_c = "
         << result.wnoa_options.position_qc << " (x, y), "
         << result.wnoa_options.heading_qc << " (theta), " << result.prior_mean
         << " mean\n";
  }
};

}  // namespace

bool StateTimes(const Dataset& dataset, const SlamOptions& options,
                const std::string& mean_name, std::vector<double>* times,
                std::string* error) {
  // A state at every distinct observation time, and at both ends of the
  // data (ground truth beyond them extrapolates). A constant mean leaves
  // the motion to the states: one at each end of every odometry residual
  // too, or the polynomial between states could not follow it (a 64 s
  // stretch without observations would be one cubic).
  double t_begin, t_end;
  TimeSpan(dataset, &t_begin, &t_end);
  *times = {t_begin, t_end};
  for (const Observation& o : dataset.observations) times->push_back(o.t);
  std::vector<PreintegratedOdometry> chains;
  if (mean_name == "constant" &&
      !OdometryChains(dataset, options.problem, &chains, error)) {
    return false;
  }
  for (const PreintegratedOdometry& chain : chains) {
    times->push_back(chain.t0);
    times->push_back(chain.t1);
  }
  return true;
}

const TrajectoryPrior& WnoaPrior() {
  static const auto* prior = new WnoaPriorImpl;
  return *prior;
}

}  // namespace rff
