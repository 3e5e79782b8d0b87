#include "rff_ceres/variance_components.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "Eigen/Cholesky"
#include "Eigen/Dense"
#include "ceres/loss_function.h"
#include "ceres/solver.h"
#include "gtest/gtest.h"
#include "rff_ceres/banded_problem.h"
#include "rff_ceres/consistency.h"
#include "rff_ceres/io/pose_covariance_io.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/landmark_init.h"
#include "rff_ceres/mean/prior_mean.h"
#include "rff_ceres/metrics.h"
#include "rff_ceres/priors/trajectory_prior.h"
#include "rff_ceres/scale_learning.h"
#include "rff_ceres/simulate.h"
#include "rff_ceres/slam_report.h"
#include "rff_ceres/slam_solver.h"
#include "test/markov_draws.h"
#include "test/trajectory_difference.h"

namespace rff {
namespace {

// A run drawn from the WNOA prior itself (x, y, theta independent
// integrated white noise of densities qc_position and qc_heading, dt = 1 s,
// starting at rest), seeing landmarks planted beside the path with tight
// priors: range-bearing (0.05 m, 0.01 rad) to every landmark within 12 m.
Dataset WnoaDraw(std::uint64_t seed, int steps, double qc_position,
                 double qc_heading) {
  std::mt19937_64 engine(seed);
  std::normal_distribution<double> normal;
  // Per step, (p, v) += (v dt, 0) + L z with L L^T = qc [1/3 1/2; 1/2 1].
  Eigen::Matrix2d q;
  q << 1.0 / 3.0, 0.5, 0.5, 1.0;
  const Eigen::Matrix2d l = q.llt().matrixL();
  std::vector<TimedPose> truth;
  Eigen::Vector3d p = Eigen::Vector3d::Zero(), v(0.5, 0.0, 0.0);
  for (int k = 0; k < steps; ++k) {
    if (k > 0) {
      for (int c = 0; c < 3; ++c) {
        const double scale = std::sqrt(c < 2 ? qc_position : qc_heading);
        const Eigen::Vector2d w =
            scale * l * Eigen::Vector2d(normal(engine), normal(engine));
        p[c] += v[c] + w[0];
        v[c] += w[1];
      }
    }
    truth.push_back({1.0 * k, p.x(), p.y(), p.z()});
  }
  return testing::SightedDraw(truth, 1, [&] { return normal(engine); });
}

// On a draw from the prior with known densities, alternating MAP solves and
// variance-component rescaling finds them from the defaults (1 and 0.1,
// 100 and 1000x off). Measured: 0.0101 / 0.00012 (seed 1), 0.0097 /
// 0.00012 (seed 2); the heading density is the less determined (the
// bearings fix theta less than the ranges fix x and y).
TEST(VarianceComponentsTest, WnoaLearningRecoversTheDensities) {
  for (const std::uint64_t seed : {1u, 2u}) {
    const Dataset dataset = WnoaDraw(seed, 300, 0.01, 1e-4);
    SlamOptions options;
    options.prior = "wnoa";
    options.problem.loss = options.problem.odometry_loss = {"none", 1.0};
    SlamResult result;
    std::string error;
    ASSERT_TRUE(RunSlam(dataset, options, &result, &error)) << error;
    EXPECT_TRUE(result.learned);
    Evaluation evaluation;
    ASSERT_TRUE(Evaluate(dataset.ground_truth, dataset.ground_truth_landmarks,
                         result.trajectory, nullptr, EvaluationOptions(),
                         &evaluation, &error));
    std::printf(
        "seed %llu: learned Q_c %.4f (truth 0.01), heading %.6f "
        "(truth 1e-4); APE %.4f m\n",
        static_cast<unsigned long long>(seed), result.wnoa_options.position_qc,
        result.wnoa_options.heading_qc, evaluation.ape_translation.rms);
    EXPECT_NEAR(result.wnoa_options.position_qc, 0.01, 0.2 * 0.01);
    EXPECT_NEAR(result.wnoa_options.heading_qc, 1e-4, 0.3 * 1e-4);
  }
}

// The scales a learning reports are those its final solve used: given back
// with learning off, they give the same MAP to the solves' tolerance (the
// last round's factors, within 10% of 1, are not taken). Measured: 2.1e-5
// m apart; 2.7e-4 m where the report took them and the solve did not.
TEST(VarianceComponentsTest, ReportedScalesReproduceTheSolve) {
  const Dataset dataset = WnoaDraw(1, 300, 0.01, 1e-4);
  SlamOptions options;
  options.prior = "wnoa";
  options.problem.loss = options.problem.odometry_loss = {"none", 1.0};
  SlamResult learned;
  std::string error;
  ASSERT_TRUE(RunSlam(dataset, options, &learned, &error)) << error;
  ASSERT_TRUE(learned.learning_converged);
  ASSERT_GT(learned.learning_rounds, 1);
  options.learn_hyperparameters = "off";
  options.wnoa = learned.wnoa_options;
  options.problem.noise = learned.noise;
  SlamResult given;
  ASSERT_TRUE(RunSlam(dataset, options, &given, &error)) << error;
  const double largest = testing::LargestPositionDifference(given, learned);
  std::printf("largest difference %.3g m\n", largest);
  EXPECT_LT(largest, 1e-4);
}

// The final solve after the rounds goes on from their point on their
// problem but for a rescale: it starts at the largest trust radius their
// solves reached, not at the initial 1e4, and converges. Measured: it
// starts at 2.7e5 here (the rounds' solves are short).
TEST(VarianceComponentsTest, FinalSolveStartsAtTheRadiusTheRoundsReached) {
  const Dataset dataset = WnoaDraw(1, 300, 0.01, 1e-4);
  SlamOptions options;
  options.prior = "wnoa";
  SlamResult result;
  std::string error;
  ASSERT_TRUE(RunSlam(dataset, options, &result, &error)) << error;
  ASSERT_TRUE(result.learned);
  ASSERT_FALSE(result.summary.iterations.empty());
  EXPECT_GT(result.summary.iterations.front().trust_region_radius,
            ceres::Solver::Options().initial_trust_region_radius);
  EXPECT_EQ(result.summary.termination_type, ceres::CONVERGENCE);
}

// The model of `options` about a constant mean, and the true landmarks
// moved by `offset`: a problem to build without solving the run first.
void ModelAboutAConstantMean(const Dataset& dataset, const SlamOptions& options,
                             std::unique_ptr<TrajectoryModel>* model) {
  std::string error;
  const std::shared_ptr<const MeanFunction> mean = BuildPriorMean(
      "constant", dataset, options.localization, kPaperSplineSmoothing, &error);
  ASSERT_NE(mean, nullptr) << error;
  *model = CreateTrajectoryModel(dataset, options, mean, &error);
  ASSERT_NE(*model, nullptr) << error;
}

// `sim` simulated; a failure is recorded where it cannot be.
Dataset Simulated(const SimulationOptions& sim) {
  Dataset dataset;
  std::string error;
  EXPECT_TRUE(Simulate(sim, &dataset, &error)) << error;
  return dataset;
}

// Default flags but the WNOA prior, whose learning rounds these tests watch.
SlamOptions WnoaDefaults() {
  SlamOptions options;
  options.prior = "wnoa";
  return options;
}

// The solve of `dataset` under `options`; a failure is recorded.
SlamResult Solved(const Dataset& dataset, const SlamOptions& options) {
  SlamResult result;
  std::string error;
  EXPECT_TRUE(RunSlam(dataset, options, &result, &error)) << error;
  return result;
}

// A short WNOA draw with its WNOA model about a constant mean.
struct WnoaDrawModel {
  WnoaDrawModel() {
    options.prior = "wnoa";
    ModelAboutAConstantMean(dataset, options, &model);
  }
  Dataset dataset = WnoaDraw(3, 40, 0.05, 0.01);
  SlamOptions options;
  std::unique_ptr<TrajectoryModel> model;
};

std::map<LandmarkId, Eigen::Vector2d> TrueLandmarks(
    const Dataset& dataset, const Eigen::Vector2d& offset) {
  std::map<LandmarkId, Eigen::Vector2d> landmarks;
  for (const Landmark& l : dataset.ground_truth_landmarks) {
    landmarks[l.id] = Eigen::Vector2d(l.x, l.y) + offset;
  }
  return landmarks;
}

// Sigmas stated 4x the noise drawn (a recording's guess): the noise scales
// learned with Q_c bring range and bearing back to the drawn ones, and the
// solve to the accuracy of the same data stated truthfully, whose scales
// stay near 1. Measured: loose 0.257 / 0.245 (seed 1), 0.241 / 0.257
// (seed 2), truthful within 4% of 1; the same APE both ways (0.029, 0.058 m).
TEST(VarianceComponentsTest, NoiseScalesFindSigmasStatedTooLoose) {
  for (const std::uint64_t seed : {1u, 2u}) {
    const Dataset truthful = WnoaDraw(seed, 300, 0.01, 1e-4);
    Dataset loose = truthful;
    for (Observation& o : loose.observations) {
      o.sigma_range *= 4.0;
      o.sigma_bearing *= 4.0;
    }
    SlamOptions options;
    options.prior = "wnoa";
    options.problem.loss = options.problem.odometry_loss = {"none", 1.0};
    double ape[2];
    NoiseScales noise[2];
    for (int k = 0; k < 2; ++k) {
      const Dataset& dataset = k == 0 ? truthful : loose;
      SlamResult result;
      std::string error;
      ASSERT_TRUE(RunSlam(dataset, options, &result, &error)) << error;
      EXPECT_TRUE(result.noise_kept.empty());
      EXPECT_TRUE(result.learning_converged);
      EXPECT_EQ(result.noise_learned,
                (std::vector<std::string>{"range", "bearing"}));
      Evaluation evaluation;
      ASSERT_TRUE(Evaluate(dataset.ground_truth, dataset.ground_truth_landmarks,
                           result.trajectory, nullptr, EvaluationOptions(),
                           &evaluation, &error));
      ape[k] = evaluation.ape_translation.rms;
      noise[k] = result.noise;
    }
    std::printf(
        "seed %llu: truthful range %.3f bearing %.3f, APE %.4f m; loose "
        "range %.3f bearing %.3f, APE %.4f m\n",
        static_cast<unsigned long long>(seed), noise[0].range, noise[0].bearing,
        ape[0], noise[1].range, noise[1].bearing, ape[1]);
    EXPECT_NEAR(noise[0].range, 1.0, 0.15);
    EXPECT_NEAR(noise[0].bearing, 1.0, 0.15);
    EXPECT_NEAR(noise[1].range, 0.25, 0.25 * 0.15);
    EXPECT_NEAR(noise[1].bearing, 0.25, 0.25 * 0.15);
    EXPECT_LT(ape[1], 1.05 * ape[0]);
  }
}

// The paper's simulation states its odometry sigmas truthfully, but its
// motion is no WNOA draw: as the odometry sigma falls the prior lets the
// trajectory follow the odometry ever closer, a weakly determined trade that
// the probes' noise in the odometry's redundancy walks downhill. The rounds
// climb the Laplace evidence, see it fall, and end at the scales before.
// Measured: odometry 0.697 and 0.502 (seeds 1 and 2) at the fourth round,
// Q_c started from the given value. From the odometry's, near the fixed
// point, the evidence falls at the first round already: the rounds keep
// the start's scales and the stated sigmas.
TEST(VarianceComponentsTest,
     OdometrySigmaRunningDownEndsWhereTheEvidenceFalls) {
  for (const std::uint64_t seed : {1u, 2u}) {
    SimulationOptions sim = PaperOptions(seed);
    sim.num_steps = 60;
    sim.num_landmarks = 10;
    const Dataset dataset = Simulated(sim);
    SlamOptions options = WnoaDefaults();
    const SlamResult started = Solved(dataset, options);
    EXPECT_TRUE(started.learning_evidence_fell);
    EXPECT_EQ(started.learning_rounds, 2);
    EXPECT_EQ(started.noise.odometry, 1.0);
    EXPECT_EQ(started.wnoa_options.position_qc,
              started.qc_from_odometry.position_qc);
    options.wnoa.qc_start = "given";
    const SlamResult result = Solved(dataset, options);
    std::printf("seed %llu: odometry %.3f after %d rounds\n",
                static_cast<unsigned long long>(seed), result.noise.odometry,
                result.learning_rounds);
    EXPECT_TRUE(result.learning_evidence_fell);
    EXPECT_FALSE(result.learning_converged);
    const std::vector<double>& evidence = result.scale_log_evidence;
    ASSERT_GE(evidence.size(), 3u);
    const std::size_t n = evidence.size();
    EXPECT_LT(evidence[n - 1], evidence[n - 2] - 1e-3);
    EXPECT_GT(evidence[n - 2], evidence[n - 3]);
    EXPECT_GT(result.noise.odometry, 0.4);
    EXPECT_LT(result.noise.odometry, 0.8);
    EXPECT_EQ(result.noise_learned,
              (std::vector<std::string>{"range", "bearing", "odometry"}));
    std::ostringstream summary;
    PrintSlamSummary(options, result, &summary);
    EXPECT_NE(summary.str().find(
                  "(ended at the round before the Laplace evidence fell)"),
              std::string::npos)
        << summary.str();
    // The RFF prior solves with (and reports) the scales of its WNOA mean.
    options.prior = "rff";
    EXPECT_EQ(Solved(dataset, options).noise.odometry, result.noise.odometry);
  }
}

// Sigmas stated ten times too tight make the default losses Cauchy's.
// The rounds then rescale loss-weighted squares, which do not climb the
// Gaussian rows' evidence, so no evidence is kept and none ends the rounds:
// the sigmas rise to the drawn ones. Measured: range 9.7, bearing 10.3
// after 9 rounds (5.2 and 5.6 when the rounds rescaled the loss-corrected
// squares, which fall short by kappa).
TEST(VarianceComponentsTest, RobustLossesLeaveTheRoundsToTheirFactors) {
  Dataset dataset = Simulated(PaperOptions(42));
  for (Observation& o : dataset.observations) {
    o.sigma_range *= 0.1;
    o.sigma_bearing *= 0.1;
  }
  const SlamResult result = Solved(dataset, WnoaDefaults());
  std::printf("range %.3f bearing %.3f after %d rounds, loss %s\n",
              result.noise.range, result.noise.bearing, result.learning_rounds,
              result.loss.c_str());
  EXPECT_EQ(result.loss, "cauchy");
  EXPECT_TRUE(result.scale_log_evidence.empty());
  EXPECT_FALSE(result.learning_evidence_fell);
  EXPECT_NEAR(result.noise.range, 10.0, 1.0);
  EXPECT_NEAR(result.noise.bearing, 10.0, 1.0);
}

// kappa in closed form: Cauchy's loss at a = 2 on two rows (|z|^2
// exponential of mean 2) gives E[s / (1 + s / 4)] / 2 = 2 - 4 e^2 E1(2);
// Huber's at a on one row of variance v gives P(|z| < a / sqrt v) =
// erf(a / sqrt(2 v)); no loss, 1.
TEST(VarianceComponentsTest, RobustConsistencyInClosedForm) {
  const double e1_of_2 = 0.04890051070806112;  // The exponential integral.
  EXPECT_NEAR(RobustConsistency(ceres::CauchyLoss(2.0), 2),
              2.0 - 4.0 * std::exp(2.0) * e1_of_2, 1e-9);
  EXPECT_NEAR(RobustConsistency(ceres::HuberLoss(1.0), 1),
              std::erf(1.0 / std::sqrt(2.0)), 1e-6);
  EXPECT_NEAR(RobustConsistency(ceres::TrivialLoss(), 3), 1.0, 1e-9);
  // Rows that keep a quarter of their variance: Huber's then reaches
  // a / sqrt(v) of the row's own sigma, and rows fitted almost exactly are
  // Gaussian's.
  EXPECT_NEAR(RobustConsistency(ceres::HuberLoss(1.0), 1, 0.25),
              std::erf(2.0 / std::sqrt(2.0)), 1e-6);
  EXPECT_NEAR(RobustConsistency(ceres::CauchyLoss(2.0), 3, 1e-6), 1.0, 1e-5);
}

// The paper's simulation states its sigmas truthfully; with Cauchy's loss
// put on every kind the rounds must still find them. Rescaling the
// loss-corrected squares they came to 0.57-0.63 (range, bearing; APE 0.59
// and 0.40 m); with the weighted squares over kappa 0.97-1.03 (APE 0.47
// and 0.26 m).
TEST(VarianceComponentsTest, RobustLossesLearnTruthfulSigmasAsStated) {
  for (const int seed : {1, 42}) {
    SlamOptions options = WnoaDefaults();
    options.problem.loss = options.problem.odometry_loss = {"cauchy", 2.0};
    const SlamResult result = Solved(Simulated(PaperOptions(seed)), options);
    std::printf("seed %d: range %.3f bearing %.3f odometry %.3f\n", seed,
                result.noise.range, result.noise.bearing,
                result.noise.odometry);
    EXPECT_NEAR(result.noise.range, 1.0, 0.1) << seed;
    EXPECT_NEAR(result.noise.bearing, 1.0, 0.1) << seed;
  }
}

// Noise-free data run every sigma down to its bound, where the product of
// the rounds' steps may land a rounding unit above it: a sigma there has
// stopped falling and is not named as unsettled. Seed 5's odometry landed
// at 0.0010000000000000002 (Q_c started from the given value: from the
// odometry's, the falls grow round after round and every sigma goes back to
// the stated one, NoiseFreeDataStopAtTheSigmaBound).
TEST(VarianceComponentsTest, ASigmaAtItsBoundIsNotUnsettled) {
  SimulationOptions sim = PaperOptions(5);
  sim.noise_free = true;
  SlamOptions options = WnoaDefaults();
  options.wnoa.qc_start = "given";
  const SlamResult result = Solved(Simulated(sim), options);
  EXPECT_NEAR(result.noise.odometry, 1e-3, 1e-15);
  EXPECT_EQ(result.learning_rounds, 12);
  EXPECT_TRUE(result.noise_unsettled.empty());
}

// A sigma still falling when the rounds reach their cap is named with the
// covariances (and in the JSON whatever was asked for).
TEST(VarianceComponentsTest, UnsettledSigmaIsNamedWithTheCovariances) {
  SlamOptions options;
  SlamResult result;
  result.noise.odometry = 0.02;
  result.noise_unsettled = {"odometry"};
  const std::string line =
      "  covariance   optimistic: the odometry sigma was still falling when "
      "the learning rounds reached their cap (0.02 of the stated one): the "
      "evidence keeps rewarding a closer fit of these rows, so the sigma, "
      "and the covariances that follow it, sit where the rounds stopped\n";
  for (const bool covariance : {false, true}) {
    options.output.covariance = covariance;
    std::ostringstream summary, json;
    PrintSlamSummary(options, result, &summary);
    EXPECT_EQ(summary.str().find(line) != std::string::npos, covariance)
        << summary.str();
    WriteSummaryJson(options, result, &json);
    EXPECT_NE(json.str().find("\"noise_unsettled\": [\"odometry\"],"),
              std::string::npos);
  }
}

// Odometry without noise beside noisy ranges and bearings: its rows fit
// ever closer as its sigma falls, faster each round, while the evidence
// climbs (the likelihood's degenerate edge). The sigma goes back to the
// stated one, and the evidence's fall after that jump ends nothing.
TEST(VarianceComponentsTest, OdometrySigmaRunningToZeroKeepsTheStatedOne) {
  SimulationOptions sim = PaperOptions(1);
  sim.num_steps = 60;
  sim.num_landmarks = 10;
  Dataset dataset = Simulated(sim);
  sim.noise_free = true;
  dataset.odometry = Simulated(sim).odometry;
  const SlamOptions options = WnoaDefaults();
  const SlamResult result = Solved(dataset, options);
  EXPECT_EQ(result.noise_kept, std::vector<std::string>{"odometry"});
  EXPECT_EQ(result.noise.odometry, 1.0);
  // A kept sigma is not reported as learned, nor printed as a factor.
  EXPECT_EQ(result.noise_learned,
            (std::vector<std::string>{"range", "bearing"}));
  std::ostringstream summary;
  PrintSlamSummary(options, result, &summary);
  EXPECT_NE(summary.str().find("odometry sigma kept as stated"),
            std::string::npos)
      << summary.str();
  EXPECT_EQ(summary.str().find("odometry 1\n"), std::string::npos)
      << summary.str();
}

// Ranges (r^2 / sigma_r^2), odometry the problem uses (per axis) and
// priors at offset o from the start (|o|^2 / sigma^2) count; bearings and
// the start's own prior do not.
TEST(ScaleInformationTest, SumsWhatScalingTheSceneMoves) {
  Dataset dataset;
  Observation bearing;
  bearing.type = ObservationType::kBearing;
  bearing.sigma_bearing = 0.01;
  dataset.observations = {bearing};
  dataset.pose_priors = {PosePrior{{5.0, 4.0, 1.0, 0.0}, 0.5, 0.1},
                         PosePrior{{0.0, 1.0, 1.0, 0.0}, 0.1, 0.1}};
  dataset.landmark_priors = {LandmarkPrior{7, 4.0, 5.0, 2.0}};
  ProblemOptions options;
  // The start is the earliest prior, at (1, 1): the later one is 3 m off,
  // the map prior 5 m.
  EXPECT_DOUBLE_EQ(ScaleInformation(dataset, options), 9.0 / 0.25 + 25.0 / 4.0);
  Observation range;
  range.type = ObservationType::kRangeBearing;
  range.range = 3.0;
  range.sigma_range = 0.5;
  dataset.observations.push_back(range);
  Odometry step;
  step.dx = 1.0;
  step.dy = 0.2;
  step.sigma_x = 0.1;
  step.sigma_y = 0.1;
  dataset.odometry = {step};
  EXPECT_DOUBLE_EQ(ScaleInformation(dataset, options),
                   36.0 + 6.25 + 36.0 + 100.0 + 4.0);
  options.use_odometry = false;
  EXPECT_DOUBLE_EQ(ScaleInformation(dataset, options), 36.0 + 6.25 + 36.0);
  // An estimated scale takes a sensor's information but for its prior:
  // ranges 36 / (1 + 36 * 0.01), odometry 104 / (1 + 104 * 0.25).
  options.use_odometry = true;
  options.range_calibration.estimate = true;
  options.range_calibration.scale_sigma = 0.1;
  options.odometry_calibration.estimate = true;
  options.odometry_calibration.scale_sigma = 0.5;
  EXPECT_DOUBLE_EQ(ScaleInformation(dataset, options),
                   36.0 + 6.25 + 36.0 / 1.36 + 104.0 / 27.0);
  // At noise factors f the sigmas are f times the stated ones.
  options = ProblemOptions();
  options.noise.range = 2.0;
  options.noise.odometry = 0.5;
  EXPECT_DOUBLE_EQ(ScaleInformation(dataset, options),
                   36.0 + 6.25 + 36.0 / 4.0 + 104.0 / 0.25);
  options = ProblemOptions();
  options.use_odometry = false;
  // Without pose priors the start is the map priors' weighted centroid.
  dataset.pose_priors.clear();
  dataset.landmark_priors.push_back(LandmarkPrior{8, 0.0, 2.0, 1.0});
  // Centroid (0.8, 2.6): offsets (3.2, 2.4) and (-0.8, -0.6).
  EXPECT_DOUBLE_EQ(ScaleInformation(dataset, options), 36.0 + 16.0 / 4.0 + 1.0);
}

// The size of the map about the start pose (at the origin) against the
// truth's: the ratio of the landmarks' RMS distances from it.
double MapSizeRatio(const SlamResult& result, const Dataset& dataset) {
  std::map<LandmarkId, Eigen::Vector2d> estimated;
  for (const Landmark& l : result.landmarks) estimated[l.id] = {l.x, l.y};
  double truth = 0.0, estimate = 0.0;
  for (const Landmark& l : dataset.ground_truth_landmarks) {
    truth += Eigen::Vector2d(l.x, l.y).squaredNorm();
    estimate += estimated.at(l.id).squaredNorm();
  }
  return std::sqrt(estimate / truth);
}

// Bearings without odometry do not measure the scene's size: with 10 map
// priors of 5 m the motion prior's pull sets it, and a learned Q_c fed on
// itself (a smaller Q_c, a smaller trajectory, smaller accelerations, a
// smaller Q_c): this run ended with a map 0.81 of the true size. Q_c stays
// as given and the bearings' factor is still learned. Map priors of 0.1 m
// hold the size: Q_c is learned there.
TEST(VarianceComponentsTest, BearingsAloneKeepTheGivenQcWhereTheSizeIsLoose) {
  SimulationOptions sim = PaperOptions(1);
  sim.kind = ObservationType::kBearing;
  sim.num_landmarks = 10;
  sim.odometry = false;
  const Dataset dataset = Simulated(sim);
  const SlamOptions options = WnoaDefaults();
  const SlamResult result = Solved(dataset, options);
  EXPECT_EQ(result.wnoa_options.position_qc, options.wnoa.position_qc);
  EXPECT_EQ(result.wnoa_options.heading_qc, options.wnoa.heading_qc);
  EXPECT_EQ(result.noise_learned, std::vector<std::string>{"bearing"});
  EXPECT_GT(MapSizeRatio(result, dataset), 0.9);
  std::ostringstream summary;
  PrintSlamSummary(options, result, &summary);
  EXPECT_NE(summary.str().find("Q_c kept as given: the data hold the "
                               "trajectory's size too loosely"),
            std::string::npos)
      << summary.str();
  std::ostringstream json;
  WriteSummaryJson(options, result, &json);
  EXPECT_NE(json.str().find("\"prior_scales_kept\": \"the data hold"),
            std::string::npos);

  // An RFF prior's rounds about such a mean learn no noise factors.
  SlamOptions rff = options;
  rff.prior = "rff";
  std::ostringstream rff_summary;
  PrintSlamSummary(rff, result, &rff_summary);
  EXPECT_NE(rff_summary.str().find("too loosely for a learned one ("),
            std::string::npos);
  EXPECT_EQ(rff_summary.str().find("noise factors"), std::string::npos)
      << rff_summary.str();

  // The RFF default starts from such a WNOA solve, and says so.
  const SlamResult rff_solved = Solved(dataset, SlamOptions());
  std::ostringstream rff_solved_summary;
  PrintSlamSummary(SlamOptions(), rff_solved, &rff_solved_summary);
  EXPECT_NE(rff_solved_summary.str().find(
                "initial trajectory from the wnoa; its Q_c kept as given: "
                "the data hold"),
            std::string::npos)
      << rff_solved_summary.str();

  sim.landmark_prior_sigma = 0.1;
  const SlamResult mapped = Solved(Simulated(sim), options);
  EXPECT_TRUE(mapped.prior_scales_kept.empty()) << mapped.prior_scales_kept;
  EXPECT_LT(mapped.wnoa_options.position_qc, 0.5 * options.wnoa.position_qc);
}

// An estimated odometry scale absorbs what the odometry says of the size,
// so bearings with odometry hold it no better than bearings alone: with Q_c
// learned this run ended with the odometry scale at 1.59 and the map 9.3 m
// off. Q_c goes back to the given value where the rounds end, and the
// scale and the map's size come out right.
TEST(VarianceComponentsTest, AnEstimatedOdometryScaleKeepsTheGivenQc) {
  SimulationOptions sim = PaperOptions(1);
  sim.kind = ObservationType::kBearing;
  sim.num_landmarks = 10;
  const Dataset dataset = Simulated(sim);
  SlamOptions options = WnoaDefaults();
  options.problem.odometry_calibration.estimate = true;
  const SlamResult result = Solved(dataset, options);
  EXPECT_EQ(result.wnoa_options.position_qc, options.wnoa.position_qc);
  EXPECT_NE(result.prior_scales_kept.find("too loosely for a learned one"),
            std::string::npos)
      << result.prior_scales_kept;
  EXPECT_NEAR(result.odometry_calibration.x(), 1.0, 0.02);
  EXPECT_NEAR(MapSizeRatio(result, dataset), 1.0, 0.03);
}

// With odometry the RFF weights correct a WNOA solve of the same data,
// which leaves them nothing to explain: their factors come out far under
// 0.01 (the likelihood peaks at zero variance). One round takes the tenfold
// step down and stops, where the rounds walked a step at a time until the
// data fixed under 10 of the weights. The answer is the WNOA solve's.
TEST(VarianceComponentsTest, CorrectionTheDataLeaveNoVarianceStopsAtZero) {
  for (const std::uint64_t seed : {1u, 2u}) {
    SimulationOptions sim = PaperOptions(seed);
    sim.num_steps = 300;
    Dataset dataset;
    std::string error;
    ASSERT_TRUE(Simulate(sim, &dataset, &error)) << error;
    SlamOptions options;
    options.prior = "rff";
    SlamResult rff;
    ASSERT_TRUE(RunSlam(dataset, options, &rff, &error)) << error;
    ASSERT_EQ(rff.prior_mean, "wnoa");
    EXPECT_EQ(rff.scales_at_boundary,
              (std::vector<std::string>{"trajectory position",
                                        "trajectory heading"}));
    EXPECT_EQ(rff.learning_rounds, 1);
    EXPECT_TRUE(rff.learning_converged);
    EXPECT_LT(rff.prior_scale_factors.maxCoeff(), 0.01);
    // A tenfold step down from the variance the capacity rule starts at.
    const FeatureTrajectoryOptions start;
    EXPECT_DOUBLE_EQ(rff.trajectory_options.position_kernel.variance,
                     std::pow(2.0 * start.capacity_position_sigma, 2) / 10.0);
    EXPECT_DOUBLE_EQ(rff.trajectory_options.heading_kernel.variance,
                     std::pow(2.0 * start.capacity_heading_sigma, 2) / 10.0);
    std::ostringstream summary;
    PrintSlamSummary(options, rff, &summary);
    EXPECT_NE(summary.str().find("1 round; at zero, the data leave no "
                                 "variance to: trajectory position, "
                                 "trajectory heading\n"),
              std::string::npos)
        << summary.str();
    options.prior = "wnoa";
    SlamResult wnoa;
    ASSERT_TRUE(RunSlam(dataset, options, &wnoa, &error)) << error;
    const double largest = testing::LargestPositionDifference(rff, wnoa);
    // Its summary's Q_c is the one its WNOA mean learned.
    EXPECT_EQ(rff.wnoa_options.position_qc, wnoa.wnoa_options.position_qc);
    EXPECT_EQ(rff.wnoa_options.heading_qc, wnoa.wnoa_options.heading_qc);
    EXPECT_NE(rff.wnoa_options.position_qc, WnoaOptions().position_qc);
    std::printf("seed %llu: factors %.3g %.3g, RFF - WNOA at most %.3g m\n",
                static_cast<unsigned long long>(seed),
                rff.prior_scale_factors[0], rff.prior_scale_factors[1],
                largest);
    EXPECT_LT(largest, 1e-3);
  }
}

// Noise-free data fit ever closer as their sigmas fall. With Q_c started
// from the odometry's the falls are the rounds' largest step from the
// first round on, so every sigma goes back to the stated one and the
// summary says it ran towards 0. From the given Q_c the steps vary while
// Q_c settles: the sigmas stop at 1/1000 of the stated ones (the system
// keeps its digits), and the learning says it did not converge.
TEST(VarianceComponentsTest, NoiseFreeDataStopAtTheSigmaBound) {
  SimulationOptions sim = PaperOptions(3);
  sim.num_steps = 60;
  sim.num_landmarks = 10;
  sim.noise_free = true;
  const Dataset dataset = Simulated(sim);
  SlamOptions options = WnoaDefaults();
  const SlamResult started = Solved(dataset, options);
  EXPECT_EQ(started.noise_kept,
            (std::vector<std::string>{"range", "bearing", "odometry"}));
  EXPECT_EQ(started.noise.range, 1.0);
  EXPECT_EQ(started.noise.bearing, 1.0);
  EXPECT_EQ(started.noise.odometry, 1.0);
  options.wnoa.qc_start = "given";
  const SlamResult result = Solved(dataset, options);
  EXPECT_DOUBLE_EQ(result.noise.range, 1e-3);
  EXPECT_DOUBLE_EQ(result.noise.bearing, 1e-3);
  EXPECT_FALSE(result.learning_converged);
  EXPECT_EQ(result.learning_rounds, 12);
}

// The problem of `dataset` under `options` about a constant mean (its model
// in `model`), built at the true landmarks moved by (0.3, -0.2); null, with
// a failure recorded, where it cannot be built.
std::unique_ptr<SlamProblem> ProblemAtShiftedLandmarks(
    const Dataset& dataset, const SlamOptions& options,
    std::unique_ptr<TrajectoryModel>* model) {
  ModelAboutAConstantMean(dataset, options, model);
  if (*model == nullptr) {
    ADD_FAILURE() << "no model";
    return nullptr;
  }
  auto problem = std::make_unique<SlamProblem>(model->get(), options.problem);
  std::string error;
  if (!problem->Build(dataset,
                      TrueLandmarks(dataset, Eigen::Vector2d(0.3, -0.2)),
                      &error)) {
    ADD_FAILURE() << error;
    return nullptr;
  }
  return problem;
}

// The problem solves with the noise-scaled sigmas; its residuals at the
// stated ones (what the quality verdict judges) are those times the scale of
// each row's kind, and every other kind's are unchanged.
TEST(VarianceComponentsTest, ResidualsAtTheStatedSigmasUndoTheNoiseScales) {
  const Dataset dataset = WnoaDraw(3, 40, 0.05, 0.01);
  SlamOptions options;
  options.prior = "wnoa";
  options.problem.noise.range = 0.5;
  options.problem.noise.bearing = 4.0;
  std::unique_ptr<TrajectoryModel> model;
  const std::unique_ptr<SlamProblem> problem =
      ProblemAtShiftedLandmarks(dataset, options, &model);
  ASSERT_NE(problem, nullptr);
  const auto scaled = problem->WhitenedResidualsByKind();
  const auto stated = problem->WhitenedResidualsByKind(/*stated_sigmas=*/true);
  ASSERT_EQ(scaled.size(), stated.size());
  for (const auto& [kind, rows] : scaled) {
    const std::vector<double>& at_stated = stated.at(kind);
    ASSERT_EQ(rows.size(), at_stated.size()) << kind;
    for (std::size_t r = 0; r < rows.size(); ++r) {
      const double factor =
          kind == "range-bearing" ? (r % 2 == 0 ? 0.5 : 4.0) : 1.0;
      EXPECT_DOUBLE_EQ(at_stated[r], factor * rows[r]) << kind << " " << r;
    }
  }
  EXPECT_GT(scaled.at("range-bearing").size(), 0u);
}

// Each landmark's series (residual_drift.h) holds its range-bearing rows,
// the range and the bearing values apart, in time order, whatever order
// the data came in: here reversed, as the blocks are added.
TEST(VarianceComponentsTest, ObservationSeriesAreEachLandmarksRowsInTimeOrder) {
  Dataset dataset = WnoaDraw(3, 40, 0.05, 0.01);
  std::reverse(dataset.observations.begin(), dataset.observations.end());
  SlamOptions options;
  options.prior = "wnoa";
  std::unique_ptr<TrajectoryModel> model;
  const std::unique_ptr<SlamProblem> problem =
      ProblemAtShiftedLandmarks(dataset, options, &model);
  ASSERT_NE(problem, nullptr);
  // Rows in the order the blocks were added: two per observation.
  const std::vector<double> rows =
      problem->WhitenedResidualsByKind().at("range-bearing");
  ASSERT_EQ(rows.size(), 2 * dataset.observations.size());
  std::map<LandmarkId, std::vector<std::pair<double, int>>> sightings;
  for (std::size_t i = 0; i < dataset.observations.size(); ++i) {
    const Observation& o = dataset.observations[i];
    sightings[o.id].emplace_back(o.t, static_cast<int>(i));
  }
  const auto series = problem->ObservationResidualSeries();
  const auto& ranges = series.at(VarianceGroup::kRange);
  const auto& bearings = series.at(VarianceGroup::kBearing);
  ASSERT_EQ(ranges.size(), sightings.size());
  for (auto& [id, seen] : sightings) {
    std::sort(seen.begin(), seen.end());
    ASSERT_EQ(ranges.at(id).size(), seen.size()) << id;
    ASSERT_EQ(bearings.at(id).size(), seen.size()) << id;
    for (std::size_t k = 0; k < seen.size(); ++k) {
      EXPECT_EQ(ranges.at(id)[k], rows[2 * seen[k].second]) << id << " " << k;
      EXPECT_EQ(bearings.at(id)[k], rows[2 * seen[k].second + 1])
          << id << " " << k;
    }
  }
}

// The Hutchinson redundancies match the exact traces of H^-1 J_g^T J_g
// (dense inverse) on a small problem, and the factors are r^T r / redundancy.
void ExpectRedundanciesMatchTheExactTraces(const SlamOptions& given) {
  const Dataset dataset = WnoaDraw(3, 40, 0.05, 0.01);
  SlamOptions options = given;
  std::unique_ptr<TrajectoryModel> model;
  ModelAboutAConstantMean(dataset, options, &model);
  ASSERT_NE(model, nullptr);
  const std::map<LandmarkId, Eigen::Vector2d> landmarks =
      TrueLandmarks(dataset, Eigen::Vector2d::Zero());
  std::string error;
  options.problem.loss = options.problem.odometry_loss = {"none", 1.0};
  SlamProblem problem(model.get(), options.problem);
  ASSERT_TRUE(problem.Build(dataset, landmarks, &error)) << error;
  ceres::Solver::Options solver;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, problem.problem(), &summary);

