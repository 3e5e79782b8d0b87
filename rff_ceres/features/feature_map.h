// Weight-space approximations of a stationary kernel on 1-D time: a feature
// map phi: R -> R^D with phi(t)^T phi(t') ~ k(t - t'), so that the trajectory
// x(t) = mu(t) + phi(t)^T b, b ~ N(0, I), has (approximately) covariance k.
//
// Families ("rff", "qmc", "gauss_hermite", "hilbert") differ in how they
// discretise the kernel's spectrum; see docs/features.md for the formulas and
// the approximation errors. Every map is deterministic given its options
// (the seed included), and all randomness is drawn once, at construction.
//
// Times: callers pass t in seconds RELATIVE to their window origin (never
// absolute Unix time): the window is [window_begin, window_end] in the same
// frame, |window_begin|, |window_end| <= kMaxFeatureWindowTime. The maps
// evaluate cos/sin at omega (t - window centre), so phases stay accurate to
// ~1e-11 rad for |t| up to 1e4 s and omega up to 10 rad/s.
#ifndef RFF_CERES_FEATURES_FEATURE_MAP_H_
#define RFF_CERES_FEATURES_FEATURE_MAP_H_

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "rff_ceres/kernels/kernel.h"

namespace rff {

// Largest |window_begin|, |window_end| accepted (seconds): larger values
// almost surely are absolute timestamps.
inline constexpr double kMaxFeatureWindowTime = 1e6;
// Largest number of features of any map (memory and build-time guard).
inline constexpr int kMaxNumFeatures = 1 << 16;
// Gauss-Hermite nodes come from a dense eigenproblem (O(D^3)).
inline constexpr int kMaxGaussHermiteFeatures = 1024;

class FeatureMap {
 public:
  virtual ~FeatureMap() = default;
  virtual int num_features() const = 0;
  // phi(t) (num_features() values) and, when `dphi` is not null, d phi / dt.
  virtual void Evaluate(double t, double* phi, double* dphi) const = 0;
  // Row i of `phi` (and of `dphi` when not null) is phi(times[i]).
  void Evaluate(const std::vector<double>& times, Eigen::MatrixXd* phi,
                Eigen::MatrixXd* dphi) const;
};

struct FeatureMapOptions {
  std::string family = "rff";
  // D. "rff", "qmc", "gauss_hermite": even (cos/sin pairs); "hilbert": any
  // D >= 1; a periodic kernel (any family): odd, 1 + 2 * harmonics.
  int num_features = 64;
  uint64_t seed = 0;  // "rff" only; the other families are deterministic.
  double window_begin = 0.0;  // seconds, relative frame (see above)
  double window_end = 1.0;
  // "hilbert": the domain is the window extended on each side by
  // max(hilbert_margin * window length / 2, hilbert_min_margin * lengthscale)
  // seconds. Dirichlet boundary conditions pull k_hat(t, t') down by about
  // k(2 d) at a distance d from a domain end, so the extension must span a
  // few lengthscales (4 of them: 1e-14 for rbf, 1e-5 matern32, 3e-4 matern12).
  double hilbert_margin = 0.1;
  double hilbert_min_margin = 4.0;  // lengthscales
  // The flag that sets D, for messages ("num_heading_features" for theta).
  std::string num_features_flag = "num_features";
};

// Builds the map. Unknown family, D out of range or of the wrong parity, an
// empty or non-finite window, |window| > kMaxFeatureWindowTime, a negative
// or non-finite margin, or a kernel the family cannot represent: nullptr and
// `error`.
std::unique_ptr<FeatureMap> CreateFeatureMap(const Kernel& kernel,
                                             const FeatureMapOptions& options,
                                             std::string* error);

// The registered family names, in registry order.
std::vector<std::string> FeatureFamilyNames();

// Max |phi(t)^T phi(t') - k(t - t')| over a uniform grid of `num_grid` times
// covering [window_begin, window_end] and all grid pairs with
// |t - t'| <= max_lag (pass a negative max_lag for every pair).
double MaxKernelError(const Kernel& kernel, const FeatureMap& map,
                      double window_begin, double window_end, double max_lag,
                      int num_grid);

// Smallest valid D among 2^k (rounded to the family's parity) whose map has
// MaxKernelError <= tolerance over lags up to 3 lengthscales (and up to one
// period for the periodic kernel) on the window. Tries D up to max_features;
// false and `error` if none reaches the tolerance.
bool DefaultNumFeatures(const Kernel& kernel, const FeatureMapOptions& options,
                        double tolerance, int max_features, int* num_features,
                        std::string* error);

}  // namespace rff

#endif  // RFF_CERES_FEATURES_FEATURE_MAP_H_
