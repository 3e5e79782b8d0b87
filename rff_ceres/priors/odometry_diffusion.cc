#include "rff_ceres/priors/odometry_diffusion.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "costs/angle.h"
#include "rff_ceres/dead_reckoning.h"

namespace rff {
namespace {

constexpr double kMinWindowSeconds = 0.5;
constexpr int kMinWindows = 10;
constexpr double kWindowsPerRecord = 4.0;

// The chain's pose at t by linear interpolation of its nodes, heading
// unwound (`nodes` sorted, t inside their span).
Eigen::Vector3d PoseAt(const std::vector<TimedPose>& nodes,
                       const std::vector<double>& unwound, double t) {
  const auto it = std::upper_bound(
      nodes.begin(), nodes.end(), t,
      [](double time, const TimedPose& p) { return time < p.t; });
  const std::size_t i1 = std::min<std::size_t>(
      std::max<std::ptrdiff_t>(it - nodes.begin(), 1), nodes.size() - 1);
  const std::size_t i0 = i1 - 1;
  const double span = nodes[i1].t - nodes[i0].t;
  const double a = span > 0.0 ? (t - nodes[i0].t) / span : 0.0;
  return Eigen::Vector3d((1 - a) * nodes[i0].x + a * nodes[i1].x,
                         (1 - a) * nodes[i0].y + a * nodes[i1].y,
                         (1 - a) * unwound[i0] + a * unwound[i1]);
}

}  // namespace

bool EstimateOdometryDiffusion(const std::vector<Odometry>& odometry,
                               OdometryDiffusion* diffusion) {
  *diffusion = OdometryDiffusion();
  if (odometry.empty()) return false;
  std::vector<double> durations;
  double first = odometry.front().t0;
  for (const Odometry& o : odometry) {
    durations.push_back(o.t1 - o.t0);
    first = std::min(first, o.t0);
  }
  std::nth_element(durations.begin(), durations.begin() + durations.size() / 2,
                   durations.end());
  const double median = durations[durations.size() / 2];
  DeadReckoningOptions chain;
  chain.hold_through_gaps = true;
  std::vector<TimedPose> nodes;
  std::vector<OdometryGap> gaps;
  std::string error;
  if (!IntegrateOdometry({first, 0.0, 0.0, 0.0}, odometry, chain, &nodes, &gaps,
                         &error) ||
      nodes.size() < 2) {
    return false;
  }
  std::vector<double> unwound(nodes.size());
  unwound[0] = nodes[0].theta;
  for (std::size_t i = 1; i < nodes.size(); ++i) {
    unwound[i] =
        unwound[i - 1] + WrapAngle(nodes[i].theta - nodes[i - 1].theta);
  }
  // The stretches the records cover, between the gaps the chain held
  // through.
  std::sort(gaps.begin(), gaps.end(),
            [](const OdometryGap& a, const OdometryGap& b) {
              return a.begin < b.begin;
            });
  std::vector<std::pair<double, double>> stretches;
  double covered = 0.0;
  double begin = nodes.front().t;
  for (const OdometryGap& g : gaps) {
    stretches.push_back({begin, g.begin});
    covered += g.begin - begin;
    begin = g.end;
  }
  stretches.push_back({begin, nodes.back().t});
  covered += nodes.back().t - begin;
  // At most kWindowsPerRecord windows a record: a record of days among
  // records of 0.1 s widens the windows rather than the loop.
  const double w = std::max(
      {kMinWindowSeconds, median,
       covered / (kWindowsPerRecord * static_cast<double>(odometry.size()))});
  double position = 0.0, heading = 0.0;
  int windows = 0;
  for (const auto& [a, b] : stretches) {
    // Whole windows, their times by multiplication: a sum of steps would
    // lose the last one to rounding.
    const double steps = std::floor((b - a) / w + 1e-9);
    for (double k = 0.0; k + 2.0 <= steps; k += 1.0) {
      const double t = a + k * w;
      const Eigen::Vector3d d =
          (PoseAt(nodes, unwound, t + 2.0 * w) -
           2.0 * PoseAt(nodes, unwound, t + w) + PoseAt(nodes, unwound, t)) /
          w;
      position += 0.5 * d.head<2>().squaredNorm();
      heading += d.z() * d.z();
      ++windows;
    }
  }
  if (windows < kMinWindows) return false;
  // Var(d) = 2 Q_c W / 3.
  const double to_qc = 3.0 / (2.0 * w * windows);
  diffusion->position_qc = position * to_qc;
  diffusion->heading_qc = heading * to_qc;
  diffusion->windows = windows;
  diffusion->window_seconds = w;
  return diffusion->position_qc > 0.0 && diffusion->heading_qc > 0.0 &&
         std::isfinite(diffusion->position_qc + diffusion->heading_qc);
}

}  // namespace rff
