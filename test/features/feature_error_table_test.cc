// Prints the approximation-error tables of docs/features.md and asserts
// their shape (rff rows: mean over seeds 0..4 of the max error). Run:
//   <build>/test/feature_error_table_test
// (the tables go to stdout).
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "gtest/gtest.h"
#include "rff_ceres/features/feature_map.h"
#include "rff_ceres/features/hilbert_features.h"

namespace rff {
namespace {

constexpr double kWindow = 300.0;
constexpr double kLengthscale = 3.0;
constexpr int kGrid = 601;  // 0.5 s spacing
const int kSizes[] = {8, 16, 32, 64, 128, 256, 512, 1024};

struct Errors {
  double short_lags = NAN;  // lags <= 3 lengthscales
  double all_lags = NAN;    // every pair of the window
};

Errors Measure(const Kernel& kernel, const FeatureMap& map) {
  std::vector<double> times(kGrid);
  for (int i = 0; i < kGrid; ++i) times[i] = kWindow * i / (kGrid - 1);
  Eigen::MatrixXd phi;
  map.Evaluate(times, &phi, nullptr);
  const Eigen::MatrixXd gram = phi * phi.transpose();
  Errors errors{0.0, 0.0};
  for (int i = 0; i < kGrid; ++i) {
    for (int j = i; j < kGrid; ++j) {
      const double lag = times[j] - times[i];
      const double e = std::abs(gram(i, j) - kernel.Evaluate(lag));
      errors.all_lags = std::max(errors.all_lags, e);
      if (lag <= 3.0 * kLengthscale + 1e-9) {
        errors.short_lags = std::max(errors.short_lags, e);
      }
    }
  }
  return errors;
}

TEST(FeatureErrorTableTest, PrintsAndChecksTheTables) {
  for (const std::string kernel_name : {"rbf", "matern32"}) {
    KernelOptions kernel_options;
    kernel_options.name = kernel_name;
    kernel_options.lengthscale = kLengthscale;
    std::string error;
    const auto kernel = CreateKernel(kernel_options, &error);
    ASSERT_NE(kernel, nullptr) << error;
    std::string header = "| family |";
    std::string rule = "| --- |";
    for (const int d : kSizes) {
      header += " D=" + std::to_string(d) + " |";
      rule += " --- |";
    }
    std::vector<std::string> short_rows, all_rows;
    for (const std::string& family : FeatureFamilyNames()) {
      std::string short_row = "| " + family + " |";
      std::string all_row = short_row;
      // Gauss-Hermite features integrate a Gaussian spectrum only; every
      // other family builds for every kernel.
      const bool builds =
          family != "gauss_hermite" || kernel->has_gaussian_spectrum();
      Errors first, last;
      for (const int d : kSizes) {
        // Monte-Carlo rows: the mean over seeds 0..4 of the max error.
        const int num_seeds = family == "rff" ? 5 : 1;
        Errors errors{0.0, 0.0};
        bool built = true;
        for (int seed = 0; seed < num_seeds && built; ++seed) {
          FeatureMapOptions options;
          options.family = family;
          options.num_features = d;
          options.seed = seed;
          options.window_begin = 0.0;
          options.window_end = kWindow;
          const auto map = CreateFeatureMap(*kernel, options, &error);
          if (map == nullptr) {
            EXPECT_FALSE(builds) << family << ", D = " << d << ": " << error;
            built = false;
            break;
          }
          EXPECT_TRUE(builds) << family << " built for " << kernel_name;
          const Errors one = Measure(*kernel, *map);
          errors.short_lags += one.short_lags / num_seeds;
          errors.all_lags += one.all_lags / num_seeds;
        }
        if (!built) {
          short_row += " - |";
          all_row += " - |";
          continue;
        }
        if (std::isnan(first.short_lags)) first = errors;
        last = errors;
        char cell[32];
        std::snprintf(cell, sizeof(cell), " %.1e |", errors.short_lags);
        short_row += cell;
        std::snprintf(cell, sizeof(cell), " %.1e |", errors.all_lags);
        all_row += cell;
      }
      short_rows.push_back(short_row);
      all_rows.push_back(all_row);
      if (!builds) continue;
      ASSERT_FALSE(std::isnan(first.short_lags)) << family;
      // Every family converges at short lags: 1024 features beat 8 by 5x.
      EXPECT_LT(last.short_lags, 0.2 * first.short_lags) << family;
      EXPECT_LE(last.short_lags, last.all_lags) << family;
    }
    std::printf(
        "\n%s, lengthscale %g s, window [0, %g] s: max |k_hat - k| "
        "over lags <= 3 lengthscales\n\n%s\n%s\n",
        kernel_name.c_str(), kLengthscale, kWindow, header.c_str(),
        rule.c_str());
    for (const auto& row : short_rows) std::printf("%s\n", row.c_str());
    std::printf("\n%s: max |k_hat - k| over all lags of the window\n\n%s\n%s\n",
                kernel_name.c_str(), header.c_str(), rule.c_str());
    for (const auto& row : all_rows) std::printf("%s\n", row.c_str());

    // The hilbert rule of thumb delivers its tolerance (within 2x).
    std::printf("\n%s hilbert rule of thumb (HilbertNumFeatures):\n",
                kernel_name.c_str());
    for (const double tolerance : {1e-2, 1e-3, 1e-4}) {
      FeatureMapOptions options;
      options.family = "hilbert";
      options.window_end = kWindow;
      options.num_features = HilbertNumFeatures(*kernel, options, tolerance);
      const auto map = CreateFeatureMap(*kernel, options, &error);
      ASSERT_NE(map, nullptr) << error;
      const double achieved = Measure(*kernel, *map).all_lags;
      std::printf("  tolerance %.0e: D = %d, error %.2e\n", tolerance,
                  options.num_features, achieved);
      EXPECT_LT(achieved, 2.0 * tolerance) << tolerance;
      EXPECT_GT(achieved, 0.1 * tolerance) << tolerance;  // not wasteful
    }
  }
}

}  // namespace
}  // namespace rff
