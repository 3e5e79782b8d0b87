// Special functions behind the kernels' spectral measures: the standard
// normal and the Student-t (odd degrees of freedom) distributions, and the
// exponentially scaled modified Bessel functions of the periodic kernel.
#ifndef RFF_CERES_KERNELS_SPECTRAL_MATH_H_
#define RFF_CERES_KERNELS_SPECTRAL_MATH_H_

#include <vector>

namespace rff {

double NormalCdf(double x);
// Inverse of NormalCdf on (0, 1): Acklam's rational approximation refined by
// one Halley step, accurate to a few ulp in the body and ~1e-15 relative in
// the tails.
double InverseNormalCdf(double u);

// Student-t with an odd number of degrees of freedom (1 = Cauchy, 3, 5, ...),
// the spectral measures of the Matern 1/2, 3/2, 5/2 kernels. The CDF uses the
// closed form in theta = atan(x / sqrt(dof)); the quantile bisects on theta in
// (-pi/2, 0) (odd symmetry for u > 1/2), which always converges (it runs once
// per frequency); its relative accuracy is ~1e-16 / min(u, 1 - u) in the
// tails (exact closed form for dof = 1).
double StudentTDensity(double x, int dof);
double StudentTCdf(double x, int dof);
double StudentTQuantile(double u, int dof);

// exp(-a) I_j(a) for j = 0 .. num_terms - 1 (Miller's backward recurrence,
// normalised by exp(-a) (I_0(a) + 2 sum_{j>=1} I_j(a)) = 1, so it neither
// overflows nor loses the normalisation for large a).
std::vector<double> ScaledBesselI(double a, int num_terms);

}  // namespace rff

#endif  // RFF_CERES_KERNELS_SPECTRAL_MATH_H_
