#include "rff_ceres/posterior_covariance.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <string>

#include "Eigen/Dense"
#include "ceres/crs_matrix.h"
#include "costs/weight_prior_cost.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "rff_ceres/banded_problem.h"
#include "rff_ceres/ceres_solve.h"
#include "rff_ceres/consistency.h"
#include "rff_ceres/feature_trajectory.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/metrics.h"
#include "rff_ceres/simulate.h"
#include "rff_ceres/slam_report.h"
#include "rff_ceres/slam_solver.h"
#include "rff_ceres/wnoa_trajectory.h"
#include "test/shared_data.h"
#include "test/synthetic_options.h"

namespace rff {
namespace {

using ::testing::HasSubstr;

// x(t), y(t), theta(t) = b_c^T (1, t) with b_c ~ N(0, I): a linear-Gaussian
// model whose posterior has a closed form.
class LineTrajectory : public TrajectoryModel {
 public:
  LineTrajectory()
      : mean_(std::make_shared<PiecewiseLinearMean>(
            std::vector<TimedPose>{{0.0, 0.0, 0.0, 0.0}})),
        weights_(3, Eigen::VectorXd::Zero(2)) {}

  int num_blocks() const override { return 3; }
  int block_size(int /*block*/) const override { return 2; }
  double* mutable_block(int block) override { return weights_[block].data(); }
  PoseMap PoseAt(double t) const override {
    PoseMap map;
    auto phi = std::make_shared<Eigen::VectorXd>(2);
    *phi << 1.0, t;
    for (int c = 0; c < 3; ++c) map.terms.push_back({c, c, phi});
    return map;
  }
  void AddPriorCosts(ceres::Problem* problem, int begin, int end) override {
    for (int b = begin; b < end; ++b) {
      problem->AddResidualBlock(new WeightPriorCost(2), nullptr,
                                mutable_block(b));
    }
  }
  const MeanFunction& mean() const override { return *mean_; }
  void set_mean(std::shared_ptr<const MeanFunction> mean) override {
    mean_ = std::move(mean);
  }
  std::vector<PriorScale> PriorRowScales(const std::vector<double*>& blocks,
                                         int num_rows) const override {
    return std::vector<PriorScale>(num_rows, blocks.front() == block(2)
                                                 ? PriorScale::kHeading
                                                 : PriorScale::kPosition);
  }
  bool PriorScalesWhitenRows() const override { return false; }