  VarianceComponentOptions vc;
  vc.probes = 20000;
  VarianceComponents components;
  ASSERT_TRUE(EstimateVarianceComponents(&problem, vc, &components, &error))
      << error;

  std::vector<ceres::ResidualBlockId> ids;
  problem.problem()->GetResidualBlocks(&ids);
  double cost = 0.0;
  Eigen::VectorXd residuals;
  Eigen::SparseMatrix<double, Eigen::RowMajor> sparse;
  ASSERT_TRUE(
      Linearize(problem.problem(), ids, &cost, &residuals, &sparse, &error));
  const Eigen::MatrixXd j = sparse;
  const Eigen::MatrixXd h_inverse = (j.transpose() * j).inverse();
  const double log_det =
      (j.transpose() * j).ldlt().vectorD().array().log().sum();
  EXPECT_NEAR(components.log_det_hessian, log_det, 1e-9 * std::abs(log_det));
  const std::vector<VarianceGroup> groups = problem.RowGroups(ids);
  for (const VarianceGroup group :
       {VarianceGroup::kRange, VarianceGroup::kBearing,
        VarianceGroup::kPriorPosition, VarianceGroup::kPriorHeading}) {
    double trace = 0.0, sum_squares = 0.0;
    int rows = 0;
    for (Eigen::Index r = 0; r < j.rows(); ++r) {
      if (groups[r] != group) continue;
      ++rows;
      trace += j.row(r) * h_inverse * j.row(r).transpose();
      sum_squares += residuals[r] * residuals[r];
    }
    const VarianceComponent& c = components[static_cast<int>(group)];
    EXPECT_EQ(c.rows, rows) << VarianceGroupName(group);
    EXPECT_NEAR(c.sum_squares, sum_squares, 1e-9 * sum_squares);
    EXPECT_NEAR(c.redundancy, rows - trace, 0.03 * (rows - trace))
        << VarianceGroupName(group);
    // A group with too little redundancy keeps its scale.
    EXPECT_DOUBLE_EQ(c.factor, c.redundancy >= vc.min_redundancy
                                   ? c.sum_squares / c.redundancy
                                   : 1.0);
  }
  // The start's priors are not rescaled.
  EXPECT_EQ(components[static_cast<int>(VarianceGroup::kFixed)].factor, 1.0);
}

// On twenty draws from the WNOA prior itself (its own model), the default
// solve (Q_c and the noise scales learned) gives pose covariances whose
// pooled mean position NEES is within 10% of 2. The map is known (priors
// 0.01 m), so each run's errors are local and the pooled mean pins the
// consistency, not one frame's draw.
TEST(VarianceComponentsTest, WnoaCovarianceIsConsistentOnItsOwnDraws) {
  double nees_sum = 0.0;
  int runs = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const Dataset dataset = WnoaDraw(seed, 150, 0.01, 1e-4);
    SlamResult result;
    const double nees = testing::SolvedPositionNees(dataset, "wnoa", &result);
    std::printf("seed %llu: position NEES %.3f\n",
                static_cast<unsigned long long>(seed), nees);
    nees_sum += nees;
    ++runs;
  }
  const double pooled = nees_sum / runs;
  std::printf("pooled mean position NEES %.3f over %d draws\n", pooled, runs);
  EXPECT_NEAR(pooled, 2.0, 0.2);
}

