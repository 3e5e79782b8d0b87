#include "rff_ceres/kernels/kernel.h"

#include <cmath>
#include <random>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "rff_ceres/kernels/spectral_math.h"

namespace rff {
namespace {

using ::testing::ElementsAre;

std::unique_ptr<Kernel> MakeKernel(const std::string& name, double variance,
                                   double lengthscale, double period = 1.0) {
  KernelOptions options;
  options.name = name;
  options.variance = variance;
  options.lengthscale = lengthscale;
  options.period = period;
  std::string error;
  std::unique_ptr<Kernel> kernel = CreateKernel(options, &error);
  EXPECT_NE(kernel, nullptr) << error;
  return kernel;
}

std::string CreateError(const KernelOptions& options) {
  std::string error;
  EXPECT_EQ(CreateKernel(options, &error), nullptr);
  return error;
}

// Composite midpoint rule of f on [a, b] with n intervals (never evaluates
// the end points, where the tan substitution is singular).
template <typename F>
double Midpoint(const F& f, double a, double b, int n) {
  const double h = (b - a) / n;
  double sum = 0.0;
  for (int i = 0; i < n; ++i) sum += f(a + (i + 0.5) * h);
  return sum * h;
}

// Composite Simpson rule of f on [a, b] with n (even) intervals.
template <typename F>
double Simpson(const F& f, double a, double b, int n) {
  const double h = (b - a) / n;
  double sum = f(a) + f(b);
  for (int i = 1; i < n; ++i) sum += (i % 2 == 1 ? 4.0 : 2.0) * f(a + i * h);
  return sum * h / 3.0;
}

TEST(KernelTest, RegistryListsEveryKernel) {
  EXPECT_THAT(KernelNames(), ElementsAre("rbf", "matern12", "matern32",
                                         "matern52", "periodic"));
  for (const std::string& name : KernelNames()) {
    EXPECT_EQ(MakeKernel(name, 1.0, 1.0)->name(), name);
  }
}

TEST(KernelTest, RejectsBadOptions) {
  KernelOptions options;
  options.name = "gaussian";
  EXPECT_EQ(CreateError(options),
            "--kernel=gaussian: unknown kernel; allowed rbf, matern12, "
            "matern32, matern52 or periodic");
  options.name = "matern32";
  options.lengthscale = 0.0;
  EXPECT_EQ(CreateError(options),
            "--lengthscale=0: allowed more than 0 up to 1e+12");
  options.lengthscale = NAN;
  EXPECT_EQ(CreateError(options),
            "--lengthscale=nan: not a finite number; allowed more than 0 up to "
            "1e+12");
  options.lengthscale = 1.0;
  options.variance = -2.0;
  EXPECT_EQ(CreateError(options),
            "--kernel_variance=-2: allowed more than 0 up to 1e+24");
  options.variance = INFINITY;
  EXPECT_EQ(CreateError(options),
            "--kernel_variance=inf: the features' frequencies and weights "
            "leave double range; allowed more than 0 up to 1e+24");
  options = KernelOptions();
  options.name = "periodic";
  options.period = 0.0;
  EXPECT_EQ(CreateError(options),
            "--period=0: allowed more than 0 up to 1e+12");
  options.period = 1.0;
  options.lengthscale = 1e-4;
  EXPECT_EQ(CreateError(options),
            "--lengthscale=1e-04: the periodic kernel's series would need "
            "more than ~12000 terms; allowed 0.001 up to 1e+12 for the "
            "periodic kernel");
}

// The flags of the heading kernel and of the GP draw are named by prefix.
TEST(KernelTest, MessagesNameTheFlagsOfThePrefix) {
  KernelOptions options;
  options.name = "sinc";
  std::string error;
  EXPECT_EQ(CreateKernel(options, &error, "heading_"), nullptr);
  EXPECT_EQ(error,
            "--heading_kernel=sinc: unknown kernel; allowed rbf, matern12, "
            "matern32, matern52 or periodic");
  options = KernelOptions();
  options.variance = 0.0;
  EXPECT_EQ(CreateKernel(options, &error, "gp_heading_"), nullptr);
  EXPECT_EQ(error,
            "--gp_heading_kernel_variance=0: allowed more than 0 up to 1e+24");
}

TEST(KernelTest, EvaluatesClosedForms) {
  // variance 2, lengthscale 3, tau = 3 (r = 1):
  // rbf 2 e^-0.5, matern12 2 e^-1, matern32 2 (1 + sqrt3) e^-sqrt3,
  // matern52 2 (1 + sqrt5 + 5/3) e^-sqrt5.
  const struct {
    const char* name;
    double at_one_lengthscale;
  } cases[] = {{"rbf", 1.2130613194252668},
               {"matern12", 0.7357588823428847},
               {"matern32", 0.9667154491930154},
               {"matern52", 1.0479882176636406}};
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const auto kernel = MakeKernel(c.name, 2.0, 3.0);
    EXPECT_EQ(kernel->variance(), 2.0);
    EXPECT_EQ(kernel->lengthscale(), 3.0);
    EXPECT_DOUBLE_EQ(kernel->Evaluate(0.0), 2.0);
    EXPECT_NEAR(kernel->Evaluate(3.0), c.at_one_lengthscale, 1e-15);
    EXPECT_NEAR(kernel->Evaluate(-3.0), c.at_one_lengthscale, 1e-15);
    EXPECT_LT(kernel->Evaluate(30.0), 1e-3);
  }
  // Periodic, variance 2, lengthscale 0.7, period 5:
  // k(p/4) = 2 exp(-2 * 0.5 / 0.49), k(p/2) = 2 exp(-2 / 0.49), k(p) = 2.
  const auto periodic = MakeKernel("periodic", 2.0, 0.7, 5.0);
  EXPECT_DOUBLE_EQ(periodic->Evaluate(0.0), 2.0);
  EXPECT_NEAR(periodic->Evaluate(1.25), 0.25984521661011895, 1e-15);
  EXPECT_NEAR(periodic->Evaluate(2.5), 0.03375976829757982, 1e-15);
  EXPECT_NEAR(periodic->Evaluate(-7.5), 0.03375976829757982, 1e-15);
  EXPECT_NEAR(periodic->Evaluate(5.0), 2.0, 1e-14);
}

// (1 / 2 pi) * integral S = variance, and (1 / 2 pi) * integral S cos(w tau)
// = k(tau): checks S against Evaluate in the documented convention.
TEST(KernelTest, SpectralDensityIsTheFourierTransform) {
  const struct {
    const char* name;
    double tolerance;  // Truncation of the spectral tails at |w| = 400 / l.
  } cases[] = {{"rbf", 1e-10},
               {"matern12", 1e-4},
               {"matern32", 1e-8},
               {"matern52", 1e-10}};
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const auto kernel = MakeKernel(c.name, 2.0, 3.0);
    // Total mass: substitute w = tan(theta) / l, smooth for heavy tails.
    const double mass =
        Midpoint(
            [&](double theta) {
              const double c2 = std::cos(theta) * std::cos(theta);
              return kernel->SpectralDensity(std::tan(theta) / 3.0) /
                     (3.0 * c2);
            },
            -0.5 * M_PI, 0.5 * M_PI, 20000) /
        (2.0 * M_PI);
    EXPECT_NEAR(mass, 2.0, 1e-9);
    for (const double tau : {0.7, 3.0, 6.5}) {
      const double limit = 400.0 / 3.0;
      const double value =
          Simpson(
              [&](double w) {
                return kernel->SpectralDensity(w) * std::cos(w * tau);
              },
              -limit, limit, 200000) /
          (2.0 * M_PI);
      EXPECT_NEAR(value, kernel->Evaluate(tau), c.tolerance) << tau;
    }
    // The normalised density is the derivative of the CDF.
    for (const double w : {-0.4, 0.1, 0.5}) {
      const double h = 1e-5;
      const double derivative =
          (kernel->FrequencyCdf(w + h) - kernel->FrequencyCdf(w - h)) /
          (2.0 * h);
      EXPECT_NEAR(derivative, kernel->SpectralDensity(w) / (2.0 * M_PI * 2.0),
                  1e-8);
    }
  }
}

