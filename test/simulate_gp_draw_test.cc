#include "rff_ceres/simulate_gp_draw.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <map>
#include <string>
#include <vector>

#include "gtest/gtest.h"
#include "rff_ceres/simulate.h"

namespace rff {
namespace {

// Sample moments of many draws at three times match the kernel: the
// variance k(0) and the correlations k(dt) / k(0). With 4000 draws the
// standard error of a correlation near 0.5 is about 0.012.
TEST(DrawGaussianProcessTest, SampleCovarianceIsTheKernel) {
  std::string error;
  const std::unique_ptr<Kernel> kernel =
      CreateKernel({"matern52", 2.0, 5.0}, &error);
  ASSERT_TRUE(kernel) << error;
  const std::vector<double> times = {0.0, 3.0, 9.0};
  SimulationRandom random(17);
  const int draws = 4000;
  double sum[3] = {0, 0, 0}, product[3][3] = {};
  for (int d = 0; d < draws; ++d) {
    std::vector<double> values;
    ASSERT_TRUE(DrawGaussianProcess(*kernel, times, &random, &values, &error))
        << error;
    for (int i = 0; i < 3; ++i) {
      sum[i] += values[i];
      for (int j = 0; j < 3; ++j) product[i][j] += values[i] * values[j];
    }
  }
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(sum[i] / draws, 0.0, 4.0 * std::sqrt(2.0 / draws));
    EXPECT_NEAR(product[i][i] / draws, 2.0, 0.15);
    for (int j = 0; j < i; ++j) {
      const double correlation =
          product[i][j] / std::sqrt(product[i][i] * product[j][j]);
      EXPECT_NEAR(correlation, kernel->Evaluate(times[i] - times[j]) / 2.0,
                  0.05)
          << "times " << times[i] << ", " << times[j];
    }
  }
}

TEST(GpDrawPresetTest, SameSeedSameDrawAndTheSetupOfTheHeldOutFile) {
  Dataset a, b, c;
  std::string error;
  ASSERT_TRUE(Simulate(GpDrawOptions(5), &a, &error)) << error;
  ASSERT_TRUE(Simulate(GpDrawOptions(5), &b, &error)) << error;
  ASSERT_TRUE(Simulate(GpDrawOptions(6), &c, &error)) << error;
  ASSERT_EQ(a.ground_truth.size(), 600u);
  ASSERT_EQ(b.ground_truth.size(), 600u);
  for (std::size_t k = 0; k < a.ground_truth.size(); ++k) {
    EXPECT_EQ(a.ground_truth[k].x, b.ground_truth[k].x);
    EXPECT_EQ(a.ground_truth[k].theta, b.ground_truth[k].theta);
  }
  EXPECT_NE(a.ground_truth[10].x, c.ground_truth[10].x);

  EXPECT_TRUE(a.odometry.empty());
  EXPECT_EQ(a.landmark_priors.size(), 25u);
  EXPECT_EQ(a.observations.size(), 4u * 600u);
  // Each pose observes the 4 nearest landmarks at least 1 m away.
  std::map<LandmarkId, Landmark> truth;
  for (const Landmark& l : a.ground_truth_landmarks) truth[l.id] = l;
  for (std::size_t k = 0; k < a.ground_truth.size(); k += 50) {
    const TimedPose& pose = a.ground_truth[k];
    std::vector<double> distances;
    for (const Landmark& l : a.ground_truth_landmarks) {
      const double d = std::hypot(l.x - pose.x, l.y - pose.y);
      if (d >= 1.0) distances.push_back(d);
    }
    std::sort(distances.begin(), distances.end());
    double farthest_seen = 0.0;
    int seen = 0;
    for (const Observation& o : a.observations) {
      if (o.t != pose.t) continue;
      ++seen;
      EXPECT_EQ(o.type, ObservationType::kRangeBearing);
      farthest_seen = std::max(farthest_seen, std::hypot(truth[o.id].x - pose.x,
                                                         truth[o.id].y - pose.y));
    }
    EXPECT_EQ(seen, 4);
    EXPECT_DOUBLE_EQ(farthest_seen, distances[3]);
  }
}

TEST(GpDrawTruthTest, RoundTripsAndNamesBadTokens) {
  SimulationOptions options = GpDrawOptions(1);
  options.gp_kernel = "rbf";
  options.gp_lengthscale = 30.0;
  options.gp_heading_kernel_variance = 0.125;
  const std::string line = GpDrawTruth(options);
  EXPECT_EQ(line,
            "kernel=rbf lengthscale=30 kernel_variance=25 "
            "heading_lengthscale=12 heading_kernel_variance=0.125");
  KernelOptions position, heading;
  std::string error;
  ASSERT_TRUE(ParseGpDrawTruth(line, &position, &heading, &error)) << error;
  EXPECT_EQ(position.name, "rbf");
  EXPECT_EQ(heading.name, "rbf");
  EXPECT_EQ(position.lengthscale, 30.0);
  EXPECT_EQ(position.variance, 25.0);
  EXPECT_EQ(heading.lengthscale, 12.0);
  EXPECT_EQ(heading.variance, 0.125);

  EXPECT_FALSE(ParseGpDrawTruth(line + " colour=red", &position, &heading,
                                &error));
  EXPECT_EQ(error, "truth: unknown key 'colour'");
  EXPECT_FALSE(ParseGpDrawTruth("kernel=rbf lengthscale=3", &position,
                                &heading, &error));
  EXPECT_EQ(error, "truth: no kernel_variance=");
  EXPECT_FALSE(ParseGpDrawTruth("kernel rbf", &position, &heading, &error));
  EXPECT_EQ(error, "truth: expected key=value, got 'kernel'");
}

TEST(GpDrawOptionsTest, RejectsWhatCannotBeDrawn) {
  std::string error;
  SimulationOptions options = GpDrawOptions(1);
  options.num_steps = kMaxGpDrawSteps + 1;
  EXPECT_FALSE(ValidateSimulationOptions(options, &error));
  EXPECT_EQ(error,
            "--num_steps=5001: a GP draw factorises a dense N x N matrix, "
            "O(N^3); allowed 1 to 5000 with --preset=gp_draw");
  options = GpDrawOptions(1);
  options.gp_heading_lengthscale = 0.0;
  EXPECT_FALSE(ValidateSimulationOptions(options, &error));
  EXPECT_EQ(error,
            "--gp_heading_lengthscale=0: allowed more than 0 up to 1e+06");
  options = GpDrawOptions(1);
  options.gp_kernel = "cubic";
  EXPECT_FALSE(ValidateSimulationOptions(options, &error));
  EXPECT_EQ(error,
            "--gp_kernel=cubic: unknown kernel; allowed rbf, matern12, "
            "matern32, matern52 or periodic");
  // The heading's kernel is checked too, under its own flags.
  options = GpDrawOptions(1);
  options.gp_kernel = "periodic";
  options.gp_heading_lengthscale = 1e-4;
  EXPECT_FALSE(ValidateSimulationOptions(options, &error));
  EXPECT_EQ(error,
            "--gp_heading_lengthscale=1e-04: the periodic kernel's series "
            "would need more than ~12000 terms; allowed 0.001 up to 1e+12 "
            "for the periodic kernel");
}

}  // namespace
}  // namespace rff
