#include "rff_ceres/perturb.h"

#include <cmath>
#include <filesystem>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "gtest/gtest.h"
#include "rff_ceres/io/dataset_io.h"
#include "rff_ceres/io/text_parser.h"
#include "test/test_files.h"

namespace rff {
namespace {

std::string ToText(const Dataset& dataset) {
  std::ostringstream output;
  WriteDataset(dataset, &output);
  return output.str();
}

// `num_landmarks` landmarks with priors at their truth, the even ids with
// sigma 0.5 and the odd ones with sigma 3 (below and above the offsets
// used here); two pose priors, the earliest at t = 0 with heading 3 rad;
// odometry, one observation and ground truth, which must never change.
Dataset ManyPriors(int num_landmarks) {
  Dataset d;
  d.metadata.emplace_back("source", "perturb_test");
  d.pose_priors.push_back({{5.0, 5.0, 0.0, 1.0}, 0.1, 0.02});
  d.pose_priors.push_back({{0.0, 0.0, 0.0, 3.0}, 0.1, 0.01});
  for (int i = 0; i < num_landmarks; ++i) {
    const double x = 0.5 * i, y = -0.25 * i;
    d.landmark_priors.push_back({i, x, y, i % 2 == 0 ? 0.5 : 3.0});
    Landmark truth;
    truth.id = i;
    truth.x = x;
    truth.y = y;
    d.ground_truth_landmarks.push_back(truth);
  }
  for (int k = 0; k < 5; ++k) {
    d.odometry.push_back({1.0 * k, k + 1.0, 1.0, 0.0, 0.1, 0.05, 0.05, 0.01});
    d.ground_truth.push_back({1.0 * k, 1.0 * k, 0.0, 3.0 + 0.1 * k});
  }
  Observation observation;
  observation.type = ObservationType::kRangeBearing;
  observation.t = 1.0;
  observation.id = 3;
  observation.range = 2.0;
  observation.bearing = 0.5;
  observation.sigma_range = 0.1;
  observation.sigma_bearing = 0.02;
  d.observations.push_back(observation);
  return d;
}

// Everything a perturbation must leave alone (all but the priors and the
// metadata), as text.
std::string Untouchable(Dataset dataset) {
  dataset.metadata.clear();
  dataset.pose_priors.clear();
  dataset.landmark_priors.clear();
  return ToText(dataset);
}

Dataset Perturbed(const PerturbOptions& options, const Dataset& input) {
  Dataset d = input;
  std::string error;
  EXPECT_TRUE(PerturbDataset(options, &d, &error)) << error;
  return d;
}

// The offsets are N(0, 2^2) per axis. Over n = 5000 priors the sample
// standard deviation of one axis has a standard error of 2 / sqrt(2 n) =
// 0.02 and the sample mean one of 2 / sqrt(n) = 0.028; the bounds are 5
// standard errors (a false alarm for a fresh seed has probability < 1e-6;
// with the fixed seed the test is deterministic). The sample correlation
// of x and y offsets has a standard error of 1 / sqrt(n) = 0.014.
TEST(PerturbTest, LandmarkOffsetsHaveTheRequestedSigma) {
  constexpr int kLandmarks = 5000;
  const Dataset input = ManyPriors(kLandmarks);
  PerturbOptions options;
  options.landmark_prior_offset = 2.0;
  options.seed = 11;
  const Dataset d = Perturbed(options, input);
  ASSERT_EQ(d.landmark_priors.size(), input.landmark_priors.size());
  std::vector<double> dx, dy;
  for (int i = 0; i < kLandmarks; ++i) {
    const LandmarkPrior& before = input.landmark_priors[i];
    const LandmarkPrior& after = d.landmark_priors[i];
    EXPECT_EQ(after.id, before.id);
    // max(sigma, offset): 0.5 is raised to 2, 3 stays.
    EXPECT_EQ(after.sigma, i % 2 == 0 ? 2.0 : 3.0) << i;
    dx.push_back(after.x - before.x);
    dy.push_back(after.y - before.y);
  }
  auto mean = [](const std::vector<double>& v) {
    double sum = 0.0;
    for (double x : v) sum += x;
    return sum / v.size();
  };
  auto covariance = [&](const std::vector<double>& a,
                        const std::vector<double>& b) {
    const double ma = mean(a), mb = mean(b);
    double sum = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      sum += (a[i] - ma) * (b[i] - mb);
    }
    return sum / (a.size() - 1);
  };
  EXPECT_NEAR(mean(dx), 0.0, 5 * 0.028);
  EXPECT_NEAR(mean(dy), 0.0, 5 * 0.028);
  EXPECT_NEAR(std::sqrt(covariance(dx, dx)), 2.0, 5 * 0.02);
  EXPECT_NEAR(std::sqrt(covariance(dy, dy)), 2.0, 5 * 0.02);
  EXPECT_NEAR(
      covariance(dx, dy) / std::sqrt(covariance(dx, dx) * covariance(dy, dy)),
      0.0, 5 * 0.014);