// The evidence with each prior's normaliser (model_log_evidence) names the
// prior a draw came from: on WNOA draws WNOA's is the higher (WNOJ's own
// draws: WnojTrajectoryTest.SolvesItsOwnDrawsBetterThanWnoa). Measured:
// 50 and 65 nats (seeds 1, 2); seeds 3-8, after: 38-65. The normalisers
// matter: on the paper's s3 bearing set with odometry they differ by 2951
// nats, the evidences with them by 248.
TEST(VarianceComponentsTest, ModelEvidencePrefersThePriorOfTheDraw) {
  for (std::uint64_t seed = 1; seed <= 2; ++seed) {
    const Dataset dataset = WnoaDraw(seed, 60, 0.01, 1e-4);
    double evidence[2];
    for (const int k : {0, 1}) {
      SlamOptions options;
      options.prior = k == 0 ? "wnoa" : "wnoj";
      evidence[k] = Solved(dataset, options).model_log_evidence;
    }
    std::printf("seed %llu: log evidence WNOA %.1f WNOJ %.1f\n",
                static_cast<unsigned long long>(seed), evidence[0],
                evidence[1]);
    EXPECT_GT(evidence[0], evidence[1]);
  }
}

// WNOA states: the probes go through the time-ordered envelope, J z term by
// term (BandedProblem::RowProducts).
TEST(VarianceComponentsTest, RedundanciesMatchTheExactTracesWnoa) {
  SlamOptions options;
  options.prior = "wnoa";
  ExpectRedundanciesMatchTheExactTraces(options);
}

