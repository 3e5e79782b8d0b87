#include "rff_ceres/features/qmc_features.h"

#include <cmath>
#include <vector>

#include "rff_ceres/features/spectral_pair_features.h"

namespace rff {

std::unique_ptr<FeatureMap> CreateQmcFeatures(const Kernel& kernel,
                                              const FeatureMapOptions& options,
                                              std::string* error) {
  if (!CheckEvenNumFeatures(options, error)) return nullptr;
  const int num_pairs = options.num_features / 2;
  std::vector<double> frequencies(num_pairs);
  for (int i = 0; i < num_pairs; ++i) {
    const double u = 0.5 + 0.5 * (i + 0.5) / num_pairs;
    frequencies[i] = kernel.FrequencyQuantile(u);
  }
  const std::vector<double> amplitudes(
      num_pairs, std::sqrt(kernel.variance() / num_pairs));
  return std::make_unique<SpectralPairFeatures>(
      WindowCentre(options), -1.0, std::move(frequencies), amplitudes);
}

}  // namespace rff
