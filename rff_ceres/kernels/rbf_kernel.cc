#include "rff_ceres/kernels/rbf_kernel.h"

#include <cmath>

#include "rff_ceres/kernels/spectral_math.h"

namespace rff {

double RbfKernel::Evaluate(double tau) const {
  const double r = tau / lengthscale();
  return variance() * std::exp(-0.5 * r * r);
}

double RbfKernel::SpectralDensity(double omega) const {
  const double x = omega * lengthscale();
  return variance() * std::sqrt(2.0 * M_PI) * lengthscale() *
         std::exp(-0.5 * x * x);
}

double RbfKernel::FrequencyCdf(double omega) const {
  return NormalCdf(omega * lengthscale());
}

double RbfKernel::FrequencyQuantile(double u) const {
  return InverseNormalCdf(u) / lengthscale();
}

}  // namespace rff
