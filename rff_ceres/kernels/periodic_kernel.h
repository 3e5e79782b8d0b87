// Periodic (exp-sine-squared) kernel
//   k(tau) = variance exp(-2 sin^2(pi tau / period) / lengthscale^2).
// Its spectrum is discrete: with a = 1 / lengthscale^2 and I_j the modified
// Bessel functions,
//   k(tau) = sum_{j>=0} q_j cos(2 pi j tau / period),
//   q_0 = variance exp(-a) I_0(a),  q_j = 2 variance exp(-a) I_j(a) (j >= 1),
// (Solin & Sarkka 2014, "Explicit link between periodic covariance functions
// and state space models"). Every feature family uses this series.
#ifndef RFF_CERES_KERNELS_PERIODIC_KERNEL_H_
#define RFF_CERES_KERNELS_PERIODIC_KERNEL_H_

#include <string>
#include <vector>

#include "rff_ceres/kernels/kernel.h"

namespace rff {

class PeriodicKernel : public Kernel {
 public:
  PeriodicKernel(double variance, double lengthscale, double period);
  std::string name() const override { return "periodic"; }
  double period() const { return period_; }
  double Evaluate(double tau) const override;
  bool has_spectral_density() const override { return false; }
  // No density (the measure is atomic): always 0.
  double SpectralDensity(double omega) const override;
  // CDF and quantile of the atomic measure: mass q_0 / variance at 0 and
  // q_j / (2 variance) at +-2 pi j / period.
  double FrequencyCdf(double omega) const override;
  double FrequencyQuantile(double u) const override;
  bool FourierSeries(int num_terms, std::vector<double>* frequencies,
                     std::vector<double>* coefficients) const override;

 private:
  double period_;
  // q_j / variance for j = 0 .. until the tail is below 1e-17.
  std::vector<double> normalized_coefficients_;
};

}  // namespace rff

#endif  // RFF_CERES_KERNELS_PERIODIC_KERNEL_H_