  EXPECT_EQ(Untouchable(d), Untouchable(input));
  EXPECT_EQ(ToText(Dataset{{}, d.pose_priors}),
            ToText(Dataset{{}, input.pose_priors}));
  ASSERT_EQ(d.metadata.size(), 2u);
  EXPECT_EQ(d.metadata[0], input.metadata[0]);
  EXPECT_EQ(d.metadata[1].first, "perturbation");
  EXPECT_EQ(d.metadata[1].second,
            "landmark_prior_offset=2 seed=11: 5000 PRIOR_LANDMARK means moved "
            "by N(0, 2^2) per axis, sigmas raised to at least 2");
}

TEST(PerturbTest, StartHeadingIsRotatedAndWrapped) {
  const Dataset input = ManyPriors(3);
  PerturbOptions options;
  options.start_heading_offset_deg = 90.0;
  options.start_heading_sigma = M_PI;
  Dataset d = Perturbed(options, input);
  // The earliest prior (t = 0, the second record): 3 + pi/2 wraps below -pi.
  EXPECT_NEAR(d.pose_priors[1].pose.theta, 3.0 + M_PI / 2.0 - 2.0 * M_PI,
              1e-15);
  EXPECT_EQ(d.pose_priors[1].sigma_theta, M_PI);
  EXPECT_EQ(d.pose_priors[1].pose.x, 0.0);
  EXPECT_EQ(d.pose_priors[1].sigma_xy, 0.1);
  // The later prior is not the start.
  EXPECT_EQ(ToText(Dataset{{}, {d.pose_priors[0]}}),
            ToText(Dataset{{}, {input.pose_priors[0]}}));
  EXPECT_EQ(ToText(Dataset{{}, {}, d.landmark_priors}),
            ToText(Dataset{{}, {}, input.landmark_priors}));
  EXPECT_EQ(Untouchable(d), Untouchable(input));
  ASSERT_EQ(d.metadata.size(), 2u);
  EXPECT_EQ(d.metadata[1].first, "perturbation");
  EXPECT_EQ(d.metadata[1].second,
            "start_heading_offset_deg=90 start_heading_sigma=" +
                FormatNumber(M_PI) + " seed=1: PRIOR_POSE at t=0 theta 3 -> " +
                FormatNumber(d.pose_priors[1].pose.theta) +
                ", sigma_theta 0.01 -> " + FormatNumber(M_PI));

  // 180 degrees from 3 rad: 3 - pi, inside (-pi, pi]; the sigma unchanged
  // when not given. -270 is +90 once wrapped.
  options.start_heading_offset_deg = 180.0;
  options.start_heading_sigma.reset();
  d = Perturbed(options, input);
  EXPECT_NEAR(d.pose_priors[1].pose.theta, 3.0 - M_PI, 1e-15);
  EXPECT_EQ(d.pose_priors[1].sigma_theta, 0.01);
  options.start_heading_offset_deg = -270.0;
  d = Perturbed(options, input);
  EXPECT_NEAR(d.pose_priors[1].pose.theta, 3.0 + M_PI / 2.0 - 2.0 * M_PI,
              1e-15);
  // A sigma alone keeps the heading.
  options.start_heading_offset_deg = 0.0;
  options.start_heading_sigma = 1.5;
  d = Perturbed(options, input);
  EXPECT_EQ(d.pose_priors[1].pose.theta, 3.0);
  EXPECT_EQ(d.pose_priors[1].sigma_theta, 1.5);
}

// Two priors at the earliest time: both are the start, and both turn.
TEST(PerturbTest, EveryPriorAtTheStartIsTurned) {
  Dataset input = ManyPriors(1);
  input.pose_priors.push_back({{0.0, 0.0, 0.0, -1.0}, 0.2, 0.05});
  PerturbOptions options;
  options.start_heading_offset_deg = 90.0;
  const Dataset d = Perturbed(options, input);
  EXPECT_NEAR(d.pose_priors[1].pose.theta, 3.0 + M_PI / 2.0 - 2.0 * M_PI,
              1e-15);
  EXPECT_NEAR(d.pose_priors[2].pose.theta, -1.0 + M_PI / 2.0, 1e-15);
  EXPECT_EQ(d.pose_priors[0].pose.theta, 1.0);
  EXPECT_EQ(d.metadata.back().second,
            "start_heading_offset_deg=90 seed=1: PRIOR_POSE at t=0 theta 3 "
            "-> " +
                FormatNumber(d.pose_priors[1].pose.theta) +
                ", sigma_theta 0.01 -> 0.01; PRIOR_POSE at t=0 theta -1 -> " +
                FormatNumber(d.pose_priors[2].pose.theta) +
                ", sigma_theta 0.05 -> 0.05");
}

TEST(PerturbTest, SameSeedGivesIdenticalOutputAndAnotherSeedDiffers) {
  const Dataset input = ManyPriors(20);
  PerturbOptions options;
  options.landmark_prior_offset = 1.0;
  options.start_heading_offset_deg = 45.0;
  options.seed = 101;
  const std::string a = ToText(Perturbed(options, input));
  EXPECT_EQ(a, ToText(Perturbed(options, input)));
  options.seed = 102;
  const Dataset other = Perturbed(options, input);
  EXPECT_NE(a, ToText(other));
  const Dataset first = Perturbed(PerturbOptions{1.0, 45.0, {}, 101}, input);
  for (std::size_t i = 0; i < input.landmark_priors.size(); ++i) {
    EXPECT_NE(other.landmark_priors[i].x, first.landmark_priors[i].x) << i;
  }
  // The heading change draws nothing: it is the same with either seed.
  EXPECT_EQ(other.pose_priors[1].pose.theta, first.pose_priors[1].pose.theta);
}

TEST(PerturbTest, NothingAskedChangesNothing) {
  const Dataset input = ManyPriors(4);
  const Dataset d = Perturbed(PerturbOptions(), input);
  EXPECT_EQ(ToText(d), ToText(input));
}

TEST(PerturbTest, RejectsBadOptionsWithExactMessages) {
  struct Case {
    std::function<void(PerturbOptions*)> change;
    std::string message;
  };
  const std::vector<Case> cases = {
      {[](PerturbOptions* o) { o->landmark_prior_offset = -1.0; },
       "--landmark_prior_offset=-1: allowed 0 to 1e+06 m"},
      {[](PerturbOptions* o) { o->landmark_prior_offset = NAN; },
       "--landmark_prior_offset=nan: allowed 0 to 1e+06 m"},
      {[](PerturbOptions* o) { o->landmark_prior_offset = INFINITY; },
       "--landmark_prior_offset=inf: allowed 0 to 1e+06 m"},
      {[](PerturbOptions* o) { o->start_heading_offset_deg = NAN; },
       "--start_heading_offset_deg=nan: allowed -360 to 360 degrees"},
      {[](PerturbOptions* o) { o->start_heading_offset_deg = -400.0; },
       "--start_heading_offset_deg=-400: allowed -360 to 360 degrees"},
      {[](PerturbOptions* o) { o->start_heading_sigma = 0.0; },
       "--start_heading_sigma=0: allowed more than 0 up to 1e+06 rad"},
      {[](PerturbOptions* o) { o->start_heading_sigma = -1.0; },
       "--start_heading_sigma=-1: allowed more than 0 up to 1e+06 rad"},
      {[](PerturbOptions* o) { o->start_heading_sigma = -INFINITY; },
       "--start_heading_sigma=-inf: allowed more than 0 up to 1e+06 rad"},
  };
  for (const Case& c : cases) {
    PerturbOptions options;
    c.change(&options);
    std::string error;
    EXPECT_FALSE(ValidatePerturbOptions(options, &error)) << c.message;
    EXPECT_EQ(error, c.message);
    Dataset d = ManyPriors(3);
    error.clear();
    EXPECT_FALSE(PerturbDataset(options, &d, &error));
    EXPECT_EQ(error, c.message);
    EXPECT_EQ(ToText(d), ToText(ManyPriors(3)));
  }
  std::string error;
  EXPECT_TRUE(ValidatePerturbOptions(PerturbOptions(), &error)) << error;
}

TEST(PerturbTest, RejectsDatasetsWithoutThePriorsToChange) {
  Dataset no_pose = ManyPriors(3);
  no_pose.pose_priors.clear();
  PerturbOptions options;
  options.start_heading_sigma = M_PI;
  std::string error;
  EXPECT_FALSE(PerturbDataset(options, &no_pose, &error));
  EXPECT_EQ(error, "start_heading_offset_deg=0 start_heading_sigma=" +
                       FormatNumber(M_PI) +
                       " seed=1 changes the start heading, but there is no "
                       "PRIOR_POSE record");

  Dataset no_landmarks = ManyPriors(0);
  options = PerturbOptions();
  options.landmark_prior_offset = 1.0;
  options.seed = 7;
  EXPECT_FALSE(PerturbDataset(options, &no_landmarks, &error));
  EXPECT_EQ(error,
            "landmark_prior_offset=1 seed=7 moves the landmark priors, but "
            "there is no PRIOR_LANDMARK record");
  EXPECT_EQ(ToText(no_landmarks), ToText(ManyPriors(0)));
}

TEST(PerturbFileTest, WritesThePerturbedDatasetWithItsMetadata) {
  const std::string dir = testing::TempDir("perturb_test");
  std::string error;
  ASSERT_TRUE(WriteDataset(ManyPriors(10), dir + "/in.rffd", &error)) << error;
  PerturbOptions options;
  options.landmark_prior_offset = 1.0;
  options.start_heading_offset_deg = 180.0;
  options.start_heading_sigma = M_PI;
  options.seed = 104;
  ASSERT_TRUE(PerturbFile(dir + "/in.rffd", dir + "/out.rffd", options, &error))
      << error;
  Dataset read, expected;
  ASSERT_TRUE(ReadDataset(dir + "/out.rffd", &read, &error)) << error;
  ASSERT_TRUE(ReadDataset(dir + "/in.rffd", &expected, &error)) << error;
  ASSERT_TRUE(PerturbDataset(options, &expected, &error)) << error;
  EXPECT_EQ(ToText(read), ToText(expected));
  ASSERT_EQ(read.metadata.size(), 3u);
  EXPECT_EQ(read.metadata[1].second.rfind("landmark_prior_offset=1 seed=104:"),
            0u);
  EXPECT_EQ(read.metadata[2].second.rfind(
                "start_heading_offset_deg=180 start_heading_sigma=" +
                FormatNumber(M_PI) + " seed=104: PRIOR_POSE at t=0 theta 3 "),
            0u);
}

TEST(PerturbFileTest, RefusesBadFilesAndWritesNothing) {
  const std::string dir = testing::TempDir("perturb_test");
  std::string error;
  ASSERT_TRUE(WriteDataset(ManyPriors(0), dir + "/in.rffd", &error)) << error;
  const std::string original = testing::ReadFile(dir + "/in.rffd");
  PerturbOptions offset;
  offset.landmark_prior_offset = 1.0;
  PerturbOptions turn;
  turn.start_heading_offset_deg = 90.0;
  struct Case {
    std::string input, output;
    PerturbOptions options;
    std::string message;
  };
  const std::vector<Case> cases = {
      {dir + "/in.rffd", dir + "/in.rffd", offset,
       "--output=" + dir + "/in.rffd: the same file as the input --input=" +
           dir + "/in.rffd; allowed another path"},
      {dir + "/in.rffd", dir + "/./in.rffd", offset,
       "--output=" + dir + "/./in.rffd: the same file as the input --input=" +
           dir + "/in.rffd; allowed another path"},
      {dir + "/none.rffd", dir + "/out.rffd", offset,
       dir + "/none.rffd: cannot open for reading: No such file or directory"},
      {dir + "/in.rffd", dir + "/out.rffd", offset,
       dir + "/in.rffd: landmark_prior_offset=1 seed=1 moves the landmark "
             "priors, but there is no PRIOR_LANDMARK record"},
      {dir + "/in.rffd", dir + "/out.rffd", PerturbOptions{-2.0, 0.0, {}, 1},
       "--landmark_prior_offset=-2: allowed 0 to 1e+06 m"},
      {dir + "/in.rffd", dir + "/no/such/dir/out.rffd", turn,
       dir + "/no/such/dir/out.rffd: cannot open for writing: No such file "
             "or directory"},
      // A copy under another name would pass for a perturbed file.
      {dir + "/none.rffd", dir + "/out.rffd", PerturbOptions(),
       "nothing to perturb: give --landmark_prior_offset, "
       "--start_heading_offset_deg or --start_heading_sigma"},
  };
  for (const Case& c : cases) {
    error.clear();
    EXPECT_FALSE(PerturbFile(c.input, c.output, c.options, &error));
    EXPECT_EQ(error, c.message);
    EXPECT_FALSE(std::filesystem::exists(dir + "/out.rffd")) << c.message;
    EXPECT_EQ(testing::ReadFile(dir + "/in.rffd"), original) << c.message;
  }
}

}  // namespace
}  // namespace rff