 private:
  std::shared_ptr<const MeanFunction> mean_;
  std::vector<Eigen::VectorXd> weights_;
};

PosePrior PriorAt(double t, double sigma_xy, double sigma_theta) {
  PosePrior p;
  p.pose.t = t;
  p.sigma_xy = sigma_xy;
  p.sigma_theta = sigma_theta;
  return p;
}

// ceres::Covariance with `algorithm`, never the envelope, the Schur form or
// the selected inverse.
CovarianceOptions WithAlgorithm(ceres::CovarianceAlgorithmType algorithm) {
  CovarianceOptions options;
  options.use_envelope = false;
  options.use_schur = false;
  options.use_selected_inverse = false;
  options.algorithm = algorithm;
  options.num_threads = 1;
  return options;
}

class LinearGaussianTest
    : public ::testing::TestWithParam<ceres::CovarianceAlgorithmType> {};

// Direct pose observations at t = 0 and 1: Sigma_b = (I + H^T R^-1 H)^-1
// with H = [1 0; 1 1]. sigma 1: Sigma = [2 -1; -1 3] / 5, so
// Var x(t) = (2 - 2 t + 3 t^2) / 5; sigma 0.5: Sigma = [5 -4; -4 9] / 29,
// Var theta(t) = (5 - 8 t + 9 t^2) / 29. A landmark with only its prior of
// sigma 2 keeps the covariance 4 I.
TEST_P(LinearGaussianTest, MatchesTheClosedForm) {
  LineTrajectory model;
  SlamProblem problem(&model, ProblemOptions());
  Dataset dataset;
  dataset.pose_priors = {PriorAt(0.0, 1.0, 0.5), PriorAt(1.0, 1.0, 0.5)};
  dataset.landmark_priors = {{3, 1.0, 2.0, 2.0}};
  std::string error;
  ASSERT_TRUE(problem.Build(dataset, {{3, Eigen::Vector2d(1.0, 2.0)}}, &error))
      << error;
  std::vector<Landmark> landmarks(1);
  landmarks[0].id = 3;
  std::vector<Eigen::Matrix3d> covariances;
  ASSERT_TRUE(ComputePosteriorCovariance(&problem, model, {0.5, 2.0},
                                         WithAlgorithm(GetParam()),
                                         &covariances, &landmarks, &error))
      << error;
  ASSERT_EQ(covariances.size(), 2u);
  Eigen::Matrix3d expected = Eigen::Matrix3d::Zero();
  expected.diagonal() << 0.35, 0.35, 3.25 / 29.0;
  EXPECT_LT((covariances[0] - expected).cwiseAbs().maxCoeff(), 1e-12)
      << covariances[0];
  expected.diagonal() << 2.0, 2.0, 25.0 / 29.0;
  EXPECT_LT((covariances[1] - expected).cwiseAbs().maxCoeff(), 1e-12)
      << covariances[1];
  ASSERT_TRUE(landmarks[0].has_covariance);
  EXPECT_NEAR(landmarks[0].sxx, 4.0, 1e-12);
  EXPECT_NEAR(landmarks[0].sxy, 0.0, 1e-12);
  EXPECT_NEAR(landmarks[0].syy, 4.0, 1e-12);
}

INSTANTIATE_TEST_SUITE_P(
    Algorithms, LinearGaussianTest,
    ::testing::Values(ceres::SPARSE_QR, ceres::DENSE_SVD),
    [](const auto& info) {
      return std::string(ceres::CovarianceAlgorithmTypeToString(info.param));
    });

// Landmark 5 has one range and no prior: the data leave it free. Landmark 7
// has a prior and a bearing seen from 1e-9 m, whose information dwarfs the
// prior's by 22 decades: its block looks singular, but it is not blamed.
TEST(PosteriorCovarianceTest, SingleRangeLeavesALandmarkUnconstrained) {
  LineTrajectory model;
  SlamProblem problem(&model, ProblemOptions());
  Dataset dataset;
  dataset.pose_priors = {PriorAt(0.0, 1.0, 0.5), PriorAt(1.0, 1.0, 0.5)};
  dataset.landmark_priors = {{7, 0.0, 0.0, 1.0}};
  Observation range;
  range.t = 0.5;
  range.id = 5;
  range.range = 3.0;
  range.sigma_range = 0.1;
  Observation bearing;
  bearing.type = ObservationType::kBearing;
  bearing.t = 0.5;
  bearing.id = 7;
  bearing.sigma_bearing = 0.01;
  dataset.observations = {range, bearing};
  std::string error;
  ASSERT_TRUE(problem.Build(
      dataset,
      {{5, Eigen::Vector2d(3.0, 0.0)}, {7, Eigen::Vector2d(1e-9, 0.0)}},
      &error))
      << error;
  std::vector<Landmark> landmarks(2);
  landmarks[0].id = 5;
  landmarks[1].id = 7;
  // The default tries the Schur form and the selected inverse first:
  // landmark 5's block is singular, so SuiteSparseQR decides, with the same
  // message.
  for (const CovarianceOptions& options :
       {WithAlgorithm(ceres::SPARSE_QR), WithAlgorithm(ceres::DENSE_SVD),
        CovarianceOptions()}) {
    std::vector<Eigen::Matrix3d> covariances;
    EXPECT_FALSE(ComputePosteriorCovariance(&problem, model, {0.5}, options,
                                            &covariances, &landmarks, &error));
    EXPECT_THAT(error,
                HasSubstr("the information matrix J^T J is singular; the "
                          "data do not fix the position of landmark 5 ("));
    EXPECT_FALSE(landmarks[0].has_covariance);
  }
}

TEST(PosteriorCovarianceTest, UnknownLandmarkIsAnError) {
  LineTrajectory model;
  SlamProblem problem(&model, ProblemOptions());
  Dataset dataset;
  dataset.pose_priors = {PriorAt(0.0, 1.0, 0.5)};
  std::string error;
  ASSERT_TRUE(problem.Build(dataset, {}, &error)) << error;
  std::vector<Landmark> landmarks(1);
  landmarks[0].id = 4;
  std::vector<Eigen::Matrix3d> covariances;
  EXPECT_FALSE(ComputePosteriorCovariance(&problem, model, {0.0}, &covariances,
                                          &landmarks, &error));
  EXPECT_EQ(error, "posterior covariance: landmark 4 is not in the problem");
}

// A simulated run of `steps` seconds, RBF features of `features` a
// coordinate (x and y; theta `heading_features`) in windows of `segment`
// s blended over `overlap` s, and its problem with the landmarks started
// 0.36 m off.
struct WindowedRun {
  Dataset dataset;
  std::unique_ptr<FeatureTrajectory> model;
  std::vector<Landmark> landmarks;
  std::unique_ptr<SlamProblem> problem;
};
void BuildWindowedRun(int steps, int features, int heading_features,
                      double segment, double overlap, WindowedRun* run) {
  SimulationOptions sim = PaperOptions(5);
  sim.num_steps = steps;
  sim.num_landmarks = 12;
  std::string error;
  ASSERT_TRUE(Simulate(sim, &run->dataset, &error)) << error;
  FeatureTrajectoryOptions options;
  options.position_kernel.name = "rbf";
  options.position_kernel.lengthscale = 5.0;
  options.position_kernel.variance = 100.0;
  options.heading_kernel = options.position_kernel;
  options.heading_kernel.variance = 0.25;
  options.num_position_features = features;
  options.num_heading_features = heading_features;
  options.segment_length = segment;
  options.segment_overlap = overlap;
  run->model = FeatureTrajectory::Create(
      options, std::make_shared<PiecewiseLinearMean>(run->dataset.ground_truth),
      0.0, steps - 1.0, &error);
  ASSERT_NE(run->model, nullptr) << error;
  std::map<LandmarkId, Eigen::Vector2d> initial;
  for (const Landmark& l : run->dataset.ground_truth_landmarks) {
    initial[l.id] = Eigen::Vector2d(l.x + 0.3, l.y - 0.2);
    run->landmarks.push_back(l);
  }
  run->problem =
      std::make_unique<SlamProblem>(run->model.get(), ProblemOptions());
  ASSERT_TRUE(run->problem->Build(run->dataset, initial, &error)) << error;
}

// Windowed features (poses in two segments at the overlaps), range-bearing
// observations and odometry: the block-pair assembly against the dense
// inverse of J^T J over all parameters.
TEST(PosteriorCovarianceTest, MatchesTheDenseInverseWithWindowedWeights) {
  WindowedRun run;
  ASSERT_NO_FATAL_FAILURE(BuildWindowedRun(60, 8, 6, 20.0, 6.0, &run));
  FeatureTrajectory* model = run.model.get();
  ASSERT_EQ(model->num_segments(), 3);
  std::vector<Landmark>& landmarks = run.landmarks;
  SlamProblem& problem = *run.problem;
  std::string error;
  // Solved banded, the problem keeps its H: the envelope serves it once.
  SolverOptions solver;
  solver.linear_solver = "BANDED_CHOLESKY";
  solver.max_iterations = 3;
  ceres::Solver::Options ceres_options;
  ASSERT_TRUE(ToCeresOptions(solver, &ceres_options, &error)) << error;
  SlamResult result;
  ASSERT_TRUE(RunSolve(solver, ceres_options, &problem, &result, &error,
                       /*keep_linearization=*/true))
      << error;
  std::vector<double> times;
  for (int k = 0; k < 118; ++k) times.push_back(0.5 * k + 0.25);
  // The envelope, then the Schur form (the default without a kept H), the
  // selected inverse and SuiteSparseQR.
  CovarianceOptions selected = WithAlgorithm(ceres::SPARSE_QR);
  selected.use_selected_inverse = true;
  const std::pair<CovarianceOptions, CovarianceMethod> methods[] = {
      {CovarianceOptions(), CovarianceMethod::kEnvelope},
      {CovarianceOptions(), CovarianceMethod::kSchur},
      {selected, CovarianceMethod::kSelectedInverse},
      {WithAlgorithm(ceres::SPARSE_QR), CovarianceMethod::kCeres}};
  for (const auto& [covariance_options, expected_method] : methods) {
    SCOPED_TRACE(static_cast<int>(expected_method));
    for (Landmark& l : landmarks) l.has_covariance = false;
    std::vector<Eigen::Matrix3d> covariances;
    CovarianceMethod method = CovarianceMethod::kCeres;
    ASSERT_TRUE(ComputePosteriorCovariance(&problem, *model, times,
                                           covariance_options, &covariances,
                                           &landmarks, &error, &method))
        << error;
    EXPECT_EQ(method, expected_method);

    // Dense J over [trajectory blocks..., landmark blocks...].
    std::vector<double*> blocks;
    std::vector<int> offsets;
    int columns = 0;
    for (int b = 0; b < model->num_blocks(); ++b) {
      blocks.push_back(model->mutable_block(b));
      offsets.push_back(columns);
      columns += model->block_size(b);
    }
    const int landmark_offset = columns;
    for (const Landmark& l : landmarks) {
      blocks.push_back(problem.landmark_block(l.id));
      columns += 2;
    }
    ceres::Problem::EvaluateOptions evaluate;
    evaluate.parameter_blocks = blocks;
    ceres::CRSMatrix crs;
    ASSERT_TRUE(
        problem.problem()->Evaluate(evaluate, nullptr, nullptr, nullptr, &crs));
    Eigen::MatrixXd jacobian = Eigen::MatrixXd::Zero(crs.num_rows, columns);
    for (int r = 0; r < crs.num_rows; ++r) {
      for (int k = crs.rows[r]; k < crs.rows[r + 1]; ++k) {
        jacobian(r, crs.cols[k]) = crs.values[k];
      }
    }
    const Eigen::MatrixXd sigma =
        (jacobian.transpose() * jacobian)
            .ldlt()
            .solve(Eigen::MatrixXd::Identity(columns, columns));
    int blended = 0;
    for (std::size_t k = 0; k < times.size(); ++k) {
      const PoseMap map = model->PoseAt(times[k]);
      if (map.terms.size() == 6) ++blended;
      Eigen::MatrixXd phi = Eigen::MatrixXd::Zero(3, columns);
      for (const PoseTerm& term : map.terms) {
        phi.block(term.coordinate, offsets[term.block], 1, term.phi->size()) =
            term.phi->transpose();
      }
      const Eigen::Matrix3d expected = phi * sigma * phi.transpose();
      EXPECT_LT((covariances[k] - expected).norm(), 1e-9 * expected.norm())
          << "t = " << times[k] << "\n"
          << covariances[k] << "\nvs\n"
          << expected;
    }
    EXPECT_GE(blended, 10);
    for (std::size_t k = 0; k < landmarks.size(); ++k) {
      const Eigen::Matrix2d expected =
          sigma.block<2, 2>(landmark_offset + 2 * k, landmark_offset + 2 * k);
      ASSERT_TRUE(landmarks[k].has_covariance);
      EXPECT_NEAR(landmarks[k].sxx, expected(0, 0), 1e-9 * expected.norm());
      EXPECT_NEAR(landmarks[k].sxy, expected(0, 1), 1e-9 * expected.norm());
      EXPECT_NEAR(landmarks[k].syy, expected(1, 1), 1e-9 * expected.norm());
    }
  }
}

// Many wide feature windows (blocks past kMinPanelWidth, a factorisation
// past both bounds of BandedSize::WorkWithinBound) and no H kept from a
// solve: the envelope, whose step is cheaper than the dense reduced
// system's, gives what the selected inverse gives.
TEST(PosteriorCovarianceTest, ManyWideWindowsUseTheEnvelope) {
  WindowedRun run;
  ASSERT_NO_FATAL_FAILURE(BuildWindowedRun(300, 60, 60, 40.0, 10.0, &run));
  const FeatureTrajectory& model = *run.model;
  ASSERT_EQ(model.num_segments(), 8);
  std::vector<Landmark>& landmarks = run.landmarks;
  SlamProblem& problem = *run.problem;
  std::string error;
  const std::shared_ptr<BandedProblem> layout =
      problem.BandedLayout(problem.BandColumns());
  ASSERT_FALSE(layout->Size().WorkWithinBound())
      << layout->Size().multiply_adds << " in " << layout->Size().num_columns;
  const StepWork work = EnvelopeAndDenseStepWork(&problem, *layout);
  ASSERT_LT(work.envelope, work.dense_reduced);
  std::vector<double> times;
  for (int k = 0; k < 150; ++k) times.push_back(1.3 * k + 0.2);
  CovarianceOptions selected = WithAlgorithm(ceres::SPARSE_QR);
  selected.use_selected_inverse = true;
  std::vector<Eigen::Matrix3d> expected, covariances;
  std::vector<Landmark> expected_landmarks = landmarks;
  CovarianceMethod method = CovarianceMethod::kCeres;
  ASSERT_TRUE(ComputePosteriorCovariance(&problem, model, times, selected,
                                         &expected, &expected_landmarks, &error,
                                         &method))
      << error;
  ASSERT_EQ(method, CovarianceMethod::kSelectedInverse);
  ASSERT_TRUE(ComputePosteriorCovariance(&problem, model, times,
                                         CovarianceOptions(), &covariances,
                                         &landmarks, &error, &method))
      << error;
  EXPECT_EQ(method, CovarianceMethod::kEnvelope);
  for (std::size_t k = 0; k < times.size(); ++k) {
    EXPECT_LT((covariances[k] - expected[k]).norm(), 1e-8 * expected[k].norm())
        << "t = " << times[k];
  }
  for (std::size_t k = 0; k < landmarks.size(); ++k) {
    const Landmark& e = expected_landmarks[k];
    ASSERT_TRUE(landmarks[k].has_covariance);
    EXPECT_NEAR(landmarks[k].sxx, e.sxx, 1e-8 * e.sxx);
    EXPECT_NEAR(landmarks[k].sxy, e.sxy, 1e-8 * e.sxx);
    EXPECT_NEAR(landmarks[k].syy, e.syy, 1e-8 * e.syy);
  }
}

// A WNOA run is banded: too many states for the Schur form. The inverse on
// its time-ordered envelope and the selected inverse of a sparse Cholesky
// both give what SuiteSparseQR gives, with and without a robust loss (whose
// corrected Jacobian all three read).
TEST(PosteriorCovarianceTest, WnoaRunUsesTheEnvelope) {
  SimulationOptions sim = PaperOptions(6);
  sim.num_steps = 400;
  sim.num_landmarks = 10;
  Dataset dataset;
  std::string error;
  ASSERT_TRUE(Simulate(sim, &dataset, &error)) << error;
  std::vector<double> times;
  for (const TimedPose& p : dataset.ground_truth) times.push_back(p.t);
  std::unique_ptr<WnoaTrajectory> model = WnoaTrajectory::Create(
      WnoaOptions(),
      std::make_shared<PiecewiseLinearMean>(dataset.ground_truth), times,
      &error);
  ASSERT_NE(model, nullptr) << error;
  ASSERT_GT(model->num_blocks() * WnoaTrajectory::kStateSize, 2000);
  std::map<LandmarkId, Eigen::Vector2d> initial;
  std::vector<Landmark> landmarks;
  for (const Landmark& l : dataset.ground_truth_landmarks) {
    initial[l.id] = Eigen::Vector2d(l.x + 0.3, l.y - 0.2);
    landmarks.push_back(l);
  }
  std::vector<double> output;
  for (int k = 0; k < 200; ++k) output.push_back(1.7 * k + 0.3);
  CovarianceOptions selected_only = WithAlgorithm(ceres::SPARSE_QR);
  selected_only.use_selected_inverse = true;
  for (const char* loss : {"none", "cauchy"}) {
    SCOPED_TRACE(loss);
    ProblemOptions problem_options;
    // At 0.5 sigma a share of the rows lies where the loss bends.
    problem_options.loss = problem_options.odometry_loss = {loss, 0.5};
    SlamProblem problem(model.get(), problem_options);
    ASSERT_TRUE(problem.Build(dataset, initial, &error)) << error;
    const std::pair<CovarianceOptions, CovarianceMethod> methods[] = {
        {WithAlgorithm(ceres::SPARSE_QR), CovarianceMethod::kCeres},
        {CovarianceOptions(), CovarianceMethod::kEnvelope},
        {selected_only, CovarianceMethod::kSelectedInverse}};
    std::vector<Eigen::Matrix3d> reference;
    std::vector<Landmark> reference_landmarks = landmarks;
    for (const auto& [options, expected_method] : methods) {
      SCOPED_TRACE(static_cast<int>(expected_method));
      std::vector<Eigen::Matrix3d> covariances;
      std::vector<Landmark> with_covariance = landmarks;
      CovarianceMethod method = CovarianceMethod::kCeres;
      ASSERT_TRUE(ComputePosteriorCovariance(&problem, *model, output, options,
                                             &covariances, &with_covariance,
                                             &error, &method))
          << error;
      EXPECT_EQ(method, expected_method);
      if (expected_method == CovarianceMethod::kCeres) {
        reference = covariances;
        reference_landmarks = with_covariance;
        continue;
      }
      for (std::size_t k = 0; k < output.size(); ++k) {
        EXPECT_LT((covariances[k] - reference[k]).norm(),
                  1e-8 * reference[k].norm())
            << "t = " << output[k];
      }
      for (std::size_t k = 0; k < landmarks.size(); ++k) {
        const Landmark& expected = reference_landmarks[k];
        EXPECT_NEAR(with_covariance[k].sxx, expected.sxx, 1e-8 * expected.sxx);
        EXPECT_NEAR(with_covariance[k].sxy, expected.sxy, 1e-8 * expected.sxx);
        EXPECT_NEAR(with_covariance[k].syy, expected.syy, 1e-8 * expected.syy);
      }
    }
  }
}

// configs/synthetic_range_bearing.flags as SlamOptions.
SlamOptions SyntheticRangeBearingOptions(int outer_rounds) {
  SlamOptions options = testing::SyntheticRangeBearingOptions();
  options.mean.outer_rounds = outer_rounds;
  options.output.covariance = true;
  return options;
}

// chi^2 quantiles at 0.95.
constexpr double kChi2Two95 = 5.991464547107979;  // 2 dof
constexpr double kChi2One95 = 3.841458820694124;  // 1 dof

struct Coverage {
  int positions = 0, positions_inside = 0;
  int headings = 0, headings_inside = 0;
  int landmarks = 0, landmarks_inside = 0;
  double position_d2_sum = 0.0;
  double position_fraction() const {
    return static_cast<double>(positions_inside) / positions;
  }
  double heading_fraction() const {
    return static_cast<double>(headings_inside) / headings;
  }
  double landmark_fraction() const {
    return static_cast<double>(landmarks_inside) / landmarks;
  }
  double mean_position_d2() const { return position_d2_sum / positions; }
  std::string Report() const {
    char text[256];
    std::snprintf(text, sizeof(text),
                  "positions %d/%d = %.4f (mean d^2 %.3f), headings %d/%d = "
                  "%.4f, landmarks %d/%d = %.4f",
                  positions_inside, positions, position_fraction(),
                  mean_position_d2(), headings_inside, headings,
                  heading_fraction(), landmarks_inside, landmarks,
                  landmark_fraction());
    return text;
  }
};

// Adds the 2-sigma coverage of one simulated run solved with `options`,
// without a robust loss: the data are Gaussian, and the Laplace covariance
// is checked against what they are.
void AddCoverage(std::uint64_t seed, SlamOptions options, Coverage* coverage) {
  Dataset dataset;
  std::string error;
  ASSERT_TRUE(Simulate(PaperOptions(seed), &dataset, &error)) << error;
  options.problem.loss = options.problem.odometry_loss = {"none", 1.0};
  SlamResult result;
  ASSERT_TRUE(RunSlam(dataset, options, &result, &error)) << error;
  ASSERT_EQ(result.pose_covariances.size(), result.trajectory.size());
  std::map<double, std::size_t> index;
  for (std::size_t k = 0; k < result.trajectory.size(); ++k) {
    index[result.trajectory[k].t] = k;
  }
  for (const TimedPose& truth : dataset.ground_truth) {
    ASSERT_EQ(index.count(truth.t), 1u);
    const std::size_t k = index[truth.t];
    const TimedPose& estimate = result.trajectory[k];
    const Eigen::Matrix3d& c = result.pose_covariances[k];
    const Eigen::Vector2d e(estimate.x - truth.x, estimate.y - truth.y);
    const double d2 = e.dot(c.topLeftCorner<2, 2>().ldlt().solve(e));
    ++coverage->positions;
    coverage->position_d2_sum += d2;
    if (d2 <= kChi2Two95) ++coverage->positions_inside;
    const double heading_error = WrapAngle(estimate.theta - truth.theta);
    ++coverage->headings;
    if (heading_error * heading_error <= kChi2One95 * c(2, 2)) {
      ++coverage->headings_inside;
    }
  }
  std::map<LandmarkId, Landmark> truths;
  for (const Landmark& l : dataset.ground_truth_landmarks) truths[l.id] = l;
  for (const Landmark& l : result.landmarks) {
    ASSERT_TRUE(l.has_covariance);
    const Landmark& truth = truths.at(l.id);
    Eigen::Matrix2d c;
    c << l.sxx, l.sxy, l.sxy, l.syy;
    const Eigen::Vector2d e(l.x - truth.x, l.y - truth.y);
    ++coverage->landmarks;
    if (e.dot(c.ldlt().solve(e)) <= kChi2Two95) ++coverage->landmarks_inside;
  }
}

// Calibration: on simulated data about 95% of true positions lie
// inside the 2-sigma (95%) ellipse of the posterior. Range-bearing with
// odometry, the paper's protocol (300 poses, 50 landmarks per seed). Errors
// within one run are strongly correlated (a drift of the whole map), so one
// run covers either nearly all or far fewer of its poses; only the pooled
// fraction over seeds is meaningful. Measured: 0.9621 of 2400 positions
// (mean d^2 2.09, 2 ideal), 0.9329 of headings, 0.9625 of 400 landmarks;
// over seeds 1-30, 0.9413 of positions (docs/uncertainty.md).
TEST(PosteriorCovarianceCalibrationTest, SplineRoundsTwoSigmaHold95Percent) {
  Coverage coverage;
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    AddCoverage(seed, SyntheticRangeBearingOptions(2), &coverage);
  }
  std::printf("outer_rounds 2: %s\n", coverage.Report().c_str());
  ASSERT_EQ(coverage.positions, 2400);
  EXPECT_GE(coverage.position_fraction(), 0.90);
  EXPECT_LE(coverage.position_fraction(), 0.99);
  EXPECT_GE(coverage.mean_position_d2(), 1.4);
  EXPECT_LE(coverage.mean_position_d2(), 2.8);
  EXPECT_GE(coverage.heading_fraction(), 0.85);
  EXPECT_LE(coverage.heading_fraction(), 0.99);
  EXPECT_GE(coverage.landmark_fraction(), 0.85);
  EXPECT_LE(coverage.landmark_fraction(), 0.99);
}

// One solve with the odometry mean (no spline refit, so the prior does not
// depend on the data). Measured: 0.9267 of 1800 positions (mean d^2 2.43),
// 0.8900 of 300 landmarks; over seeds 1-30 it is over-confident (0.8876,
// the prior pulls towards dead reckoning: docs/uncertainty.md).
TEST(PosteriorCovarianceCalibrationTest, OneSolveTwoSigmaHoldAbout95Percent) {
  Coverage coverage;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    AddCoverage(seed, SyntheticRangeBearingOptions(0), &coverage);
  }
  std::printf("outer_rounds 0: %s\n", coverage.Report().c_str());
  ASSERT_EQ(coverage.positions, 1800);
  EXPECT_GE(coverage.position_fraction(), 0.85);
  EXPECT_LE(coverage.position_fraction(), 0.99);
  EXPECT_GE(coverage.landmark_fraction(), 0.80);
  EXPECT_LE(coverage.landmark_fraction(), 0.99);
}

