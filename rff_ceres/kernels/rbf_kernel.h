// Squared-exponential kernel k(tau) = variance exp(-tau^2 / (2 lengthscale^2)).
// Spectrum: S(omega) = variance sqrt(2 pi) lengthscale
// exp(-omega^2 lengthscale^2 / 2), i.e. p = N(0, 1 / lengthscale^2).
#ifndef RFF_CERES_KERNELS_RBF_KERNEL_H_
#define RFF_CERES_KERNELS_RBF_KERNEL_H_

#include <string>

#include "rff_ceres/kernels/kernel.h"

namespace rff {

class RbfKernel : public Kernel {
 public:
  using Kernel::Kernel;
  std::string name() const override { return "rbf"; }
  double Evaluate(double tau) const override;
  bool has_gaussian_spectrum() const override { return true; }
  double SpectralDensity(double omega) const override;
  double FrequencyCdf(double omega) const override;
  double FrequencyQuantile(double u) const override;
};

}  // namespace rff

#endif  // RFF_CERES_KERNELS_RBF_KERNEL_H_
