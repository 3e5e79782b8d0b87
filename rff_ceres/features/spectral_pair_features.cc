#include "rff_ceres/features/spectral_pair_features.h"

#include <cmath>
#include <utility>

#include "rff_ceres/option_error.h"

namespace rff {

SpectralPairFeatures::SpectralPairFeatures(double centre, double constant,
                                           std::vector<double> frequencies,
                                           std::vector<double> amplitudes)
    : centre_(centre),
      constant_(constant),
      frequencies_(std::move(frequencies)),
      amplitudes_(std::move(amplitudes)) {}

int SpectralPairFeatures::num_features() const {
  return (constant_ >= 0.0 ? 1 : 0) + 2 * static_cast<int>(frequencies_.size());
}

void SpectralPairFeatures::Evaluate(double t, double* phi, double* dphi) const {
  const double s = t - centre_;
  if (constant_ >= 0.0) {
    *phi++ = constant_;
    if (dphi != nullptr) *dphi++ = 0.0;
  }
  for (size_t i = 0; i < frequencies_.size(); ++i) {
    const double w = frequencies_[i];
    const double a = amplitudes_[i];
    const double c = std::cos(w * s);
    const double sn = std::sin(w * s);
    phi[2 * i] = a * c;
    phi[2 * i + 1] = a * sn;
    if (dphi != nullptr) {
      dphi[2 * i] = -a * w * sn;
      dphi[2 * i + 1] = a * w * c;
    }
  }
}

double WindowCentre(const FeatureMapOptions& options) {
  return 0.5 * (options.window_begin + options.window_end);
}

bool CheckEvenNumFeatures(const FeatureMapOptions& options,
                          std::string* error) {
  if (options.num_features % 2 == 0) return true;
  *error = OptionError(
      options.num_features_flag, std::to_string(options.num_features),
      options.family + " features come in cos/sin pairs", "even numbers");
  return false;
}

std::unique_ptr<FeatureMap> CreateFourierSeriesFeatures(
    const Kernel& kernel, const FeatureMapOptions& options,
    std::string* error) {
  if (options.num_features % 2 == 0) {
    *error = OptionError(
        options.num_features_flag, std::to_string(options.num_features),
        "the " + kernel.name() + " kernel's features are 1 + 2 x harmonics",
        "odd numbers");
    return nullptr;
  }
  const int num_terms = (options.num_features + 1) / 2;
  std::vector<double> frequencies;
  std::vector<double> coefficients;
  if (!kernel.FourierSeries(num_terms, &frequencies, &coefficients)) {
    *error = kernel.name() + " kernel has no cosine series";
    return nullptr;
  }
  std::vector<double> amplitudes(num_terms - 1);
  for (int j = 1; j < num_terms; ++j) {
    amplitudes[j - 1] = std::sqrt(coefficients[j]);
  }
  return std::make_unique<SpectralPairFeatures>(
      WindowCentre(options), std::sqrt(coefficients[0]),
      std::vector<double>(frequencies.begin() + 1, frequencies.end()),
      std::move(amplitudes));
}

}  // namespace rff