// A cache hands the next call the probes its seed draws: the same
// components as without one, call after call; another seed draws anew.
TEST(VarianceComponentsTest, CacheKeepsTheProbesOfItsSeed) {
  const WnoaDrawModel draw;
  ASSERT_NE(draw.model, nullptr);
  std::string error;
  SlamProblem problem(draw.model.get(), draw.options.problem);
  ASSERT_TRUE(problem.Build(draw.dataset,
                            TrueLandmarks(draw.dataset, {0.0, 0.0}), &error))
      << error;
  ceres::Solver::Options solver;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, problem.problem(), &summary);

  auto estimate = [&](unsigned seed, VarianceComponentCache* cache) {
    VarianceComponentOptions vc;
    vc.seed = seed;
    VarianceComponents components;
    EXPECT_TRUE(
        EstimateVarianceComponents(&problem, vc, &components, &error, cache))
        << error;
    std::vector<double> redundancies;
    for (const VarianceComponent& c : components) {
      redundancies.push_back(c.redundancy);
    }
    return redundancies;
  };
  const std::vector<double> seed_1 = estimate(1, nullptr);
  const std::vector<double> seed_2 = estimate(2, nullptr);
  EXPECT_NE(seed_1, seed_2);
  VarianceComponentCache cache;
  EXPECT_EQ(estimate(1, &cache), seed_1);
  EXPECT_EQ(cache.columns, problem.problem()->NumParameters());
  EXPECT_EQ(cache.signs.size(),
            static_cast<std::size_t>(cache.columns) * cache.probes);
  EXPECT_EQ(estimate(1, &cache), seed_1);
  EXPECT_EQ(estimate(2, &cache), seed_2);
  EXPECT_EQ(cache.seed, 2u);
}

