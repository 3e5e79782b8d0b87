// The map shared by every spectral-sampling family: an optional constant
// feature followed by cos/sin pairs,
//   phi = [c0,] a_1 cos(w_1 s), a_1 sin(w_1 s), ..., a_M cos(w_M s), a_M
//   sin(w_M s)
// with s = t - centre, so phi(t)^T phi(t') = c0^2 + sum a_i^2 cos(w_i (t -
// t')): exactly stationary whatever the frequencies.
#ifndef RFF_CERES_FEATURES_SPECTRAL_PAIR_FEATURES_H_
#define RFF_CERES_FEATURES_SPECTRAL_PAIR_FEATURES_H_

#include <memory>
#include <string>
#include <vector>

#include "rff_ceres/features/feature_map.h"

namespace rff {

class SpectralPairFeatures : public FeatureMap {
 public:
  // `constant` < 0 means no constant feature.
  SpectralPairFeatures(double centre, double constant,
                       std::vector<double> frequencies,
                       std::vector<double> amplitudes);
  int num_features() const override;
  void Evaluate(double t, double* phi, double* dphi) const override;
  using FeatureMap::Evaluate;

  const std::vector<double>& frequencies() const { return frequencies_; }
  const std::vector<double>& amplitudes() const { return amplitudes_; }

 private:
  double centre_;
  double constant_;
  std::vector<double> frequencies_;
  std::vector<double> amplitudes_;
};

// The window centre, where every family puts its time origin.
double WindowCentre(const FeatureMapOptions& options);

// Fails with "--num_features=D: <family> features come in cos/sin pairs;
// allowed even numbers" (the flag of options.num_features_flag).
bool CheckEvenNumFeatures(const FeatureMapOptions& options, std::string* error);

// Kernels with a discrete spectrum (periodic), whatever the family: the first
// (D + 1) / 2 terms of the kernel's cosine series, D odd.
std::unique_ptr<FeatureMap> CreateFourierSeriesFeatures(
    const Kernel& kernel, const FeatureMapOptions& options, std::string* error);

}  // namespace rff

#endif  // RFF_CERES_FEATURES_SPECTRAL_PAIR_FEATURES_H_