TEST(KernelTest, CdfValuesAndQuantileInversion) {
  // Cdf(1 / l): Phi(1); Cauchy 3/4; t3 1/2 + 1/6 + sqrt(3) / (4 pi).
  EXPECT_NEAR(MakeKernel("rbf", 1.0, 2.0)->FrequencyCdf(0.5),
              0.8413447460685429, 1e-15);
  EXPECT_NEAR(MakeKernel("matern12", 1.0, 2.0)->FrequencyCdf(0.5), 0.75, 1e-15);
  EXPECT_NEAR(MakeKernel("matern32", 1.0, 2.0)->FrequencyCdf(0.5),
              0.8044988905221147, 1e-15);
  // Tabulated quantiles: z_0.975, t_{0.975, 3}, t_{0.975, 5}.
  EXPECT_NEAR(InverseNormalCdf(0.975), 1.959963984540054, 1e-14);
  EXPECT_NEAR(InverseNormalCdf(0.025), -1.959963984540054, 1e-14);
  EXPECT_NEAR(InverseNormalCdf(1e-10), -6.361340902404056, 1e-12);
  EXPECT_NEAR(StudentTQuantile(0.975, 3), 3.182446305284263, 1e-12);
  EXPECT_NEAR(StudentTQuantile(0.975, 5), 2.570581835636314, 1e-12);
  EXPECT_EQ(InverseNormalCdf(0.0), -INFINITY);
  EXPECT_EQ(StudentTQuantile(1.0, 3), INFINITY);

  for (const char* name : {"rbf", "matern12", "matern32", "matern52"}) {
    SCOPED_TRACE(name);
    const auto kernel = MakeKernel(name, 1.5, 0.8);
    EXPECT_EQ(kernel->FrequencyQuantile(0.5), 0.0);
    for (const double u :
         {1e-9, 1e-4, 0.01, 0.3, 0.5, 0.77, 0.999, 1.0 - 1e-6}) {
      const double w = kernel->FrequencyQuantile(u);
      EXPECT_NEAR(kernel->FrequencyCdf(w), u, 1e-14 + 1e-9 * u) << u;
      // Symmetric spectrum (1 - u is rounded: only for u not tiny).
      if (u >= 1e-4) {
        EXPECT_NEAR(kernel->FrequencyQuantile(1.0 - u), -w, 1e-9 * std::abs(w))
            << u;
      }
    }
  }
}