// The banded path's per-row residuals and probe products are those of the
// problem's own Jacobian (Ceres's, through the Cauchy loss's correction),
// its columns in the envelope's time order.
TEST(VarianceComponentsTest, BandedRowProductsAreThoseOfTheJacobian) {
  WnoaDrawModel draw;
  ASSERT_NE(draw.model, nullptr);
  const Dataset& dataset = draw.dataset;
  SlamOptions& options = draw.options;
  const std::unique_ptr<TrajectoryModel>& model = draw.model;
  std::map<LandmarkId, Eigen::Vector2d> landmarks =
      TrueLandmarks(dataset, Eigen::Vector2d::Zero());
  for (auto& [id, position] : landmarks) position += Eigen::Vector2d(0.3, -0.2);
  std::string error;
  options.problem.loss = {"cauchy", 0.5};  // Outliers: the clamped branch.
  SlamProblem problem(model.get(), options.problem);
  ASSERT_TRUE(problem.Build(dataset, landmarks, &error)) << error;

  std::vector<ceres::ResidualBlockId> ids;
  problem.problem()->GetResidualBlocks(&ids);
  int num_leading = 0;
  const std::vector<double*> columns = LandmarksLast(&problem, &num_leading);
  double cost = 0.0;
  Eigen::VectorXd residuals;
  Eigen::SparseMatrix<double, Eigen::RowMajor> sparse;
  ASSERT_TRUE(Linearize(problem.problem(), ids, &cost, &residuals, &sparse,
                        &error, columns));
  const Eigen::MatrixXd j = sparse;
  const std::vector<int> position = TimeOrderPositions(&problem, columns);
  ASSERT_EQ(position.size(), static_cast<std::size_t>(j.cols()));

  BandedProblem banded(*problem.problem(), problem.BandColumns());
  ASSERT_EQ(banded.num_columns(), j.cols());
  ASSERT_EQ(banded.num_rows(), j.rows());
  std::mt19937 engine(7);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd z(j.cols(), 3), u(j.cols(), 3);
  for (Eigen::Index i = 0; i < z.size(); ++i) {
    z.data()[i] = normal(engine);
    u.data()[i] = normal(engine);
  }
  EnvelopeMatrix::RowMajorMatrix z_banded(j.cols(), 3), u_banded(j.cols(), 3);
  for (Eigen::Index c = 0; c < j.cols(); ++c) {
    z_banded.row(position[c]) = z.row(c);
    u_banded.row(position[c]) = u.row(c);
  }
  Eigen::VectorXd banded_residuals, products;
  ASSERT_TRUE(banded.RowProducts(banded.Gather(), z_banded, u_banded,
                                 &banded_residuals, &products));
  const Eigen::MatrixXd jz = j * z, ju = j * u;
  int outliers = 0;
  for (Eigen::Index r = 0; r < j.rows(); ++r) {
    EXPECT_NEAR(banded_residuals[r], residuals[r], 1e-12) << "row " << r;
    const double expected = jz.row(r).dot(ju.row(r));
    EXPECT_NEAR(products[r], expected, 1e-10 * (1.0 + std::abs(expected)))
        << "row " << r;
    outliers += std::abs(residuals[r]) > 0.5;
  }
  EXPECT_GT(outliers, 10);  // The correction was exercised.
}

