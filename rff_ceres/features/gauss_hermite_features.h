// "gauss_hermite": Gauss-Hermite quadrature features (Munkhoeva, Kapushev,
// Burnaev & Oseledets 2018) for kernels whose spectral measure is
// p = N(0, 1 / lengthscale^2) (rbf). With the n = D point Gauss-Hermite rule
// (x_i, w_i) for the weight exp(-x^2),
//   k(tau) = variance E_p[cos(omega tau)]
//          ~ variance sum_i w_i / sqrt(pi) cos(sqrt(2) x_i tau / lengthscale).
// The nodes are symmetric, so the D / 2 positive ones carry twice the weight:
//   phi(t) = [a_i cos(w_i s), a_i sin(w_i s)]_i,
//   a_i = sqrt(2 variance w_i / sqrt(pi)),  w_i = sqrt(2) x_i / lengthscale.
// Nodes and weights: Golub-Welsch (eigen-decomposition of the Jacobi matrix).
// Exact to machine precision for lags up to ~sqrt(D) lengthscales; beyond
// that the regular-ish node spacing aliases (see docs/features.md).
#ifndef RFF_CERES_FEATURES_GAUSS_HERMITE_FEATURES_H_
#define RFF_CERES_FEATURES_GAUSS_HERMITE_FEATURES_H_

#include <memory>
#include <string>
#include <vector>

#include "rff_ceres/features/feature_map.h"

namespace rff {

// The n-point rule for the weight exp(-x^2) on the real line, nodes ascending.
void GaussHermiteRule(int n, std::vector<double>* nodes,
                      std::vector<double>* weights);

std::unique_ptr<FeatureMap> CreateGaussHermiteFeatures(
    const Kernel& kernel, const FeatureMapOptions& options, std::string* error);

}  // namespace rff

#endif  // RFF_CERES_FEATURES_GAUSS_HERMITE_FEATURES_H_