// The RFF default with odometry is a correction around a WNOA solve: its
// pose covariance is the WNOA solve's plus the correction's, never the
// correction's alone (which was 300x over-confident on Plaza 1). The sum
// counts the first pose's prior in both solves: at that pose (sigma 0.01 m)
// it is up to twice the WNOA covariance, elsewhere within 1.5x.
TEST(WnoaMeanCovarianceTest, RffCovarianceContainsTheWnoaSolves) {
  SimulationOptions simulation = PaperOptions(3);
  simulation.num_steps = 120;
  Dataset dataset;
  std::string error;
  ASSERT_TRUE(Simulate(simulation, &dataset, &error)) << error;
  SlamOptions options;
  options.output.covariance = true;
  SlamResult rff, wnoa;
  ASSERT_TRUE(RunSlam(dataset, options, &rff, &error)) << error;
  ASSERT_EQ(rff.prior_mean, "wnoa");
  options.prior = "wnoa";
  ASSERT_TRUE(RunSlam(dataset, options, &wnoa, &error)) << error;
  ASSERT_EQ(rff.pose_covariances.size(), wnoa.pose_covariances.size());
  for (std::size_t i = 0; i < rff.pose_covariances.size(); ++i) {
    const double ratio = rff.pose_covariances[i].topLeftCorner<2, 2>().trace() /
                         wnoa.pose_covariances[i].topLeftCorner<2, 2>().trace();
    EXPECT_GE(ratio, 1.0) << "pose " << i;
    EXPECT_LE(ratio, i == 0 ? 2.0 : 1.5) << "pose " << i;
  }
}

