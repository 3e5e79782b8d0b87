#include "rff_ceres/feature_trajectory.h"

#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "gtest/gtest.h"
#include "rff_ceres/features/hilbert_features.h"
#include "rff_ceres/kernels/kernel.h"
#include "rff_ceres/mean/mean_function.h"

namespace rff {
namespace {

std::shared_ptr<const MeanFunction> ZeroMean() {
  return std::make_shared<PiecewiseLinearMean>(
      std::vector<TimedPose>{{0.0, 0.0, 0.0, 0.0}});
}

// Every weight drawn from N(0, 1), block by block.
void RandomizeWeights(FeatureTrajectory* model, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  for (int b = 0; b < model->num_blocks(); ++b) {
    for (int i = 0; i < model->block_size(b); ++i) {
      model->mutable_block(b)[i] = normal(rng);
    }
  }
}

// Options with the given kernels (x and y, theta) and feature counts.
FeatureTrajectoryOptions Options(const KernelOptions& position,
                                 const KernelOptions& heading, int features) {
  FeatureTrajectoryOptions options;
  options.position_kernel = position;
  options.heading_kernel = heading;
  options.num_position_features = features;
  options.num_heading_features = features;
  return options;
}

// Windows of 20 s blended over 8 s, `features` per window, RBF kernels of
// 4 s (x, y) and 0.3 s (theta).
FeatureTrajectoryOptions WindowedOptions(int features) {
  FeatureTrajectoryOptions options =
      Options({"rbf", 4.0, 3.0}, {"rbf", 0.3, 3.0}, features);
  options.segment_length = 20.0;
  options.segment_overlap = 8.0;
  return options;
}

// Prior covariance of coordinate c at t and u under b ~ N(0, I): the sum of
// phi_t . phi_u over the terms of the two maps that share a block.
double PriorCovariance(const FeatureTrajectory& model, int c, double t,
                       double u) {
  const PoseMap a = model.PoseAt(t), b = model.PoseAt(u);
  double covariance = 0.0;
  for (const PoseTerm& p : a.terms) {
    for (const PoseTerm& q : b.terms) {
      if (p.coordinate == c && q.coordinate == c && p.block == q.block) {
        covariance += p.phi->dot(*q.phi);
      }
    }
  }
  return covariance;
}

// The weight-space prior is the kernel (paper eq. 4): with ample Hilbert
// features on one global map, phi(t)^T phi(u) = k(t - u) for x, y and theta.
TEST(FeatureTrajectoryTest, PriorCovarianceIsTheKernel) {
  const FeatureTrajectoryOptions options =
      Options({"matern52", 4.0, 5.0}, {"rbf", 0.3, 8.0}, 200);
  std::string error;
  const auto model =
      FeatureTrajectory::Create(options, ZeroMean(), 0.0, 60.0, &error);
  ASSERT_TRUE(model) << error;
  ASSERT_EQ(model->num_segments(), 1);
  const auto position = CreateKernel(options.position_kernel, &error);
  const auto heading = CreateKernel(options.heading_kernel, &error);
  for (const double t : {10.0, 30.0, 50.0}) {
    for (const double lag : {0.0, 1.0, 4.0, 12.0}) {
      EXPECT_NEAR(PriorCovariance(*model, 0, t, t - lag),
                  position->Evaluate(lag), 0.02 * 4.0)
          << "x at " << t << ", lag " << lag;
      EXPECT_NEAR(PriorCovariance(*model, 1, t, t - lag),
                  position->Evaluate(lag), 0.02 * 4.0);
      EXPECT_NEAR(PriorCovariance(*model, 2, t, t - lag),
                  heading->Evaluate(lag), 0.02 * 0.3)
          << "theta at " << t << ", lag " << lag;
    }
  }
}

// Windowed weights: the pose is continuous across the blends of segments
// (random weights, the derivative bounded by the features' bandwidth).
TEST(FeatureTrajectoryTest, SegmentsBlendContinuously) {
  std::string error;
  auto model = FeatureTrajectory::Create(WindowedOptions(40), ZeroMean(), 0.0,
                                         100.0, &error);
  ASSERT_TRUE(model) << error;
  EXPECT_EQ(model->num_segments(), 5);
  RandomizeWeights(model.get(), 3);
  const double step = 1e-4;
  for (double t = 0.5; t < 99.5; t += 0.25) {
    const Eigen::Vector3d jump = model->Pose(t + step) - model->Pose(t);
    EXPECT_LT(jump.cwiseAbs().maxCoeff(), 20.0 * step) << "at t " << t;
  }
}

// Pose() without the PoseMap is the map's value to the bit, in blends and
// single segments, with a mean that is not zero.
TEST(FeatureTrajectoryTest, PoseIsThePoseMapsValue) {
  std::string error;
  auto model = FeatureTrajectory::Create(
      WindowedOptions(12),
      std::make_shared<PiecewiseLinearMean>(std::vector<TimedPose>{
          {0.0, 1.0, -2.0, 0.3}, {100.0, 7.0, 4.0, -1.0}}),
      0.0, 100.0, &error);
  ASSERT_TRUE(model) << error;
  RandomizeWeights(model.get(), 5);
  for (double t = -3.0; t < 104.0; t += 0.7) {
    EXPECT_EQ(model->Pose(t), model->TrajectoryModel::Pose(t)) << "t = " << t;
  }
}

// Capacity follows the lengthscale: segments of 10 lengthscales, each with
// about the same number of features (the same number of lengthscales to
// cover at the same tolerance), whatever the lengthscale in seconds.
TEST(FeatureTrajectoryTest, AutoCapacityFollowsTheLengthscale) {
  FeatureTrajectoryOptions options =
      Options({"matern52", 25.0, 8.0}, {"matern52", 0.25, 12.0}, kAutoCapacity);
  const FeatureTrajectoryOptions long_scale = AutoCapacity(options, 600.0);
  EXPECT_DOUBLE_EQ(long_scale.segment_length, 80.0);
  EXPECT_DOUBLE_EQ(long_scale.segment_overlap, 32.0);
  options.position_kernel.lengthscale = 2.0;
  const FeatureTrajectoryOptions short_scale = AutoCapacity(options, 600.0);
  EXPECT_DOUBLE_EQ(short_scale.segment_length, 20.0);
  EXPECT_GT(long_scale.num_position_features, 20);
  EXPECT_NEAR(short_scale.num_position_features,
              long_scale.num_position_features, 3);
  // A run shorter than 1.5 segments: one global map.
  EXPECT_DOUBLE_EQ(AutoCapacity(options, 25.0).segment_length, 0.0);
  // Given capacities are kept.
  options.num_position_features = 7;
  EXPECT_EQ(AutoCapacity(options, 600.0).num_position_features, 7);
}

TEST(FeatureTrajectoryTest, OverlapNotShorterThanTheSegmentFails) {
  FeatureTrajectoryOptions options;
  options.segment_length = 10.0;
  options.segment_overlap = 10.0;
  std::string error;
  EXPECT_EQ(FeatureTrajectory::Create(options, ZeroMean(), 0.0, 50.0, &error),
            nullptr);
  EXPECT_EQ(error,
            "--segment_overlap=10: allowed 0 or more, less than "
            "--segment_length=10");
}

// The prior's weights are bounded by memory: the message gives the features
// and the segment length that fit this run.
TEST(FeatureTrajectoryTest, MoreWeightsThanMemoryAllowsFails) {
  FeatureTrajectoryOptions options;
  options.num_position_features = 512;
  options.num_heading_features = 512;
  options.segment_length = 0.25;
  std::string error;
  EXPECT_EQ(FeatureTrajectory::Create(options, ZeroMean(), 0.0, 100.0, &error),
            nullptr);
  EXPECT_EQ(error,
            "--num_features=512: the run's 100 s need 400 segments of 512 "
            "features (x, y) and 512 (theta): more weights than memory "
            "allows; allowed at most 408 (as many for theta) for this run, or "
            "--segment_length of at least 0.3937007874015748");
}

// Options of the windowed-weight tests: 40 features per map, segments of
// 20 s blended over 8 s, rbf lengthscales of 3 s (gaps over 30 s split).
FeatureTrajectoryOptions WindowedOptions() {
  FeatureTrajectoryOptions options =
      Options({"rbf", 4.0, 3.0}, {"rbf", 0.3, 3.0}, 40);
  options.segment_length = 20.0;
  options.segment_overlap = 8.0;
  return options;
}

int NumWeights(const FeatureTrajectory& model) {
  int count = 0;
  for (int b = 0; b < model.num_blocks(); ++b) count += model.block_size(b);
  return count;
}

// Segments only where data is: two stretches of data 9e5 s apart get the
// segments each gets alone and none over the gap, where the pose is the
// prior mean. The later stretch has the features it has alone, bit for bit.
TEST(FeatureTrajectoryTest, SegmentsOnlyWhereDataIs) {
  const FeatureTrajectoryOptions options = WindowedOptions();
  DataTimes times;
  times.constraints = {{0.0, 100.0}, {9e5, 9e5 + 50.0}};
  std::string error;
  const auto model =
      FeatureTrajectory::Create(options, ZeroMean(), times, &error);
  ASSERT_TRUE(model) << error;
  EXPECT_EQ(model->num_stretches(), 2);
  EXPECT_EQ(model->num_segments(), 5 + 3);
  EXPECT_EQ(NumWeights(*model), (5 + 3) * 3 * 40);
  EXPECT_TRUE(model->PoseAt(4.5e5).terms.empty());
  // The last segment of a stretch reaches 4 lengthscales past it.
  EXPECT_EQ(model->PoseAt(100.0 + 11.5).terms.front().block, 3 * 4);
  EXPECT_TRUE(model->PoseAt(100.0 + 12.5).terms.empty());
  const auto alone =
      FeatureTrajectory::Create(options, ZeroMean(), 9e5, 9e5 + 50.0, &error);
  ASSERT_TRUE(alone) << error;
  ASSERT_EQ(alone->num_segments(), 3);
  for (const double t : {9e5, 9e5 + 17.5, 9e5 + 50.0}) {
    const PoseMap joint = model->PoseAt(t), single = alone->PoseAt(t);
    ASSERT_EQ(joint.terms.size(), single.terms.size()) << t;
    for (std::size_t i = 0; i < joint.terms.size(); ++i) {
      EXPECT_EQ(joint.terms[i].block, single.terms[i].block + 3 * 5);
      EXPECT_EQ(*joint.terms[i].phi, *single.terms[i].phi) << t;
    }
  }
}

// A time only evaluated (a ground-truth pose) 1e6 s from the data adds no
// segment: it is the prior mean. One near the data widens its stretch.
TEST(FeatureTrajectoryTest, StrayQueryAddsNoSegments) {
  DataTimes times;
  times.constraints = {{0.0, 100.0}};
  times.queries = {50.0, 1e6};
  std::string error;
  const auto model =
      FeatureTrajectory::Create(WindowedOptions(), ZeroMean(), times, &error);
  ASSERT_TRUE(model) << error;
  EXPECT_EQ(model->num_stretches(), 1);
  EXPECT_EQ(model->num_segments(), 5);
  EXPECT_TRUE(model->PoseAt(1e6).terms.empty());
  times.queries = {125.0};
  EXPECT_EQ(
      FeatureTrajectory::Create(WindowedOptions(), ZeroMean(), times, &error)
          ->num_segments(),
      7);
}

// The size check counts the segments of every stretch, and says so.
TEST(FeatureTrajectoryTest, MoreWeightsThanMemoryAllowsOverStretchesFails) {
  FeatureTrajectoryOptions options;
  options.num_position_features = 512;
  options.num_heading_features = 512;
  options.segment_length = 0.25;
  DataTimes times;
  times.constraints = {{0.0, 100.0}, {1e6, 1e6 + 50.0}};
  std::string error;
  EXPECT_EQ(FeatureTrajectory::Create(options, ZeroMean(), times, &error),
            nullptr);
  EXPECT_EQ(error,
            "--num_features=512: the data's 150 s (in 2 stretches) need 600 "
            "segments of 512 features (x, y) and 512 (theta): more weights "
            "than memory allows; allowed at most 333 (as many for theta) for "
            "this run, or --segment_length of at least 0.5905511811023622");
}

// The variances of `rescaled` taken in place: pose maps handed out before
// (as a problem's costs hold them) then equal those of a model built with
// the new variances, bit for bit, and the blocks keep their values.
TEST(FeatureTrajectoryTest, AdoptScalesRewritesSharedFeaturesInPlace) {
  std::string error;
  FeatureTrajectoryOptions options = WindowedOptions(8);
  const std::shared_ptr<const MeanFunction> mean = ZeroMean();
  auto model = FeatureTrajectory::Create(options, mean, 0.0, 50.0, &error);
  ASSERT_NE(model, nullptr) << error;
  RandomizeWeights(model.get(), 7);
  const std::vector<double> weights = ModelBlocks(*model);
  const std::vector<double> times = {0.0, 13.5, 26.0, 49.0};
  std::vector<PoseMap> held;
  for (const double t : times) held.push_back(model->PoseAt(t));
  options.position_kernel.variance = 0.03;
  options.heading_kernel.variance = 0.5;
  auto rescaled =
      FeatureTrajectory::Create(options, ZeroMean(), 0.0, 50.0, &error);
  ASSERT_NE(rescaled, nullptr) << error;
  // A different mean object: the costs' maps carry the old one.
  EXPECT_FALSE(model->AdoptScales(rescaled.get()));
  auto same_mean = FeatureTrajectory::Create(options, mean, 0.0, 50.0, &error);
  ASSERT_NE(same_mean, nullptr) << error;
  const std::vector<PoseMap> expected = [&] {
    std::vector<PoseMap> maps;
    for (const double t : times) maps.push_back(same_mean->PoseAt(t));
    return maps;
  }();
  ASSERT_TRUE(model->AdoptScales(same_mean.get()));
  EXPECT_EQ(model->options().position_kernel.variance, 0.03);
  EXPECT_EQ(ModelBlocks(*model), weights);
  for (std::size_t i = 0; i < times.size(); ++i) {
    ASSERT_EQ(held[i].terms.size(), expected[i].terms.size()) << times[i];
    for (std::size_t k = 0; k < held[i].terms.size(); ++k) {
      const Eigen::VectorXd& phi = *held[i].terms[k].phi;
      EXPECT_TRUE(phi == *expected[i].terms[k].phi) << times[i] << " " << k;
      EXPECT_TRUE(*model->PoseAt(times[i]).terms[k].phi == phi);
    }
  }
  // Another capacity is another structure: refused, nothing changed.
  FeatureTrajectoryOptions wider = options;
  wider.num_position_features = 12;
  auto other = FeatureTrajectory::Create(wider, mean, 0.0, 50.0, &error);
  ASSERT_NE(other, nullptr) << error;
  EXPECT_FALSE(model->AdoptScales(other.get()));
  EXPECT_TRUE(*held[1].terms[0].phi == *expected[1].terms[0].phi);
}

// More modes of the same basis: each block grows by the next modes of its
// Hilbert domain until the missed spectral mass is a twentieth of the
// basis's (the fewest that do); the first features of every map and all
// weights are the model's, so its poses are too.
TEST(FeatureTrajectoryTest, MoreModesKeepTheModelsFeaturesAndPoses) {
  std::string error;
  auto model = FeatureTrajectory::Create(WindowedOptions(12), ZeroMean(), 0.0,
                                         100.0, &error);
  ASSERT_NE(model, nullptr) << error;
  RandomizeWeights(model.get(), 11);
  auto wider = model->WithMoreModes(0.05, 4, &error);
  ASSERT_NE(wider, nullptr) << error;
  ASSERT_EQ(wider->num_blocks(), model->num_blocks());
  for (int b = 0; b < model->num_blocks(); ++b) {
    const int d = model->block_size(b);
    EXPECT_GT(wider->block_size(b), d) << b;
    EXPECT_LE(wider->block_size(b), 4 * d) << b;
    for (int i = 0; i < wider->block_size(b); ++i) {
      EXPECT_EQ(wider->block(b)[i], i < d ? model->block(b)[i] : 0.0);
    }
  }
  for (double t = -2.0; t < 102.0; t += 0.9) {
    EXPECT_LT((wider->Pose(t) - model->Pose(t)).norm(), 1e-12) << t;
    const PoseMap narrow = model->PoseAt(t), wide = wider->PoseAt(t);
    ASSERT_EQ(wide.terms.size(), narrow.terms.size()) << t;
    for (std::size_t k = 0; k < narrow.terms.size(); ++k) {
      const Eigen::VectorXd& phi = *narrow.terms[k].phi;
      EXPECT_TRUE(wide.terms[k].phi->head(phi.size()) == phi) << t;
    }
  }
  // The fewest modes that miss a twentieth: of the x block of the first
  // segment (rbf, 3 s), on the domain its map has.
  std::string kernel_error;
  const std::unique_ptr<Kernel> kernel =
      CreateKernel({"rbf", 4.0, 3.0}, &kernel_error);
  ASSERT_NE(kernel, nullptr) << kernel_error;
  FeatureMapOptions map;
  map.window_begin = 0.0;
  map.window_end = 24.0;  // 20 s and half the 8 s overlap.
  const double half_width = HilbertHalfWidth(*kernel, map);
  auto tail = [&](int modes) {
    return 1.0 -
           kernel->FrequencyCdf(M_PI * (modes + 0.5) / (2.0 * half_width));
  };
  const int modes = wider->block_size(0);
  EXPECT_EQ(modes, HilbertModesForTail(*kernel, half_width, 12, 0.05, 48));
  EXPECT_LE(tail(modes), 0.05 * tail(12));
  EXPECT_GT(tail(modes - 1), 0.05 * tail(12));

  // Random features have no next modes.
  FeatureTrajectoryOptions random = WindowedOptions(12);
  random.family = "rff";
  auto drawn =
      FeatureTrajectory::Create(random, ZeroMean(), 0.0, 100.0, &error);
  ASSERT_NE(drawn, nullptr) << error;
  EXPECT_EQ(drawn->WithMoreModes(0.05, 4, &error), nullptr);
  EXPECT_EQ(error,
            "more modes of the same basis need the hilbert family, not rff");
}

}  // namespace
}  // namespace rff
