// Matern kernels of half-integer order nu = 1/2, 3/2, 5/2 ("matern12",
// "matern32", "matern52"), with r = |tau| / lengthscale:
//   nu = 1/2: k = variance exp(-r)
//   nu = 3/2: k = variance (1 + sqrt(3) r) exp(-sqrt(3) r)
//   nu = 5/2: k = variance (1 + sqrt(5) r + 5 r^2 / 3) exp(-sqrt(5) r)
// Spectrum: S(omega) = 2 pi variance lengthscale f_{2 nu}(omega lengthscale),
// f_n the Student-t density with n degrees of freedom, i.e. the usual
// S ~ (2 nu / lengthscale^2 + omega^2)^-(nu + 1/2): omega = T / lengthscale
// with T ~ t_{2 nu} (Cauchy for nu = 1/2).
#ifndef RFF_CERES_KERNELS_MATERN_KERNEL_H_
#define RFF_CERES_KERNELS_MATERN_KERNEL_H_

#include <string>

#include "rff_ceres/kernels/kernel.h"

namespace rff {

class MaternKernel : public Kernel {
 public:
  // `twice_nu` is 1, 3 or 5 (the Student-t degrees of freedom).
  MaternKernel(int twice_nu, double variance, double lengthscale);
  std::string name() const override;
  double Evaluate(double tau) const override;
  double SpectralDensity(double omega) const override;
  double FrequencyCdf(double omega) const override;
  double FrequencyQuantile(double u) const override;

  int twice_nu() const { return twice_nu_; }

 private:
  int twice_nu_;
};

}  // namespace rff

#endif  // RFF_CERES_KERNELS_MATERN_KERNEL_H_
