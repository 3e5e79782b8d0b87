#include "rff_ceres/features/feature_map.h"

#include <cmath>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "rff_ceres/features/gauss_hermite_features.h"
#include "rff_ceres/features/hilbert_features.h"
#include "rff_ceres/features/spectral_pair_features.h"

namespace rff {
namespace {

using ::testing::ElementsAre;

std::unique_ptr<Kernel> MakeKernel(const std::string& name,
                                   double lengthscale = 3.0,
                                   double variance = 1.0) {
  KernelOptions options;
  options.name = name;
  options.lengthscale = lengthscale;
  options.variance = variance;
  options.period = 20.0;
  std::string error;
  std::unique_ptr<Kernel> kernel = CreateKernel(options, &error);
  EXPECT_NE(kernel, nullptr) << error;
  return kernel;
}

FeatureMapOptions Options(const std::string& family, int num_features,
                          uint64_t seed = 1) {
  FeatureMapOptions options;
  options.family = family;
  options.num_features = num_features;
  options.seed = seed;
  options.window_begin = 0.0;
  options.window_end = 300.0;
  return options;
}

std::unique_ptr<FeatureMap> MakeMap(const Kernel& kernel,
                                    const FeatureMapOptions& options) {
  std::string error;
  std::unique_ptr<FeatureMap> map = CreateFeatureMap(kernel, options, &error);
  EXPECT_NE(map, nullptr) << error;
  return map;
}

std::string CreateError(const Kernel& kernel,
                        const FeatureMapOptions& options) {
  std::string error;
  EXPECT_EQ(CreateFeatureMap(kernel, options, &error), nullptr);
  return error;
}

// Max error over lags in [0, 3 lengthscales] from every grid time (0.5 s)
// of the window [0, 300] s.
double ShortLagError(const Kernel& kernel, const FeatureMap& map) {
  return MaxKernelError(kernel, map, 0.0, 300.0, 3.0 * kernel.lengthscale(),
                        601);
}

TEST(FeatureMapTest, RegistryListsEveryFamily) {
  EXPECT_THAT(FeatureFamilyNames(),
              ElementsAre("rff", "qmc", "gauss_hermite", "hilbert"));
  const auto kernel = MakeKernel("rbf");
  for (const std::string& family : FeatureFamilyNames()) {
    EXPECT_EQ(MakeMap(*kernel, Options(family, 16))->num_features(), 16)
        << family;
  }
  EXPECT_EQ(MakeMap(*kernel, Options("hilbert", 7))->num_features(), 7);
}

TEST(FeatureMapTest, RejectsBadOptions) {
  const auto rbf = MakeKernel("rbf");
  const auto matern = MakeKernel("matern32");
  const auto periodic = MakeKernel("periodic", 1.0);
  EXPECT_EQ(CreateError(*rbf, Options("fourier", 16)),
            "--features=fourier: unknown feature family; allowed rff, qmc, "
            "gauss_hermite or hilbert");
  EXPECT_EQ(CreateError(*rbf, Options("rff", 0)),
            "--num_features=0: allowed 1 to 65536");
  EXPECT_EQ(CreateError(*rbf, Options("hilbert", -4)),
            "--num_features=-4: allowed 1 to 65536");
  EXPECT_EQ(CreateError(*rbf, Options("qmc", 1 << 20)),
            "--num_features=1048576: allowed 1 to 65536");
  EXPECT_EQ(CreateError(*rbf, Options("rff", 33)),
            "--num_features=33: rff features come in cos/sin pairs; allowed "
            "even numbers");
  EXPECT_EQ(CreateError(*matern, Options("qmc", 9)),
            "--num_features=9: qmc features come in cos/sin pairs; allowed "
            "even numbers");
  EXPECT_EQ(CreateError(*matern, Options("gauss_hermite", 16)),
            "--features=gauss_hermite: needs a kernel with a Gaussian "
            "spectral density, got matern32; allowed with rbf kernels only");
  EXPECT_EQ(CreateError(*rbf, Options("gauss_hermite", 2048)),
            "--num_features=2048: gauss_hermite nodes come from a dense "
            "eigenproblem; allowed at most 1024");
  FeatureMapOptions heading = Options("hilbert", 16);
  heading.num_features_flag = "num_heading_features";
  EXPECT_EQ(CreateError(*periodic, heading),
            "--num_heading_features=16: the periodic kernel's features are "
            "1 + 2 x harmonics; allowed odd numbers");

  FeatureMapOptions options = Options("hilbert", 16);
  options.window_end = 0.0;
  EXPECT_EQ(CreateError(*rbf, options),
            "hilbert: window [0, 0] must be finite with end > begin");
  options.window_begin = 5.0;
  options.window_end = 4.0;
  EXPECT_EQ(CreateError(*rbf, options),
            "hilbert: window [5, 4] must be finite with end > begin");
  options.window_end = NAN;
  EXPECT_EQ(CreateError(*rbf, options),
            "hilbert: window [5, nan] must be finite with end > begin");
  options.window_begin = 1248444175.0;  // A Unix timestamp.
  options.window_end = 1248444475.0;
  EXPECT_EQ(CreateError(*rbf, options),
            "hilbert: window [1.24844e+09, 1.24844e+09] exceeds +-1e+06 s; "
            "pass times relative to the window origin");
  options = Options("hilbert", 16);
  options.hilbert_margin = -0.1;
  EXPECT_EQ(CreateError(*rbf, options),
            "--hilbert_margin=-0.1: allowed 0 or more");
  options.hilbert_margin = 0.1;
  options.hilbert_min_margin = NAN;
  EXPECT_EQ(CreateError(*rbf, options),
            "--hilbert_min_margin=nan: not a finite number; allowed 0 or "
            "more");
}

// The acceptance table of docs/features.md, asserted: short-lag error of
// each family falls with D, to the values measured (with ~2x margin).
TEST(FeatureMapTest, DeterministicFamiliesConvergeForRbf) {
  const auto kernel = MakeKernel("rbf");
  const struct {
    const char* family;
    double bounds[4];  // D = 8, 32, 128, 512
  } cases[] = {
      {"qmc", {0.15, 0.04, 8e-3, 2e-3}},  // 0.074 0.020 3.7e-3 8e-4
      {"gauss_hermite", {0.02, 1e-13, 1e-13, 1e-12}},  // 9.7e-3, then ~1e-14
      {"hilbert", {1.0, 0.5, 1e-3, 1e-13}},            // 0.86 0.39 3.2e-4 4e-15
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.family);
    double previous = INFINITY;
    const int sizes[] = {8, 32, 128, 512};
    for (int i = 0; i < 4; ++i) {
      const double error = ShortLagError(
          *kernel, *MakeMap(*kernel, Options(c.family, sizes[i])));
      EXPECT_LT(error, c.bounds[i]) << sizes[i];
      // Monotone until machine precision.
      if (previous > 1e-12) {
        EXPECT_LT(error, previous) << sizes[i];
      }
      previous = error;
    }
  }
}

TEST(FeatureMapTest, DeterministicFamiliesConvergeForMatern) {
  const struct {
    const char* kernel;
    const char* family;
    double bounds[4];  // D = 8, 32, 128, 512
  } cases[] = {
      {"matern32", "qmc", {0.3, 0.1, 0.04, 0.01}},  // .18 .054 .022 5.6e-3
      {"matern32", "hilbert", {1.0, 0.6, 0.06, 1.5e-3}},  // .87 .45 .037 7e-4
      {"matern52", "hilbert", {1.0, 0.6, 0.03, 6e-5}},    // .87 .43 .016 2.8e-5
      {"matern12", "hilbert", {1.0, 0.7, 0.3, 0.08}},     // .89 .55 .17 .044
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(std::string(c.kernel) + " " + c.family);
    const auto kernel = MakeKernel(c.kernel);
    double previous = INFINITY;
    const int sizes[] = {8, 32, 128, 512};
    for (int i = 0; i < 4; ++i) {
      const double error = ShortLagError(
          *kernel, *MakeMap(*kernel, Options(c.family, sizes[i])));
      EXPECT_LT(error, c.bounds[i]) << sizes[i];
      EXPECT_LT(error, previous) << sizes[i];
      previous = error;
    }
  }
}

// Monte-Carlo features: the mean (over 10 seeds) max error halves when D
// quadruples, and the variance of k_hat(tau) is the textbook
// variance^2 (1 + k(2 tau) - 2 k(tau)^2) / (2 M) for M cos/sin pairs.
TEST(FeatureMapTest, MonteCarloErrorFallsLikeOneOverSqrtD) {
  const auto kernel = MakeKernel("rbf");
  double mean_errors[4];
  const int sizes[] = {8, 32, 128, 512};
  for (int i = 0; i < 4; ++i) {
    mean_errors[i] = 0.0;
    for (uint64_t seed = 0; seed < 10; ++seed) {
      mean_errors[i] +=
          ShortLagError(*kernel,
                        *MakeMap(*kernel, Options("rff", sizes[i], seed))) /
          10.0;
    }
  }
  // Measured: 0.43 0.195 0.083 0.051.
  for (int i = 1; i < 4; ++i) {
    EXPECT_LT(mean_errors[i], 0.75 * mean_errors[i - 1]) << sizes[i];
    EXPECT_GT(mean_errors[i], 0.25 * mean_errors[i - 1]) << sizes[i];
  }
  EXPECT_LT(mean_errors[3], 0.1);

  const int num_pairs = 16;
  const double tau = 3.0;
  const int num_maps = 2000;
  double sum = 0.0;
  double sum_squares = 0.0;
  std::vector<double> phi0(2 * num_pairs), phi1(2 * num_pairs);
  for (int seed = 0; seed < num_maps; ++seed) {
    const auto map = MakeMap(*kernel, Options("rff", 2 * num_pairs, seed));
    map->Evaluate(100.0, phi0.data(), nullptr);
    map->Evaluate(100.0 + tau, phi1.data(), nullptr);
    double k_hat = 0.0;
    for (int j = 0; j < 2 * num_pairs; ++j) k_hat += phi0[j] * phi1[j];
    sum += k_hat;
    sum_squares += k_hat * k_hat;
  }
  const double mean = sum / num_maps;
  const double variance = sum_squares / num_maps - mean * mean;
  const double k1 = kernel->Evaluate(tau);
  const double expected =
      (1.0 + kernel->Evaluate(2.0 * tau) - 2.0 * k1 * k1) / (2.0 * num_pairs);
  EXPECT_NEAR(mean, k1, 4.0 * std::sqrt(expected / num_maps));
  EXPECT_NEAR(variance, expected, 0.15 * expected);
}

TEST(FeatureMapTest, SameSeedSameFeatures) {
  const auto kernel = MakeKernel("matern52");
  for (const std::string family : {"rff", "qmc", "hilbert"}) {
    const auto a = MakeMap(*kernel, Options(family, 64, 5));
    const auto b = MakeMap(*kernel, Options(family, 64, 5));
    const auto c = MakeMap(*kernel, Options(family, 64, 6));
    std::vector<double> pa(64), pb(64), pc(64);
    a->Evaluate(123.4, pa.data(), nullptr);
    b->Evaluate(123.4, pb.data(), nullptr);
    c->Evaluate(123.4, pc.data(), nullptr);
    EXPECT_EQ(pa, pb) << family;
    // Only the Monte-Carlo family uses the seed.
    EXPECT_EQ(pa != pc, family == "rff") << family;
  }
}

// d phi / dt against central differences, relative to the largest entry.
TEST(FeatureMapTest, DerivativeMatchesFiniteDifferences) {
  const struct {
    const char* kernel;
    const char* family;
    int num_features;
  } cases[] = {{"rbf", "rff", 64},           {"matern52", "rff", 64},
               {"rbf", "qmc", 64},           {"matern32", "qmc", 64},
               {"rbf", "gauss_hermite", 32}, {"rbf", "hilbert", 128},
               {"matern32", "hilbert", 128}, {"periodic", "rff", 21}};
  for (const auto& c : cases) {
    SCOPED_TRACE(std::string(c.kernel) + " " + c.family);
    const auto kernel =
        MakeKernel(c.kernel, c.kernel == std::string("periodic") ? 1.0 : 3.0);
    const auto map = MakeMap(*kernel, Options(c.family, c.num_features));
    const int d = map->num_features();
    std::vector<double> phi(d), dphi(d), plus(d), minus(d), ignored(d);
    for (const double t : {0.0, 17.3, 150.0, 299.9}) {
      map->Evaluate(t, phi.data(), dphi.data());
      const double h = 1e-5;
      map->Evaluate(t + h, plus.data(), nullptr);
      map->Evaluate(t - h, minus.data(), nullptr);
      double scale = 0.0;
      for (int j = 0; j < d; ++j) scale = std::max(scale, std::abs(dphi[j]));
      ASSERT_GT(scale, 0.0);
      for (int j = 0; j < d; ++j) {
        EXPECT_NEAR((plus[j] - minus[j]) / (2.0 * h), dphi[j], 1e-6 * scale)
            << t << " " << j;
      }
      // phi does not depend on whether dphi is asked for.
      map->Evaluate(t, ignored.data(), nullptr);
      EXPECT_EQ(ignored, phi);
    }
  }
}

TEST(FeatureMapTest, BatchEvaluateStacksRows) {
  const auto kernel = MakeKernel("rbf");
  const auto map = MakeMap(*kernel, Options("hilbert", 10));
  const std::vector<double> times = {0.0, 1.5, 299.0};
  Eigen::MatrixXd phi, dphi;
  map->Evaluate(times, &phi, &dphi);
  ASSERT_EQ(phi.rows(), 3);
  ASSERT_EQ(phi.cols(), 10);
  ASSERT_EQ(dphi.rows(), 3);
  std::vector<double> row(10), drow(10);
  for (int i = 0; i < 3; ++i) {
    map->Evaluate(times[i], row.data(), drow.data());
    for (int j = 0; j < 10; ++j) {
      EXPECT_EQ(phi(i, j), row[j]);
      EXPECT_EQ(dphi(i, j), drow[j]);
    }
  }
  Eigen::MatrixXd only_phi;
  map->Evaluate(times, &only_phi, nullptr);
  EXPECT_EQ(only_phi, phi);
}

// Solin & Sarkka: phi_j(x) = sqrt(S(sqrt(lambda_j))) L^-1/2
// sin(pi j (x + L) / (2 L)), x = t - centre, lambda_j = (pi j / (2 L))^2.
TEST(FeatureMapTest, HilbertBasisFollowsThePaper) {
  const auto kernel = MakeKernel("matern32", 3.0, 2.0);
  FeatureMapOptions options = Options("hilbert", 5);
  options.window_begin = 10.0;
  options.window_end = 110.0;  // centre 60, half-width 50, margin 5 s
  options.hilbert_min_margin = 0.0;
  const auto map = MakeMap(*kernel, options);
  const double L = 55.0;
  const double x = 37.0 - 60.0;
  std::vector<double> phi(5);
  map->Evaluate(37.0, phi.data(), nullptr);
  for (int j = 1; j <= 5; ++j) {
    const double sqrt_lambda = M_PI * j / (2.0 * L);
    EXPECT_NEAR(phi[j - 1],
                std::sqrt(kernel->SpectralDensity(sqrt_lambda)) / std::sqrt(L) *
                    std::sin(M_PI * j * (x + L) / (2.0 * L)),
                1e-15);
  }
  // The margin floor: 4 lengthscales when 10% of the half-width is less.
  options.hilbert_min_margin = 4.0;
  EXPECT_DOUBLE_EQ(
      dynamic_cast<const HilbertFeatures&>(*MakeMap(*kernel, options))
          .half_width(),
      62.0);
  options.window_end = 20.0;
  const auto short_window = MakeMap(*kernel, options);
  EXPECT_DOUBLE_EQ(
      dynamic_cast<const HilbertFeatures&>(*short_window).half_width(), 17.0);
  // Enough features: the kernel to machine precision on a short window,
  // right up to its ends.
  options.num_features = 400;
  const auto rbf = MakeKernel("rbf", 3.0, 2.0);
  const auto exact = MakeMap(*rbf, options);
  EXPECT_LT(MaxKernelError(*rbf, *exact, 10.0, 20.0, -1.0, 41), 1e-12);
}

TEST(FeatureMapTest, GaussHermiteRuleHasTabulatedNodes) {
  std::vector<double> nodes, weights;
  GaussHermiteRule(5, &nodes, &weights);
  ASSERT_EQ(nodes.size(), 5u);
  // Abramowitz & Stegun 25.4.46, n = 5.
  const double expected_nodes[] = {-2.020182870456086, -0.958572464613819, 0.0,
                                   0.958572464613819, 2.020182870456086};
  const double expected_weights[] = {0.019953242059046, 0.393619323152241,
                                     0.945308720482942, 0.393619323152241,
                                     0.019953242059046};
  for (int i = 0; i < 5; ++i) {
    EXPECT_NEAR(nodes[i], expected_nodes[i], 1e-13);
    EXPECT_NEAR(weights[i], expected_weights[i], 1e-13);
  }
  // D = 8 features: the 4 positive nodes of the 8-point rule, twice weighted.
  const auto kernel = MakeKernel("rbf", 2.0, 3.0);
  const auto map = MakeMap(*kernel, Options("gauss_hermite", 8));
  const auto& pairs = dynamic_cast<const SpectralPairFeatures&>(*map);
  GaussHermiteRule(8, &nodes, &weights);
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(pairs.frequencies()[i], std::sqrt(2.0) * nodes[4 + i] / 2.0,
                1e-14);
    EXPECT_NEAR(pairs.amplitudes()[i],
                std::sqrt(3.0 * 2.0 * weights[4 + i] / std::sqrt(M_PI)), 1e-14);
  }
}

