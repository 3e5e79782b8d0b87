#include "rff_ceres/kernels/spectral_math.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace rff {

double NormalCdf(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

double InverseNormalCdf(double u) {
  if (!(u > 0.0)) return -std::numeric_limits<double>::infinity();
  if (!(u < 1.0)) return std::numeric_limits<double>::infinity();
  // P. J. Acklam's coefficients (relative error < 1.15e-9 before refinement).
  static const double a[] = {-3.969683028665376e+01, 2.209460984245205e+02,
                             -2.759285104469687e+02, 1.383577518672690e+02,
                             -3.066479806614716e+01, 2.506628277459239e+00};
  static const double b[] = {-5.447609879822406e+01, 1.615858368580409e+02,
                             -1.556989798598866e+02, 6.680131188771972e+01,
                             -1.328068155288572e+01};
  static const double c[] = {-7.784894002430293e-03, -3.223964580411365e-01,
                             -2.400758277161838e+00, -2.549732539343734e+00,
                             4.374664141464968e+00,  2.938163982698783e+00};
  static const double d[] = {7.784695709041462e-03, 3.224671290700398e-01,
                             2.445134137142996e+00, 3.754408661907416e+00};
  // Upper half by symmetry: 1 - u is exact there, and the residual of the
  // lower tail keeps its relative accuracy.
  if (u > 0.5) return -InverseNormalCdf(1.0 - u);
  constexpr double kLow = 0.02425;
  double x;
  if (u < kLow) {
    const double q = std::sqrt(-2.0 * std::log(u));
    x = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
        ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
  } else {
    const double q = u - 0.5;
    const double r = q * q;
    x = (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) *
        q /
        (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1.0);
  }
  // One Halley step on the CDF residual (u <= 1/2 here).
  const double e = 0.5 * std::erfc(-x / std::sqrt(2.0)) - u;
  const double step = e * std::sqrt(2.0 * M_PI) * std::exp(0.5 * x * x);
  return x - step / (1.0 + 0.5 * x * step);
}

namespace {

// pi (F(x) - 1/2) as a function of theta = atan(x / sqrt(dof)), dof odd:
// theta + sin cos (1 + 2/3 cos^2 + 2*4/(3*5) cos^4 + ...), (dof - 1) / 2 terms.
double StudentTAngleSeries(double theta, int dof) {
  if (dof == 1) return theta;
  const double s = std::sin(theta);
  const double c = std::cos(theta);
  const double c2 = c * c;
  double term = 1.0;
  double sum = 1.0;
  for (int k = 1; k <= (dof - 3) / 2; ++k) {
    term *= c2 * (2.0 * k) / (2.0 * k + 1.0);
    sum += term;
  }
  return theta + s * c * sum;
}

}  // namespace

double StudentTDensity(double x, int dof) {
  const double n = dof;
  const double log_norm = std::lgamma(0.5 * (n + 1.0)) - std::lgamma(0.5 * n) -
                          0.5 * std::log(n * M_PI);
  return std::exp(log_norm - 0.5 * (n + 1.0) * std::log1p(x * x / n));
}

double StudentTCdf(double x, int dof) {
  const double theta = std::atan(x / std::sqrt(static_cast<double>(dof)));
  return 0.5 + StudentTAngleSeries(theta, dof) / M_PI;
}

double StudentTQuantile(double u, int dof) {
  if (!(u > 0.0)) return -std::numeric_limits<double>::infinity();
  if (!(u < 1.0)) return std::numeric_limits<double>::infinity();
  // Odd symmetry: solve in the lower half, where u itself is exact.
  if (u > 0.5) return -StudentTQuantile(1.0 - u, dof);
  if (u == 0.5) return 0.0;
  if (dof == 1) return -1.0 / std::tan(M_PI * u);  // tan(pi (u - 1/2))
  // The series is increasing in theta; bisect on (-pi/2, 0) until the
  // bracket stops shrinking (about 60 halvings).
  const double target = M_PI * (u - 0.5);
  double lo = -0.5 * M_PI;
  double hi = 0.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (mid <= lo || mid >= hi) break;
    if (StudentTAngleSeries(mid, dof) < target) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return std::sqrt(static_cast<double>(dof)) * std::tan(0.5 * (lo + hi));
}

std::vector<double> ScaledBesselI(double a, int num_terms) {
  std::vector<double> result(std::max(num_terms, 0), 0.0);
  if (num_terms <= 0) return result;
  if (a <= 0.0) {
    result[0] = 1.0;
    return result;
  }
  // exp(-a) I_j(a) ~ exp(-j^2 / (2a)) for large a and ~ (a/2)^j / j! for
  // small a: start far enough that the neglected terms are below 1e-17.
  const int start =
      num_terms + 40 + static_cast<int>(std::ceil(10.0 * std::sqrt(a)));
  std::vector<double> values(start + 2, 0.0);
  values[start] = 1.0;  // Arbitrary scale: only ratios matter.
  for (int j = start; j >= 1; --j) {
    values[j - 1] = values[j + 1] + (2.0 * j / a) * values[j];
    if (values[j - 1] > 1e250) {
      for (int k = j - 1; k <= start; ++k) values[k] *= 1e-250;
    }
  }
  // Normalise with I_0 + 2 sum_{j>=1} I_j = exp(a), summing small terms first.
  double sum = 0.0;
  for (int j = start; j >= 1; --j) sum += 2.0 * values[j];
  sum += values[0];
  for (int j = 0; j < num_terms; ++j) result[j] = values[j] / sum;
  return result;
}

}  // namespace rff
