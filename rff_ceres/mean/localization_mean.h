// The "localization" prior mean, for data without odometry (and as a
// drift-free start with it): the robot is localised at each observation
// time against the PRIOR_LANDMARK means, the fixes are smoothed robustly in
// time, and the heading comes from the measurements or, for range-only
// data, from the direction of motion (paper section III-B). See
// docs/prior_means.md.
#ifndef RFF_CERES_MEAN_LOCALIZATION_MEAN_H_
#define RFF_CERES_MEAN_LOCALIZATION_MEAN_H_

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "Eigen/Core"
#include "rff_ceres/mean/mean_function.h"
#include "rff_ceres/types.h"

namespace rff {

// A landmark position known to the localiser and its standard deviation.
struct KnownLandmark {
  Eigen::Vector2d position = Eigen::Vector2d::Zero();
  double sigma = 0.0;
};

// One whitened residual row of an observation against a known landmark over
// the unknowns (x, y, theta).
struct MapResidualRow {
  double residual = 0.0;
  // The residual's derivative: a bearing's sigma moves with the range.
  Eigen::RowVector3d jacobian = Eigen::RowVector3d::Zero();
  // The measurement's derivative over its sigma held: the fix's information
  // (Fisher's, which does not grow with the residual).
  Eigen::RowVector3d measurement_jacobian = Eigen::RowVector3d::Zero();
};

// Whitened residuals of `observations` (landmarks missing from `landmarks`
// are skipped) at pose `p`: the measurement models of the solver's costs with
// the landmark's spread added (sigma_r^2 + s^2; sigma_b^2 + (s / r)^2). One
// row per measured value at every pose (a zero row for a bearing to a
// landmark on the robot), so the count does not depend on `p`.
std::vector<MapResidualRow> MapResiduals(
    const std::vector<Observation>& observations,
    const std::map<LandmarkId, KnownLandmark>& landmarks,
    const Eigen::Vector3d& p);

// One localisation: pose at time t and its covariance (x, y, theta). When the
// measurements carry no heading (range-only), has_heading is false and the
// heading is that of the seed.
struct PoseFix {
  TimedPose pose;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
  bool has_heading = false;
  // Whitened residual sum of squares and its degrees of freedom (0 when the
  // measurements just determine the pose, so nothing checks it).
  double chi2 = 0.0;
  int dof = 0;
};

// Localises the robot at one time from `observations` (all at that time) of
// landmarks in `landmarks` (others are ignored): Gauss-Newton on
// (x, y, theta), or (x, y) for range-only, started from every pose in
// `seeds`; among the minima within chi^2 4 of the lowest, the one nearest
// the first seed. The landmark sigma is added to the
// measurement noise (sigma_r^2 + s^2; sigma_b^2 + (s / r)^2). With
// `fixed_heading` (range-bearing from one landmark) the heading is held at
// that value, and its uncertainty `fixed_heading_sigma` is carried into the
// position covariance. Returns false when the measurements do not determine the
// pose (fewer equations than unknowns, or a degenerate geometry) or when no
// start converges.
bool LocalizePose(const std::vector<Observation>& observations,
                  const std::map<LandmarkId, KnownLandmark>& landmarks,
                  const std::vector<Eigen::Vector3d>& seeds,
                  const double* fixed_heading, double fixed_heading_sigma,
                  PoseFix* fix);

struct LocalizationOptions {
  // Acceleration noise density q (m^2/s^3) of the position smoother: the
  // spline minimises sum (fix - f)^2 / var + (1 / q) int f''^2. Larger
  // follows the fixes more closely.
  double position_smoothing = 0.2;
  // The same for the heading (rad^2/s^3), when the fixes carry it.
  double heading_smoothing = 0.005;
  // With odometry: the smoother of the correction (fix - dead reckoning),
  // which drifts slowly.
  double correction_smoothing = 1e-4;
  // Uncertainty of the predicted heading that a range-bearing fix from one
  // landmark holds (rad).
  double held_heading_sigma = 0.1;
  // The running prediction that seeds each time is a random walk filtered
  // through the fixes: of the pose without odometry, of the correction to
  // dead reckoning with it (spectral densities per second: m^2, rad^2).
  double walk_position = 4.0;
  double walk_heading = 0.1;
  double walk_correction_position = 0.01;
  double walk_correction_heading = 1e-3;
  // A fix whose chi^2 per degree of freedom exceeds this is discarded.
  double max_chi2_per_dof = 9.0;
  // Robust smoothing: iterations of reweighting (Cauchy weights at this
  // many standard deviations of the fix).
  int robust_iterations = 5;
  double robust_scale = 2.0;
  // Fuse ODOM when the dataset has it: the mean is dead reckoning plus the
  // smoothed correction towards the fixes.
  bool use_odometry = true;
};

// What the localiser did, for reports and tests.
struct LocalizationReport {
  int times = 0;      // Distinct observation times.
  int localized = 0;  // Fixes kept.
  int rejected = 0;   // Fixes discarded by the residual check.
  bool heading_from_velocity = false;
  bool fused_odometry = false;
  std::vector<PoseFix> fixes;  // The kept fixes, in time order.
};

// Fails, naming the option as localization_<field>, when a smoothing density
// or the held heading sigma is not finite and positive.
bool CheckLocalizationOptions(const LocalizationOptions& options,
                              std::string* error);

// Builds the mean. Fails with a clear message when the dataset has no
// landmark priors, or when no time can be localised.
std::shared_ptr<const MeanFunction> BuildLocalizationMean(
    const Dataset& dataset, const LocalizationOptions& options,
    LocalizationReport* report, std::string* error);

}  // namespace rff

#endif  // RFF_CERES_MEAN_LOCALIZATION_MEAN_H_
