#include "rff_ceres/kernels/periodic_kernel.h"

#include <cmath>

#include "rff_ceres/kernels/spectral_math.h"

namespace rff {
namespace {

// Number of series terms that carries all the mass to double precision.
int FullSeriesLength(double a) {
  return 64 + static_cast<int>(std::ceil(12.0 * std::sqrt(a)));
}

std::vector<double> NormalizedCoefficients(double a, int num_terms) {
  std::vector<double> q = ScaledBesselI(a, num_terms);
  for (size_t j = 1; j < q.size(); ++j) q[j] *= 2.0;
  return q;
}

}  // namespace

PeriodicKernel::PeriodicKernel(double variance, double lengthscale,
                               double period)
    : Kernel(variance, lengthscale), period_(period) {
  const double a = 1.0 / (lengthscale * lengthscale);
  normalized_coefficients_ = NormalizedCoefficients(a, FullSeriesLength(a));
}

double PeriodicKernel::Evaluate(double tau) const {
  const double s = std::sin(M_PI * tau / period_) / lengthscale();
  return variance() * std::exp(-2.0 * s * s);
}

double PeriodicKernel::SpectralDensity(double /*omega*/) const { return 0.0; }

double PeriodicKernel::FrequencyCdf(double omega) const {
  // Atoms at +-step j carry q_j / 2 each; sum the tail beyond |omega|.
  const double step = 2.0 * M_PI / period_;
  double tail = 0.0;
  for (size_t j = normalized_coefficients_.size() - 1; j >= 1; --j) {
    const double atom = step * static_cast<double>(j);
    if (omega < 0.0 ? -atom > omega : atom <= omega) break;
    tail += 0.5 * normalized_coefficients_[j];
  }
  return omega < 0.0 ? tail : 1.0 - tail;
}

double PeriodicKernel::FrequencyQuantile(double u) const {
  const double step = 2.0 * M_PI / period_;
  const int n = static_cast<int>(normalized_coefficients_.size());
  if (u <= 0.5 - 0.5 * normalized_coefficients_[0]) {
    // Negative atoms, from the far left.
    double cdf = 0.0;
    for (int j = n - 1; j >= 1; --j) {
      cdf += 0.5 * normalized_coefficients_[j];
      if (cdf >= u) return -step * j;
    }
    return 0.0;
  }
  if (u <= 0.5 + 0.5 * normalized_coefficients_[0]) return 0.0;
  double cdf = 0.5 + 0.5 * normalized_coefficients_[0];
  for (int j = 1; j < n; ++j) {
    cdf += 0.5 * normalized_coefficients_[j];
    if (cdf >= u) return step * j;
  }
  return step * (n - 1);
}

bool PeriodicKernel::FourierSeries(int num_terms,
                                   std::vector<double>* frequencies,
                                   std::vector<double>* coefficients) const {
  frequencies->assign(num_terms, 0.0);
  coefficients->assign(num_terms, 0.0);
  const double a = 1.0 / (lengthscale() * lengthscale());
  const std::vector<double> q =
      num_terms <= static_cast<int>(normalized_coefficients_.size())
          ? normalized_coefficients_
          : NormalizedCoefficients(a, num_terms);
  for (int j = 0; j < num_terms; ++j) {
    (*frequencies)[j] = 2.0 * M_PI * j / period_;
    (*coefficients)[j] = variance() * q[j];
  }
  return true;
}

}  // namespace rff
