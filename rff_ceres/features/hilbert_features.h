// "hilbert": the reduced-rank Hilbert-space basis of Solin & Sarkka (2020):
// eigenfunctions of the Laplacian on [centre - L, centre + L] with Dirichlet
// boundary conditions, L = window length / 2 + margin (see FeatureMapOptions):
//   phi_j(t) = sqrt(S(w_j) / L) sin(w_j (t - centre + L)),  w_j = pi j / (2 L),
// for j = 1 .. D, so k(t, t') ~ sum_j S(sqrt(lambda_j)) phi_j(t) phi_j(t') with
// lambda_j = w_j^2 and S in the convention of kernel.h. Not stationary: the
// approximation degrades within a few lengthscales of the domain ends, and
// vanishes at them; only times inside the window are meant to be evaluated.
// D must cover the spectrum: w_D = pi D / (2 L) beyond the kernel's bandwidth,
// i.e. D >= c * L / lengthscale (see docs/features.md for c).
#ifndef RFF_CERES_FEATURES_HILBERT_FEATURES_H_
#define RFF_CERES_FEATURES_HILBERT_FEATURES_H_

#include <memory>
#include <string>
#include <vector>

#include "rff_ceres/features/feature_map.h"

namespace rff {

class HilbertFeatures : public FeatureMap {
 public:
  HilbertFeatures(double centre, double half_width,
                  std::vector<double> amplitudes);
  int num_features() const override {
    return static_cast<int>(amplitudes_.size());
  }
  void Evaluate(double t, double* phi, double* dphi) const override;
  using FeatureMap::Evaluate;
  double half_width() const { return half_width_; }

 private:
  double centre_;
  double half_width_;  // L
  std::vector<double> amplitudes_;
};

// The domain half-width L the options give (window / 2 plus the margin).
double HilbertHalfWidth(const Kernel& kernel, const FeatureMapOptions& options);

// Rule of thumb for D: the basis resolves frequencies up to pi D / (2 L), so
// k_hat(t, t) misses the spectral mass beyond; choose D so that this mass is
// `tolerance` (absolute, in variance units):
//   D = ceil(2 L Q(1 - tolerance / (2 variance)) / pi),  Q the quantile of p.
// For rbf this is D ~ 2 L z / (pi l) with z the normal quantile (3.3 for
// 1e-3). Kernels with a density only; at least 1.
int HilbertNumFeatures(const Kernel& kernel, const FeatureMapOptions& options,
                       double tolerance);

// The number of modes D' > D of a map on [centre - L, centre + L] whose
// missed spectral mass, 1 - P(pi (D' + 1/2) / (2 L)) of the normalised
// density, is at most `fraction` of D's; at most `most`.
int HilbertModesForTail(const Kernel& kernel, double half_width, int d,
                        double fraction, int most);

std::unique_ptr<FeatureMap> CreateHilbertFeatures(
    const Kernel& kernel, const FeatureMapOptions& options, std::string* error);

}  // namespace rff

#endif  // RFF_CERES_FEATURES_HILBERT_FEATURES_H_