TEST(FeatureMapTest, PeriodicKernelUsesItsCosineSeries) {
  const auto kernel = MakeKernel("periodic", 1.0, 2.0);  // period 20 s
  for (const std::string& family : FeatureFamilyNames()) {
    SCOPED_TRACE(family);
    const auto map = MakeMap(*kernel, Options(family, 41));  // 20 harmonics
    EXPECT_EQ(map->num_features(), 41);
    // Every lag of the window, long ones included: exact periodicity.
    EXPECT_LT(MaxKernelError(*kernel, *map, 0.0, 300.0, -1.0, 301), 1e-13);
  }
  // Truncation error = the dropped tail, largest at lag 0.
  std::vector<double> frequencies, coefficients;
  kernel->FourierSeries(400, &frequencies, &coefficients);
  double tail = 0.0;
  for (int j = 3; j < 400; ++j) tail += coefficients[j];
  const auto coarse = MakeMap(*kernel, Options("rff", 5));  // harmonics 0..2
  EXPECT_NEAR(MaxKernelError(*kernel, *coarse, 0.0, 40.0, -1.0, 401), tail,
              1e-12);
}

// Absolute times far from 0 keep the pair maps stationary to ~1e-11 (the
// caller passes times relative to the window origin; 1e4 s is a long run).
TEST(FeatureMapTest, StaysAccurateAtLongTimes) {
  const auto kernel = MakeKernel("rbf", 0.2);
  FeatureMapOptions options = Options("rff", 256);
  options.window_end = 2e4;
  const auto map = MakeMap(*kernel, options);
  std::vector<double> a(256), b(256);
  auto k_hat = [&](double t, double u) {
    map->Evaluate(t, a.data(), nullptr);
    map->Evaluate(u, b.data(), nullptr);
    double sum = 0.0;
    for (int j = 0; j < 256; ++j) sum += a[j] * b[j];
    return sum;
  };
  EXPECT_NEAR(k_hat(2e4, 2e4 + 0.1), k_hat(1e4, 1e4 + 0.1), 1e-10);
  EXPECT_NEAR(k_hat(0.0, 0.1), k_hat(1e4, 1e4 + 0.1), 1e-10);
  EXPECT_NEAR(k_hat(5.0, 5.0), 1.0, 1e-12);
}

