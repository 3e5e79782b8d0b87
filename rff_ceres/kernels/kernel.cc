#include "rff_ceres/kernels/kernel.h"

#include <cmath>
#include <functional>

#include "rff_ceres/kernels/matern_kernel.h"
#include "rff_ceres/kernels/periodic_kernel.h"
#include "rff_ceres/kernels/rbf_kernel.h"
#include "rff_ceres/option_error.h"

namespace rff {
namespace {

struct KernelEntry {
  const char* name;
  std::function<std::unique_ptr<Kernel>(const KernelOptions&)> create;
};

// The registry: one line per kernel.
const std::vector<KernelEntry>& Registry() {
  static const std::vector<KernelEntry> registry = {
      {"rbf",
       [](const KernelOptions& o) {
         return std::make_unique<RbfKernel>(o.variance, o.lengthscale);
       }},
      {"matern12",
       [](const KernelOptions& o) {
         return std::make_unique<MaternKernel>(1, o.variance, o.lengthscale);
       }},
      {"matern32",
       [](const KernelOptions& o) {
         return std::make_unique<MaternKernel>(3, o.variance, o.lengthscale);
       }},
      {"matern52",
       [](const KernelOptions& o) {
         return std::make_unique<MaternKernel>(5, o.variance, o.lengthscale);
       }},
      {"periodic",
       [](const KernelOptions& o) {
         return std::make_unique<PeriodicKernel>(o.variance, o.lengthscale,
                                                 o.period);
       }},
  };
  return registry;
}

// Beyond these the features' frequencies and weights leave double range
// (1e12 s is 30000 years; 1e24 m^2 a spread of 1e12 m).
constexpr double kMaxTimeScale = 1e12;
constexpr double kMaxVariance = 1e24;

bool CheckPositive(const std::string& flag, double value, double largest,
                   std::string* error) {
  return CheckPositiveUpToOption(
      value, flag, largest, error,
      "the features' frequencies and weights leave double range");
}

}  // namespace

double UniformOpen01(std::mt19937_64* rng) {
  // 53 random bits, offset by half a step: never 0 or 1.
  return (static_cast<double>((*rng)() >> 11) + 0.5) * 0x1.0p-53;
}

double Kernel::SampleFrequency(std::mt19937_64* rng) const {
  return FrequencyQuantile(UniformOpen01(rng));
}

bool Kernel::FourierSeries(int /*num_terms*/, std::vector<double>* frequencies,
                           std::vector<double>* coefficients) const {
  frequencies->clear();
  coefficients->clear();
  return false;
}

std::unique_ptr<Kernel> CreateKernel(const KernelOptions& options,
                                     std::string* error,
                                     const std::string& flag_prefix) {
  for (const KernelEntry& entry : Registry()) {
    if (options.name != entry.name) continue;
    // The period too, for every kernel: a value given is checked, used or
    // not.
    if (!CheckPositive(flag_prefix + "kernel_variance", options.variance,
                       kMaxVariance, error) ||
        !CheckPositive(flag_prefix + "lengthscale", options.lengthscale,
                       kMaxTimeScale, error) ||
        !CheckPositive("period", options.period, kMaxTimeScale, error)) {
      return nullptr;
    }
    if (options.name == "periodic") {
      // Below this the series needs more than ~12000 terms (white noise).
      constexpr double kMinPeriodicLengthscale = 1e-3;
      if (options.lengthscale < kMinPeriodicLengthscale) {
        *error = OptionError(
            flag_prefix + "lengthscale", FormatNumber(options.lengthscale),
            "the periodic kernel's series would need more than ~12000 terms",
            FormatNumber(kMinPeriodicLengthscale) + " up to " +
                FormatNumber(kMaxTimeScale) + " for the periodic kernel");
        return nullptr;
      }
    }
    return entry.create(options);
  }
  *error = OptionError(flag_prefix + "kernel", options.name, "unknown kernel",
                       JoinAlternatives(KernelNames()));
  return nullptr;
}

std::vector<std::string> KernelNames() {
  std::vector<std::string> names;
  for (const KernelEntry& entry : Registry()) names.push_back(entry.name);
  return names;
}

}  // namespace rff
