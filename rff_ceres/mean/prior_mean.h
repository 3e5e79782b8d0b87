// Builds the prior mean mu(t) of the trajectory from a dataset (paper
// section III-B): the odometry motion model, a constant pose, or "auto"
// (odometry when the dataset has ODOM records).
#ifndef RFF_CERES_MEAN_PRIOR_MEAN_H_
#define RFF_CERES_MEAN_PRIOR_MEAN_H_

#include <memory>
#include <string>
#include <vector>

#include "rff_ceres/mean/mean_function.h"
#include "rff_ceres/types.h"

namespace rff {

// Registered prior-mean names, for flag help and validation.
std::vector<std::string> PriorMeanNames();

// "odometry": dead reckoning from the earliest PRIOR_POSE (paper III-B.1).
// "constant": the earliest PRIOR_POSE at every time.
// "auto": odometry if the dataset has ODOM records, else constant.
std::shared_ptr<const MeanFunction> BuildPriorMean(const std::string& name,
                                                   const Dataset& dataset,
                                                   std::string* error);

}  // namespace rff

#endif  // RFF_CERES_MEAN_PRIOR_MEAN_H_
