// Stationary covariance functions k(tau), tau = t - t', of the 1-D time axis,
// with the spectral side that the weight-space feature maps need.
//
// Fourier convention (used everywhere in rff_ceres, as in Solin & Sarkka):
//   S(omega) = integral k(tau) exp(-i omega tau) dtau,
//   k(tau)   = 1 / (2 pi) * integral S(omega) exp(i omega tau) domega,
// with omega in rad/s. The normalised spectral density is
//   p(omega) = S(omega) / (2 pi variance),  so  k(tau) = variance E_p[cos(omega
//   tau)].
// A kernel with a discrete spectrum (the periodic one) has no density: it
// exposes its cosine series instead (FourierSeries).
#ifndef RFF_CERES_KERNELS_KERNEL_H_
#define RFF_CERES_KERNELS_KERNEL_H_

#include <memory>
#include <random>
#include <string>
#include <vector>

namespace rff {

class Kernel {
 public:
  Kernel(double variance, double lengthscale)
      : variance_(variance), lengthscale_(lengthscale) {}
  virtual ~Kernel() = default;

  // The registry name ("rbf", "matern32", ...).
  virtual std::string name() const = 0;
  double variance() const { return variance_; }
  double lengthscale() const { return lengthscale_; }

  // k(tau); k(0) = variance.
  virtual double Evaluate(double tau) const = 0;

  // True when the spectral measure has a density S (every kernel but
  // "periodic"). Otherwise SpectralDensity returns 0 and FourierSeries holds
  // the spectrum.
  virtual bool has_spectral_density() const { return true; }
  // True when p = N(0, 1 / lengthscale^2) (the kernels Gauss-Hermite
  // features integrate exactly).
  virtual bool has_gaussian_spectrum() const { return false; }

  // S(omega) in the convention above; even in omega.
  virtual double SpectralDensity(double omega) const = 0;
  // CDF of the normalised spectral measure p, and its inverse (u in (0, 1)).
  virtual double FrequencyCdf(double omega) const = 0;
  virtual double FrequencyQuantile(double u) const = 0;
  // One draw from p: FrequencyQuantile of a uniform number in (0, 1) built
  // from one 64-bit output, so a seed gives the same draws on every platform.
  double SampleFrequency(std::mt19937_64* rng) const;

  // Discrete spectrum: k(tau) = sum_j coefficients[j] cos(frequencies[j] tau)
  // for j = 0, 1, ..., with the series cut after `num_terms` terms. Returns
  // false (and leaves the vectors empty) for kernels with a density.
  virtual bool FourierSeries(int num_terms, std::vector<double>* frequencies,
                             std::vector<double>* coefficients) const;

 private:
  double variance_;
  double lengthscale_;
};

struct KernelOptions {
  std::string name = "rbf";
  double variance = 1.0;     // k(0), units^2
  double lengthscale = 1.0;  // seconds (periodic: dimensionless, see below)
  double period = 1.0;       // seconds; "periodic" only
};

// Builds a kernel by name. Unknown name, or a variance, lengthscale or period
// that is not positive and finite: returns nullptr and fills `error`. The
// message names the flags PREFIXkernel, PREFIXkernel_variance,
// PREFIXlengthscale and period, for PREFIX = `flag_prefix` ("heading_" for
// theta, "gp_" for rff_simulate's GP draw).
std::unique_ptr<Kernel> CreateKernel(const KernelOptions& options,
                                     std::string* error,
                                     const std::string& flag_prefix = "");

// The registered names, in registry order.
std::vector<std::string> KernelNames();

// A uniform number in the open interval (0, 1) from one draw of `rng`.
double UniformOpen01(std::mt19937_64* rng);

}  // namespace rff

#endif  // RFF_CERES_KERNELS_KERNEL_H_
