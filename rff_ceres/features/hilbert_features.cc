#include "rff_ceres/features/hilbert_features.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "rff_ceres/features/spectral_pair_features.h"

namespace rff {

HilbertFeatures::HilbertFeatures(double centre, double half_width,
                                 std::vector<double> amplitudes)
    : centre_(centre),
      half_width_(half_width),
      amplitudes_(std::move(amplitudes)) {}

void HilbertFeatures::Evaluate(double t, double* phi, double* dphi) const {
  const double x = t - centre_ + half_width_;
  const double base = M_PI / (2.0 * half_width_);
  for (size_t j = 0; j < amplitudes_.size(); ++j) {
    const double w = base * static_cast<double>(j + 1);
    phi[j] = amplitudes_[j] * std::sin(w * x);
    if (dphi != nullptr) dphi[j] = amplitudes_[j] * w * std::cos(w * x);
  }
}

double HilbertHalfWidth(const Kernel& kernel,
                        const FeatureMapOptions& options) {
  const double half_window = 0.5 * (options.window_end - options.window_begin);
  return half_window +
         std::max(options.hilbert_margin * half_window,
                  options.hilbert_min_margin * kernel.lengthscale());
}

int HilbertNumFeatures(const Kernel& kernel, const FeatureMapOptions& options,
                       double tolerance) {
  const double tail = std::clamp(tolerance / kernel.variance(), 1e-15, 1.0);
  const double bandwidth = kernel.FrequencyQuantile(1.0 - 0.5 * tail);
  const double d = 2.0 * HilbertHalfWidth(kernel, options) * bandwidth / M_PI;
  if (!(d < kMaxNumFeatures)) return kMaxNumFeatures;
  return std::max(1, static_cast<int>(std::ceil(d)));
}

int HilbertModesForTail(const Kernel& kernel, double half_width, int d,
                        double fraction, int most) {
  auto tail = [&](int modes) {
    return 1.0 - kernel.FrequencyCdf(M_PI * (modes + 0.5) / (2.0 * half_width));
  };
  // Below rounding the basis misses nothing: one more mode says so.
  const double missed = tail(d);
  if (!(missed > 1e-12)) return std::min(d + 1, most);
  const double target = fraction * missed;
  int modes = d + 1;
  while (modes < most && tail(modes) > target) ++modes;
  return std::min(modes, most);
}

std::unique_ptr<FeatureMap> CreateHilbertFeatures(
    const Kernel& kernel, const FeatureMapOptions& options,
    std::string* /*error*/) {
  const double half_width = HilbertHalfWidth(kernel, options);
  std::vector<double> amplitudes(options.num_features);
  for (int j = 0; j < options.num_features; ++j) {
    const double w = M_PI * (j + 1) / (2.0 * half_width);
    amplitudes[j] = std::sqrt(kernel.SpectralDensity(w) / half_width);
  }
  return std::make_unique<HilbertFeatures>(WindowCentre(options), half_width,
                                           std::move(amplitudes));
}

}  // namespace rff
