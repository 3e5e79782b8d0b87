#include "rff_ceres/priors/odometry_diffusion.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "rff_ceres/dead_reckoning.h"
#include "rff_ceres/mean/mean_function.h"
#include "rff_ceres/metrics.h"

namespace rff {
namespace {

constexpr double kMinWindowSeconds = 0.5;
constexpr int kMinWindows = 10;
constexpr double kMinShare = 0.5;

}  // namespace

bool EstimateOdometryDiffusion(std::vector<Odometry> odometry,
                               OdometryDiffusion* diffusion, std::string* why) {
  *diffusion = OdometryDiffusion();
  if (odometry.empty()) {
    *why = "the run has no odometry";
    return false;
  }
  std::sort(odometry.begin(), odometry.end(),
            [](const Odometry& a, const Odometry& b) { return a.t0 < b.t0; });
  std::vector<double> durations;
  for (const Odometry& o : odometry) durations.push_back(o.t1 - o.t0);
  std::nth_element(durations.begin(), durations.begin() + durations.size() / 2,
                   durations.end());
  const double w = std::max(kMinWindowSeconds, durations[durations.size() / 2]);
  // Stretches of records no longer than a window, meeting end to end: a
  // longer record is a straight line whose second differences are zero, and
  // a gap holds the pose.
  std::vector<std::pair<double, double>> stretches;
  double recorded = 0.0, in_stretches = 0.0;
  for (const Odometry& o : odometry) {
    const double duration = o.t1 - o.t0;
    const bool short_record = duration <= w;
    recorded += duration;
    if (short_record) in_stretches += duration;
    const bool meets =
        !stretches.empty() &&
        std::abs(o.t0 - stretches.back().second) <= kTimeToleranceSeconds;
    if (short_record && meets) {
      stretches.back().second = o.t1;
    } else if (short_record) {
      stretches.push_back({o.t0, o.t1});
    }
  }
  std::ostringstream out;
  if (in_stretches < kMinShare * recorded) {
    // Then the estimate would describe the motion of a minority of the run.
    out << "the odometry's records no longer than " << w << " s cover "
        << in_stretches / recorded << " of its time, under " << kMinShare;
    *why = out.str();
    return false;
  }
  DeadReckoningOptions chain;
  chain.hold_through_gaps = true;
  std::vector<TimedPose> nodes;
  std::vector<OdometryGap> gaps;
  if (!IntegrateOdometry({odometry.front().t0, 0.0, 0.0, 0.0}, odometry, chain,
                         &nodes, &gaps, why)) {
    return false;
  }
  // Linear between the nodes, the heading unwound.
  const PiecewiseLinearMean chain_at(nodes);
  double position = 0.0, heading = 0.0;
  int windows = 0;
  for (const auto& [a, b] : stretches) {
    // Whole windows, their times by multiplication: a sum of steps would
    // lose the last one to rounding.
    const double steps = std::floor((b - a) / w + 1e-9);
    for (double k = 0.0; k + 2.0 <= steps; k += 1.0) {
      const double t = a + k * w;
      const Eigen::Vector3d d =
          (chain_at.Evaluate(t + 2.0 * w) - 2.0 * chain_at.Evaluate(t + w) +
           chain_at.Evaluate(t)) /
          w;
      position += 0.5 * d.head<2>().squaredNorm();
      heading += d.z() * d.z();
      ++windows;
    }
  }
  if (windows < kMinWindows) {
    out << "the odometry has " << windows << " pairs of adjacent " << w
        << " s windows of records no longer than one, under " << kMinWindows;
    *why = out.str();
    return false;
  }
  // Var(d) = 2 Q_c W / 3.
  const double to_qc = 3.0 / (2.0 * w * windows);
  diffusion->position_qc = position * to_qc;
  diffusion->heading_qc = heading * to_qc;
  diffusion->windows = windows;
  diffusion->window_seconds = w;
  if (!(diffusion->position_qc > 0.0 && diffusion->heading_qc > 0.0 &&
        std::isfinite(diffusion->position_qc + diffusion->heading_qc))) {
    out << "the odometry's second differences give Q_c "
        << diffusion->position_qc << " (x, y), " << diffusion->heading_qc
        << " (theta)";
    *why = out.str();
    *diffusion = OdometryDiffusion();
    return false;
  }
  return true;
}

}  // namespace rff
