#include "rff_ceres/kernels/matern_kernel.h"

#include <cmath>

#include "rff_ceres/kernels/spectral_math.h"

namespace rff {

MaternKernel::MaternKernel(int twice_nu, double variance, double lengthscale)
    : Kernel(variance, lengthscale), twice_nu_(twice_nu) {}

std::string MaternKernel::name() const {
  return "matern" + std::to_string(twice_nu_) + "2";
}

double MaternKernel::Evaluate(double tau) const {
  const double r = std::abs(tau) / lengthscale();
  switch (twice_nu_) {
    case 1:
      return variance() * std::exp(-r);
    case 3: {
      const double s = std::sqrt(3.0) * r;
      return variance() * (1.0 + s) * std::exp(-s);
    }
    default: {
      const double s = std::sqrt(5.0) * r;
      return variance() * (1.0 + s + s * s / 3.0) * std::exp(-s);
    }
  }
}

double MaternKernel::SpectralDensity(double omega) const {
  return 2.0 * M_PI * variance() * lengthscale() *
         StudentTDensity(omega * lengthscale(), twice_nu_);
}

double MaternKernel::FrequencyCdf(double omega) const {
  return StudentTCdf(omega * lengthscale(), twice_nu_);
}

double MaternKernel::FrequencyQuantile(double u) const {
  return StudentTQuantile(u, twice_nu_) / lengthscale();
}

}  // namespace rff