TEST(FeatureMapTest, DefaultNumFeaturesFindsTheSmallestPowerOfTwo) {
  const auto kernel = MakeKernel("rbf");
  int num_features = 0;
  std::string error;
  // Hilbert on [0, 300] s, l = 3 s: 3.2e-4 at D = 128, 0.39 at D = 64.
  ASSERT_TRUE(DefaultNumFeatures(*kernel, Options("hilbert", 1), 1e-3, 4096,
                                 &num_features, &error))
      << error;
  EXPECT_EQ(num_features, 128);
  ASSERT_TRUE(DefaultNumFeatures(*kernel, Options("gauss_hermite", 1), 1e-6,
                                 1024, &num_features, &error))
      << error;
  EXPECT_EQ(num_features, 16);  // 9.7e-3 at D = 8
  const auto periodic = MakeKernel("periodic", 1.0);
  ASSERT_TRUE(DefaultNumFeatures(*periodic, Options("rff", 1), 1e-6, 4096,
                                 &num_features, &error))
      << error;
  EXPECT_EQ(num_features % 2, 1);
  EXPECT_FALSE(DefaultNumFeatures(*kernel, Options("rff", 1), 1e-3, 64,
                                  &num_features, &error));
  EXPECT_THAT(error, ::testing::StartsWith(
                         "rff: no num_features <= 64 reaches a kernel error "
                         "of 0.001 (last: "));
}

}  // namespace
}  // namespace rff
