#include "rff_ceres/residual_drift.h"

#include <cmath>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "gtest/gtest.h"
#include "rff_ceres/simulate.h"
#include "rff_ceres/slam_report.h"
#include "rff_ceres/slam_solver.h"

namespace rff {
namespace {

// `landmarks` series of `length` draws of a unit AR(1) process with
// coefficient `phi` (white for 0), seeded.
std::map<LandmarkId, std::vector<double>> Ar1Series(int landmarks, int length,
                                                    double phi, unsigned seed) {
  std::mt19937 random(seed);
  std::normal_distribution<double> normal;
  std::map<LandmarkId, std::vector<double>> series;
  const double innovation = std::sqrt(1.0 - phi * phi);
  for (int l = 0; l < landmarks; ++l) {
    double e = normal(random);
    for (int i = 0; i < length; ++i) {
      series[l].push_back(e);
      e = phi * e + innovation * normal(random);
    }
  }
  return series;
}

TEST(ResidualDriftTest, WhiteErrorsDoNotDrift) {
  const ResidualDrift drift =
      MeasureResidualDrift("range", Ar1Series(50, 400, 0.0, 7));
  EXPECT_EQ(drift.kind, "range");
  EXPECT_EQ(drift.batches, 50 * 25);
  // White errors' ratio has standard deviation sqrt(2 / 1250) = 0.04.
  EXPECT_NEAR(drift.ratio, 1.0, 0.16);
  EXPECT_FALSE(drift.drifts);
}

TEST(ResidualDriftTest, CorrelatedErrorsDriftByTheirAutocorrelationTime) {
  const double phi = 0.8;
  // 1 + 2 sum_{k<16} (1 - k/16) phi^k: the batch sums' variance over the
  // rows'.
  double expected = 1.0;
  for (int k = 1; k < kDriftBatch; ++k) {
    expected +=
        2.0 * (1.0 - static_cast<double>(k) / kDriftBatch) * std::pow(phi, k);
  }
  const ResidualDrift drift =
      MeasureResidualDrift("bearing", Ar1Series(50, 400, phi, 11));
  EXPECT_NEAR(drift.ratio, expected, 0.1 * expected);  // 6.57
  EXPECT_TRUE(drift.drifts);
}

TEST(ResidualDriftTest, ExactRatiosAndTheirLimits) {
  // A constant error: each batch sums to 16, so the ratio is 16; two
  // batches are too few to call it.
  ResidualDrift drift = MeasureResidualDrift(
      "range", {{3, std::vector<double>(32, 1.0)}, {4, {1.0, 2.0}}});
  EXPECT_EQ(drift.batches, 2);
  EXPECT_EQ(drift.ratio, 16.0);
  EXPECT_FALSE(drift.drifts);
  // Alternating signs cancel in every batch but the outlier's, which counts
  // at 5 robust sigmas (1.4826 times the median |r| of 1).
  std::vector<double> alternating(32);
  for (int i = 0; i < 32; ++i) alternating[i] = i % 2 == 0 ? 1.0 : -1.0;
  alternating[0] = 1e6;
  drift = MeasureResidualDrift("range", {{0, alternating}});
  const double level = 5.0 * 1.4826;
  EXPECT_NEAR(drift.ratio,
              (level - 1.0) * (level - 1.0) / (level * level + 31.0), 1e-15);
  // Nothing to judge: no whole batch, or no error at all.
  drift = MeasureResidualDrift("bearing", {{0, {0.5, -0.5}}});
  EXPECT_EQ(drift.batches, 0);
  EXPECT_EQ(drift.ratio, 1.0);
  EXPECT_FALSE(drift.drifts);
  drift = MeasureResidualDrift("bearing", {{0, std::vector<double>(64, 0.0)}});
  EXPECT_EQ(drift.batches, 0);
  EXPECT_EQ(drift.ratio, 1.0);
  EXPECT_FALSE(drift.drifts);
  drift = MeasureResidualDrift("bearing", {});
  EXPECT_EQ(drift.batches, 0);
  EXPECT_EQ(drift.ratio, 1.0);
}

// The drift of each value in a solve's result; fails the test if absent.
const ResidualDrift& DriftOf(const SlamResult& result,
                             const std::string& kind) {
  for (const ResidualDrift& drift : result.residual_drift) {
    if (drift.kind == kind) return drift;
  }
  ADD_FAILURE() << "no drift of " << kind;
  static const ResidualDrift none;
  return none;
}

// On the simulator's white errors the solve's residuals do not drift (range
// and bearing ratios 0.72: the fit takes some of each batch). Add to each
// range a bias of 2 sigmas that turns over 400 s with a phase of the
// landmark's own, as a camera's range error follows the viewing geometry
// (a landmark's 16 sightings here span about 3 minutes), and the ranges
// drift (4.66 over 50 batches) while the bearings do not (0.85), and the
// summary says the covariances are optimistic.
TEST(ResidualDriftSolveTest, ReportsRangesThatDriftTogether) {
  SimulationOptions simulation = PaperOptions(4);
  Dataset dataset;
  std::string error;
  ASSERT_TRUE(Simulate(simulation, &dataset, &error)) << error;
  SlamOptions options;
  options.prior = "wnoa";
  options.output.covariance = true;
  SlamResult white;
  ASSERT_TRUE(RunSlam(dataset, options, &white, &error)) << error;
  EXPECT_FALSE(DriftOf(white, "range").drifts);
  EXPECT_FALSE(DriftOf(white, "bearing").drifts);
  // Every range-bearing row in its landmark's range and bearing series.
  std::map<LandmarkId, int> sightings;
  for (const Observation& o : dataset.observations) ++sightings[o.id];
  int batches = 0;
  for (const auto& [id, count] : sightings) batches += count / kDriftBatch;
  EXPECT_EQ(DriftOf(white, "range").batches, batches);
  EXPECT_EQ(DriftOf(white, "bearing").batches, batches);

  for (Observation& o : dataset.observations) {
    o.range +=
        2.0 * o.sigma_range * std::sin(2.0 * M_PI * o.t / 400.0 + 0.7 * o.id);
  }
  SlamResult drifting;
  ASSERT_TRUE(RunSlam(dataset, options, &drifting, &error)) << error;
  const ResidualDrift& range = DriftOf(drifting, "range");
  EXPECT_TRUE(range.drifts) << range.ratio;
  EXPECT_FALSE(DriftOf(drifting, "bearing").drifts);
  std::ostringstream summary;
  PrintSlamSummary(options, drifting, &summary);
  EXPECT_NE(summary.str().find("covariance   optimistic: the range residuals "
                               "drift together"),
            std::string::npos)
      << summary.str();
}

}  // namespace
}  // namespace rff
