// The WNOA diffusion Q_c the odometry alone implies, a start for the
// learning rounds. Under white noise on acceleration of density Q_c the
// velocity is a Brownian motion, so the mean velocities of two adjacent
// windows of W seconds, (p(t + 2W) - 2 p(t + W) + p(t)) / W, differ with
// variance 2 Q_c W / 3 per axis (the LTV-SDE prior of Barfoot et al. 2014).
#ifndef RFF_CERES_PRIORS_ODOMETRY_DIFFUSION_H_
#define RFF_CERES_PRIORS_ODOMETRY_DIFFUSION_H_

#include <string>
#include <vector>

#include "Eigen/Core"
#include "rff_ceres/types.h"

namespace rff {

struct OdometryDiffusion {
  double position_qc = 0.0;  // Pooled over x and y.
  double heading_qc = 0.0;
  int windows = 0;  // Pairs of windows the estimate averages.
  double window_seconds = 0.0;
};

// Estimates from the dead reckoning of `odometry` (any order): W is the
// larger of 0.5 s and the median record's duration, and the windows fill
// the stretches of records no longer than W that meet end to end. False,
// saying why, where those records hold under half the odometry's time,
// fewer than 10 pairs fit, the chain does not integrate, or the estimate is
// not positive (no motion).
bool EstimateOdometryDiffusion(std::vector<Odometry> odometry,
                               OdometryDiffusion* diffusion, std::string* why);

}  // namespace rff

#endif  // RFF_CERES_PRIORS_ODOMETRY_DIFFUSION_H_