// The Laplace log evidence of `dataset` solved at the scales of `options`
// (the map at the truth, no losses), with its variance components.
double EvidenceAt(const Dataset& dataset, SlamOptions options,
                  VarianceComponents* components) {
  std::unique_ptr<TrajectoryModel> model;
  ModelAboutAConstantMean(dataset, options, &model);
  if (model == nullptr) return 0.0;
  SlamProblem problem(model.get(), options.problem);
  std::string error;
  EXPECT_TRUE(
      problem.Build(dataset, TrueLandmarks(dataset, {0.0, 0.0}), &error))
      << error;
  ceres::Solver::Options solver;
  solver.function_tolerance = solver.gradient_tolerance =
      solver.parameter_tolerance = 1e-14;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, problem.problem(), &summary);
  VarianceComponentOptions vc;
  vc.probes = 4000;
  vc.min_redundancy = 1.0;  // Every group estimated, however few its data.
  EXPECT_TRUE(EstimateVarianceComponents(&problem, vc, components, &error))
      << error;
  const TrajectoryPrior& prior = PriorOf(options);
  return LaplaceLogEvidence(
      *components,
      LogRowScales(*model, *prior.PositionScale(&options),
                   *prior.HeadingScale(&options), options.problem.noise));
}

// The variance components' fixed point is where the Laplace evidence
// peaks: from the scales at which every factor is 1, each scale moved by
// 30% either way gives a lower evidence. This holds only with the right
// normalisers (n log s for rows a scale divides, none for feature weights).
void ExpectEvidencePeaksAtTheFixedPoint(SlamOptions options) {
  const Dataset dataset = WnoaDraw(3, 40, 0.05, 0.01);
  options.problem.loss = options.problem.odometry_loss = {"none", 1.0};
  const TrajectoryPrior& prior = PriorOf(options);
  NoiseScales& noise = options.problem.noise;
  // The scales of the groups estimated (the prior's and the sigmas').
  const std::vector<std::pair<VarianceGroup, double*>> scales = {
      {VarianceGroup::kPriorPosition, prior.PositionScale(&options)},
      {VarianceGroup::kPriorHeading, prior.HeadingScale(&options)},
      {VarianceGroup::kRange, &noise.range},
      {VarianceGroup::kBearing, &noise.bearing}};
  VarianceComponents components;
  double largest = 1.0;
  for (int round = 0; round < 60 && largest > 1e-4; ++round) {
    EvidenceAt(dataset, options, &components);
    largest = 0.0;
    for (const auto& [group, scale] : scales) {
      const double factor = components[static_cast<int>(group)].factor;
      ASSERT_TRUE(components[static_cast<int>(group)].estimated)
          << VarianceGroupName(group) << " redundancy "
          << components[static_cast<int>(group)].redundancy;
      // Sigmas take the square root of their variance factor.
      *scale *= group == VarianceGroup::kPriorPosition ||
                        group == VarianceGroup::kPriorHeading
                    ? factor
                    : std::sqrt(factor);
      largest = std::max(largest, std::abs(std::log(factor)));
    }
  }
  ASSERT_LT(largest, 1e-4);
  const double peak = EvidenceAt(dataset, options, &components);
  for (const auto& [group, scale] : scales) {
    const double at_peak = *scale;
    for (const double move : {0.7, 1.0 / 0.7}) {
      *scale = at_peak * move;
      EXPECT_LT(EvidenceAt(dataset, options, &components), peak - 0.05)
          << VarianceGroupName(group) << " times " << move;
    }
    *scale = at_peak;
  }
}

TEST(VarianceComponentsTest, EvidencePeaksAtTheFixedPointWnoa) {
  SlamOptions options;
  options.prior = "wnoa";
  ExpectEvidencePeaksAtTheFixedPoint(options);
}

// The RFF prior as one global feature map of 20 weights per coordinate.
SlamOptions OneGlobalFeatureMap() {
  SlamOptions options;
  options.prior = "rff";
  options.features.num_position_features = 20;
  options.features.num_heading_features = 20;
  options.features.segment_length = 0.0;
  return options;
}

TEST(VarianceComponentsTest, EvidencePeaksAtTheFixedPointRff) {
  ExpectEvidencePeaksAtTheFixedPoint(OneGlobalFeatureMap());
}

// One global feature map: every row is dense over the 3 x 20 weights, so
// A = J_t^T J_t by dense products.
TEST(VarianceComponentsTest, RedundanciesMatchTheExactTracesRffDenseRows) {
  ExpectRedundanciesMatchTheExactTraces(OneGlobalFeatureMap());
}

}  // namespace
}  // namespace rff
