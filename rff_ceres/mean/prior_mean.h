// Builds the prior mean mu(t) of the trajectory from a dataset (paper
// section III-B): the odometry motion model, localisation against the
// landmark priors, a smoothing spline, a constant pose, or "auto".
#ifndef RFF_CERES_MEAN_PRIOR_MEAN_H_
#define RFF_CERES_MEAN_PRIOR_MEAN_H_

#include <memory>
#include <string>
#include <vector>

#include "rff_ceres/mean/localization_mean.h"
#include "rff_ceres/mean/mean_function.h"
#include "rff_ceres/types.h"

namespace rff {

// Registered prior-mean names, for flag help and validation.
std::vector<std::string> PriorMeanNames();

// "odometry": dead reckoning from the earliest PRIOR_POSE (paper III-B.1).
// "localization": per-time localisation against the PRIOR_LANDMARK means,
//   smoothed robustly; fused with dead reckoning when the dataset has ODOM
//   (see localization_mean.h and docs/prior_means.md).
// "spline": a smoothing spline (De Boor's p = `spline_smoothing`) through the
//   "localization" mean at the observation times, the first round of the
//   paper's III-B.2.
// "constant": the earliest PRIOR_POSE at every time.
// "wnoa": the posterior mean of the WNOA prior given the whole dataset, for
//   the RFF prior; a solve, so RunSlam builds it (slam_solver.h) and this
//   function fails on it.
// "auto": odometry if the dataset has ODOM records, else constant: the mean
//   comes from the inputs only (the observations enter as residuals; a
//   localisation of them is the solver's initial value, not its mean).
// "localization" (also through "spline") uses `localization`.
std::shared_ptr<const MeanFunction> BuildPriorMean(
    const std::string& name, const Dataset& dataset,
    const LocalizationOptions& localization, double spline_smoothing,
    std::string* error);
// The paper's smoothing (III-B.2).
inline constexpr double kPaperSplineSmoothing = 0.98;
// The same with the default LocalizationOptions and the paper's smoothing.
std::shared_ptr<const MeanFunction> BuildPriorMean(const std::string& name,
                                                   const Dataset& dataset,
                                                   std::string* error);

}  // namespace rff

#endif  // RFF_CERES_MEAN_PRIOR_MEAN_H_