// The `../shared` MRCLAM robot 3 file without robust losses, Q_c started
// from the given value: the WNOA solve diverges through its outliers and
// stops at the iteration cap (APE 4.5 m), where J^T J has no digits left.
// Its landmarks all have priors, so none is blamed; the error says which
// solve it was taken at. (From the odometry's Q_c it converges, 1.08 m.)
TEST(PosteriorCovarianceSharedTest,
     ASuspectSolveIsNamedWhereTheCovarianceFails) {
  constexpr char kFile[] = "data/heldout/mrclam6_robot3_map_1m_off.rffd";
  Dataset dataset;
  if (!testing::ReadSharedDataset(kFile, &dataset)) GTEST_SKIP() << kFile;
  std::string error;
  SlamOptions options;
  options.prior = "wnoa";
  options.problem.loss.name = "none";
  options.problem.odometry_loss.name = "none";
  options.wnoa.qc_start = "given";
  options.output.covariance = true;
  SlamResult result;
  EXPECT_FALSE(RunSlam(dataset, options, &result, &error));
  EXPECT_THAT(error, HasSubstr("the information matrix J^T J is singular; the "
                               "solve it is taken at is suspect: the solver "
                               "stopped before convergence (NO_CONVERGENCE)"));
  EXPECT_THAT(error, ::testing::Not(HasSubstr("landmark")));
}

