#include "rff_ceres/features/feature_map.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "rff_ceres/features/gauss_hermite_features.h"
#include "rff_ceres/features/hilbert_features.h"
#include "rff_ceres/features/qmc_features.h"
#include "rff_ceres/features/rff_features.h"
#include "rff_ceres/features/spectral_pair_features.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/option_error.h"

namespace rff {
namespace {

using FamilyFactory = std::unique_ptr<FeatureMap> (*)(const Kernel&,
                                                      const FeatureMapOptions&,
                                                      std::string*);
struct FamilyEntry {
  const char* name;
  FamilyFactory create;
};

// The registry: one line per family.
const std::vector<FamilyEntry>& Registry() {
  static const std::vector<FamilyEntry> registry = {
      {"rff", &CreateRffFeatures},
      {"qmc", &CreateQmcFeatures},
      {"gauss_hermite", &CreateGaussHermiteFeatures},
      {"hilbert", &CreateHilbertFeatures},
  };
  return registry;
}

bool CheckOptions(const FeatureMapOptions& options, std::string* error) {
  if (options.num_features <= 0 || options.num_features > kMaxNumFeatures) {
    *error = OptionError(options.num_features_flag,
                         std::to_string(options.num_features), "",
                         "1 to " + std::to_string(kMaxNumFeatures));
    return false;
  }
  // The window comes from the caller's times, not from an option.
  std::ostringstream message;
  if (!std::isfinite(options.window_begin) ||
      !std::isfinite(options.window_end) ||
      !(options.window_end > options.window_begin)) {
    message << options.family << ": window [" << options.window_begin << ", "
            << options.window_end << "] must be finite with end > begin";
  } else if (std::max(std::abs(options.window_begin),
                      std::abs(options.window_end)) > kMaxFeatureWindowTime) {
    message << options.family << ": window [" << options.window_begin << ", "
            << options.window_end << "] exceeds +-" << kMaxFeatureWindowTime
            << " s; pass times relative to the window origin";
  } else {
    return CheckNonNegativeOption(options.hilbert_margin, "hilbert_margin",
                                  error) &&
           CheckNonNegativeOption(options.hilbert_min_margin,
                                  "hilbert_min_margin", error);
  }
  *error = message.str();
  return false;
}

}  // namespace

void FeatureMap::Evaluate(const std::vector<double>& times,
                          Eigen::MatrixXd* phi, Eigen::MatrixXd* dphi) const {
  const int rows = static_cast<int>(times.size());
  const int cols = num_features();
  // Row-major scratch: Evaluate writes one contiguous row per time.
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> p(
      rows, cols);
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> d;
  if (dphi != nullptr) d.resize(rows, cols);
  for (int i = 0; i < rows; ++i) {
    Evaluate(times[i], p.row(i).data(),
             dphi != nullptr ? d.row(i).data() : nullptr);
  }
  *phi = p;
  if (dphi != nullptr) *dphi = d;
}

std::unique_ptr<FeatureMap> CreateFeatureMap(const Kernel& kernel,
                                             const FeatureMapOptions& options,
                                             std::string* error) {
  for (const FamilyEntry& entry : Registry()) {
    if (options.family != entry.name) continue;
    if (!CheckOptions(options, error)) return nullptr;
    if (!kernel.has_spectral_density()) {
      return CreateFourierSeriesFeatures(kernel, options, error);
    }
    return entry.create(kernel, options, error);
  }
  *error = OptionError("features", options.family, "unknown feature family",
                       JoinAlternatives(FeatureFamilyNames()));
  return nullptr;
}

std::vector<std::string> FeatureFamilyNames() {
  std::vector<std::string> names;
  for (const FamilyEntry& entry : Registry()) names.push_back(entry.name);
  return names;
}

double MaxKernelError(const Kernel& kernel, const FeatureMap& map,
                      double window_begin, double window_end, double max_lag,
                      int num_grid) {
  num_grid = std::max(num_grid, 2);
  const double step = (window_end - window_begin) / (num_grid - 1);
  std::vector<double> times(num_grid);
  for (int i = 0; i < num_grid; ++i) times[i] = window_begin + i * step;
  Eigen::MatrixXd phi;
  map.Evaluate(times, &phi, nullptr);
  const Eigen::MatrixXd gram = phi * phi.transpose();
  double worst = 0.0;
  for (int i = 0; i < num_grid; ++i) {
    for (int j = i; j < num_grid; ++j) {
      const double lag = times[j] - times[i];
      if (max_lag >= 0.0 && lag > max_lag + 1e-9 * step) break;
      worst = std::max(worst, std::abs(gram(i, j) - kernel.Evaluate(lag)));
    }
  }
  return worst;
}

bool DefaultNumFeatures(const Kernel& kernel, const FeatureMapOptions& options,
                        double tolerance, int max_features, int* num_features,
                        std::string* error) {
  const double window = options.window_end - options.window_begin;
  // Resolve the kernel's shape: a quarter lengthscale, or for the periodic
  // kernel (dimensionless lengthscale) a fortieth of min(1, l) periods.
  const bool periodic = !kernel.has_spectral_density();
  double spacing = kernel.lengthscale() / 4.0;
  double max_lag = 3.0 * kernel.lengthscale();
  if (periodic) {
    std::vector<double> frequencies, coefficients;
    kernel.FourierSeries(2, &frequencies, &coefficients);
    const double period = 2.0 * M_PI / frequencies[1];
    spacing = period * std::min(kernel.lengthscale(), 1.0) / 40.0;
    max_lag = period;
  }
  const int num_grid = static_cast<int>(
      std::min(2001.0, std::max(101.0, std::ceil(window / spacing) + 1.0)));
  FeatureMapOptions trial = options;
  double last_error = -1.0;
  for (int d = 2; d <= std::min(max_features, kMaxNumFeatures); d *= 2) {
    trial.num_features = periodic ? d - 1 : d;
    std::unique_ptr<FeatureMap> map = CreateFeatureMap(kernel, trial, error);
    if (map == nullptr) return false;
    last_error = MaxKernelError(kernel, *map, options.window_begin,
                                options.window_end, max_lag, num_grid);
    if (last_error <= tolerance) {
      *num_features = trial.num_features;
      return true;
    }
  }
  std::ostringstream message;
  message << options.family << ": no num_features <= " << max_features
          << " reaches a kernel error of " << tolerance
          << " (last: " << last_error << ")";
  *error = message.str();
  return false;
}

}  // namespace rff
