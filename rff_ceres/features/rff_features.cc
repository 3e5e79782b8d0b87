#include "rff_ceres/features/rff_features.h"

#include <cmath>
#include <random>
#include <vector>

#include "rff_ceres/features/spectral_pair_features.h"

namespace rff {

std::unique_ptr<FeatureMap> CreateRffFeatures(const Kernel& kernel,
                                              const FeatureMapOptions& options,
                                              std::string* error) {
  if (!CheckEvenNumFeatures(options, error)) return nullptr;
  const int num_pairs = options.num_features / 2;
  std::mt19937_64 rng(options.seed);
  std::vector<double> frequencies(num_pairs);
  for (double& w : frequencies) w = kernel.SampleFrequency(&rng);
  const std::vector<double> amplitudes(
      num_pairs, std::sqrt(kernel.variance() / num_pairs));
  return std::make_unique<SpectralPairFeatures>(
      WindowCentre(options), -1.0, std::move(frequencies), amplitudes);
}

}  // namespace rff
