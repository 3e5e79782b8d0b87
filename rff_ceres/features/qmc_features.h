// "qmc": quasi-Monte-Carlo Fourier features. In one dimension the best
// low-discrepancy point set is the midpoint rule: M = D / 2 frequencies
//   w_i = Q(1/2 + (i + 1/2) / (2 M)),  i = 0 .. M - 1,
// with Q the quantile of p, i.e. the midpoint quantiles of |omega| (cos is
// even in omega, so the negative half would only duplicate features), and
//   phi(t) = sqrt(variance / M) [cos(w_i s), sin(w_i s)]_i,  s = t - centre.
// Deterministic (the seed is unused). Like any regular grid of frequencies it
// aliases: k_hat stops decaying at lags of order 2 pi / (w_{i+1} - w_i).
#ifndef RFF_CERES_FEATURES_QMC_FEATURES_H_
#define RFF_CERES_FEATURES_QMC_FEATURES_H_

#include <memory>
#include <string>

#include "rff_ceres/features/feature_map.h"

namespace rff {

std::unique_ptr<FeatureMap> CreateQmcFeatures(const Kernel& kernel,
                                              const FeatureMapOptions& options,
                                              std::string* error);

}  // namespace rff

#endif  // RFF_CERES_FEATURES_QMC_FEATURES_H_