TEST(KernelTest, SamplesTheNormalisedSpectrum) {
  const auto kernel = MakeKernel("rbf", 1.0, 2.0);  // p = N(0, 0.25)
  std::mt19937_64 rng(7);
  const int n = 200000;
  double sum = 0.0;
  double sum_squares = 0.0;
  for (int i = 0; i < n; ++i) {
    const double w = kernel->SampleFrequency(&rng);
    sum += w;
    sum_squares += w * w;
  }
  const double mean = sum / n;
  // 4 standard errors: 4 * 0.5 / sqrt(n) = 0.0045; var rel. s.e. sqrt(2/n).
  EXPECT_LT(std::abs(mean), 0.0045);
  EXPECT_NEAR(sum_squares / n - mean * mean, 0.25,
              4 * 0.25 * std::sqrt(2.0 / n));

  // E[cos(w tau)] = k(tau) / variance for a heavy-tailed spectrum too.
  const auto matern = MakeKernel("matern12", 1.0, 2.0);
  double cos_sum = 0.0;
  for (int i = 0; i < n; ++i)
    cos_sum += std::cos(matern->SampleFrequency(&rng) * 1.5);
  EXPECT_NEAR(cos_sum / n, matern->Evaluate(1.5), 4.0 * 0.71 / std::sqrt(n));

  // The draws are a function of the seed alone.
  std::mt19937_64 a(42), b(42);
  for (int i = 0; i < 10; ++i) {
    EXPECT_EQ(matern->SampleFrequency(&a), matern->SampleFrequency(&b));
  }
  std::mt19937_64 c(3);
  for (int i = 0; i < 1000; ++i) {
    const double u = UniformOpen01(&c);
    ASSERT_GT(u, 0.0);
    ASSERT_LT(u, 1.0);
  }
}

