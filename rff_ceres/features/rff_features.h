// "rff": Monte-Carlo random Fourier features (Rahimi & Recht; eq. 3 of the
// RFF-SLAM paper). M = D / 2 frequencies w_i ~ p(omega) are drawn ONCE, when
// the map is built, from std::mt19937_64(seed):
//   phi(t) = sqrt(variance / M) [cos(w_i s), sin(w_i s)]_i,  s = t - centre.
// E[phi(t)^T phi(t')] = k(t - t'), error ~ variance * O(1 / sqrt(M)).
#ifndef RFF_CERES_FEATURES_RFF_FEATURES_H_
#define RFF_CERES_FEATURES_RFF_FEATURES_H_

#include <memory>
#include <string>

#include "rff_ceres/features/feature_map.h"

namespace rff {

std::unique_ptr<FeatureMap> CreateRffFeatures(const Kernel& kernel,
                                              const FeatureMapOptions& options,
                                              std::string* error);

}  // namespace rff

#endif  // RFF_CERES_FEATURES_RFF_FEATURES_H_