// The `../shared` MRCLAM robot 3 file at default flags. Under the Cauchy
// loss its data settle to, the rounds rescaled loss-corrected squares,
// short of Gaussian rows' by kappa: the WNOA mean's odometry sigma fell to
// 0.024 of the stated one at the round cap, and 0.83 of the positions were
// inside their 95% ellipses (NEES 2.52). Weighted by kappa it settles at
// 0.108 (the fit's forward residuals 0.14 of the stated sigma, the truth's
// 0.17): measured NEES 1.49, coverage 0.986.
TEST(PosteriorCovarianceSharedTest, TheOdometrySigmaSettlesUnderCauchysLoss) {
  constexpr char kFile[] = "data/heldout/mrclam6_robot3_map_1m_off.rffd";
  Dataset dataset;
  if (!testing::ReadSharedDataset(kFile, &dataset)) GTEST_SKIP() << kFile;
  std::string error;
  SlamOptions options;
  options.output.covariance = true;
  SlamResult result;
  ASSERT_TRUE(RunSlam(dataset, options, &result, &error)) << error;
  EXPECT_TRUE(result.noise_unsettled.empty());
  EXPECT_EQ(result.loss, "cauchy");
  EXPECT_GT(result.noise.odometry, 0.08);
  EXPECT_LT(result.noise.odometry, 0.15);
  std::vector<PoseCovariance> covariances;
  for (std::size_t k = 0; k < result.trajectory.size(); ++k) {
    covariances.push_back({result.trajectory[k].t, result.pose_covariances[k]});
  }
  Evaluation evaluation;
  ASSERT_TRUE(EvaluateConsistency(dataset.ground_truth, result.trajectory,
                                  covariances, &evaluation, &error))
      << error;
  EXPECT_NEAR(evaluation.consistency.mean_position_nees, 1.49, 0.15);
  EXPECT_GT(evaluation.consistency.position_coverage[1], 0.95);
}

}  // namespace
}  // namespace rff