TEST(KernelTest, PeriodicSeriesMatchesTheKernel) {
  for (const double lengthscale : {0.05, 0.7, 3.0}) {
    SCOPED_TRACE(lengthscale);
    const auto kernel = MakeKernel("periodic", 2.0, lengthscale, 5.0);
    EXPECT_FALSE(kernel->has_spectral_density());
    EXPECT_EQ(kernel->SpectralDensity(1.0), 0.0);
    std::vector<double> frequencies, coefficients;
    ASSERT_TRUE(kernel->FourierSeries(400, &frequencies, &coefficients));
    ASSERT_EQ(coefficients.size(), 400u);
    EXPECT_DOUBLE_EQ(frequencies[3], 2.0 * M_PI * 3.0 / 5.0);
    double total = 0.0;
    for (const double q : coefficients) {
      EXPECT_GE(q, 0.0);
      total += q;
    }
    EXPECT_NEAR(total, 2.0, 1e-13);
    for (const double tau : {0.0, 0.3, 1.25, 2.5, 7.1}) {
      double series = 0.0;
      for (size_t j = 0; j < coefficients.size(); ++j) {
        series += coefficients[j] * std::cos(frequencies[j] * tau);
      }
      EXPECT_NEAR(series, kernel->Evaluate(tau), 1e-13) << tau;
    }
    // The atomic measure: half the mass of harmonic 0 on each side of 0.
    EXPECT_EQ(kernel->FrequencyQuantile(0.5), 0.0);
    EXPECT_NEAR(kernel->FrequencyCdf(-1e-12), 0.5 - 0.25 * coefficients[0],
                1e-14);
    EXPECT_NEAR(kernel->FrequencyCdf(0.0), 0.5 + 0.25 * coefficients[0], 1e-14);
    const double w1 = frequencies[1];
    EXPECT_EQ(kernel->FrequencyQuantile(0.5 + 0.25 * coefficients[0] + 1e-9),
              w1);
    EXPECT_NEAR(kernel->FrequencyCdf(w1),
                0.5 + 0.25 * (coefficients[0] + coefficients[1]), 1e-14);
  }
  std::vector<double> frequencies, coefficients;
  EXPECT_FALSE(MakeKernel("rbf", 1.0, 1.0)
                   ->FourierSeries(3, &frequencies, &coefficients));
  EXPECT_TRUE(coefficients.empty());
}

TEST(KernelTest, ScaledBesselMatchesTheStandardLibrary) {
  for (const double a : {0.01, 2.0, 30.0}) {
    const std::vector<double> values = ScaledBesselI(a, 12);
    for (int j = 0; j < 12; ++j) {
      const double expected = std::exp(-a) * std::cyl_bessel_i(j, a);
      EXPECT_NEAR(values[j], expected, 1e-14 + 1e-12 * expected)
          << a << " " << j;
    }
  }
  // Far beyond exp overflow (a = 1e5, lengthscale ~ 0.003).
  const std::vector<double> large = ScaledBesselI(1e5, 3);
  EXPECT_NEAR(large[0], 1.0 / std::sqrt(2.0 * M_PI * 1e5), 1e-8);
}

}  // namespace
}  // namespace rff
