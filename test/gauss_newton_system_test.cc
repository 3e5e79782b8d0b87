#include "rff_ceres/gauss_newton_system.h"

#include <algorithm>
#include <memory>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "Eigen/Dense"
#include "gtest/gtest.h"
#include "rff_ceres/ceres_solve.h"
#include "rff_ceres/mean/prior_mean.h"
#include "rff_ceres/priors/trajectory_prior.h"
#include "rff_ceres/simulate.h"
#include "rff_ceres/variance_components.h"

namespace rff {
namespace {

// A Jacobian of `t` chained leading columns and `landmarks` landmark pairs,
// every row touching two neighbouring leading columns and one landmark.
RowMajorSparse ChainWithLandmarks(int t, int landmarks, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  std::vector<Eigen::Triplet<double>> entries;
  int row = 0;
  for (int i = 0; i + 1 < t; ++i) {
    for (int k = 0; k < 3; ++k, ++row) {
      entries.emplace_back(row, i, normal(rng));
      entries.emplace_back(row, i + 1, normal(rng));
      const int landmark = t + 2 * (row % landmarks);
      entries.emplace_back(row, landmark, normal(rng));
      entries.emplace_back(row, landmark + 1, normal(rng));
    }
  }
  RowMajorSparse jacobian(row, t + 2 * landmarks);
  jacobian.setFromTriplets(entries.begin(), entries.end());
  return jacobian;
}

TEST(GaussNewtonSystemTest, EveryFactorizationSolvesTheSameSystem) {
  const int t = 40;
  const RowMajorSparse jacobian = ChainWithLandmarks(t, 3, 7);
  const GaussNewtonSystem schur(jacobian, t, Factorization::kSchurOrSparse);
  const GaussNewtonSystem schur_only(jacobian, t, Factorization::kSchurOnly);
  const GaussNewtonSystem sparse(jacobian, t, Factorization::kSparse);
  ASSERT_TRUE(schur.positive_definite());
  ASSERT_TRUE(schur_only.positive_definite());
  ASSERT_TRUE(sparse.positive_definite());
  EXPECT_TRUE(schur.structured());
  EXPECT_TRUE(schur_only.structured());
  EXPECT_FALSE(sparse.structured());

  const Eigen::MatrixXd h = Eigen::MatrixXd(
      Eigen::SparseMatrix<double>(jacobian.transpose()) * jacobian);
  const Eigen::VectorXd z = Eigen::VectorXd::LinSpaced(h.rows(), -1.0, 2.0);
  const Eigen::VectorXd expected = h.ldlt().solve(z);
  const double scale = expected.cwiseAbs().maxCoeff();
  EXPECT_LT((schur.Solve(z) - expected).cwiseAbs().maxCoeff(), 1e-9 * scale);
  EXPECT_LT((sparse.Solve(z) - expected).cwiseAbs().maxCoeff(), 1e-9 * scale);
}

// Every factorisation gives log det H of the dense LDLT: the Schur form as
// det C det S, the sparse LDLT's pivots, the envelope's diagonal.
TEST(GaussNewtonSystemTest, EveryFactorizationGivesTheLogDeterminant) {
  const int t = 40, landmarks = 3;
  const RowMajorSparse jacobian = ChainWithLandmarks(t, landmarks, 7);
  std::vector<int> time_order(t + 2 * landmarks);
  std::iota(time_order.begin(), time_order.end(), 0);
  const GaussNewtonSystem schur(jacobian, t, Factorization::kSchurOnly);
  const GaussNewtonSystem sparse(jacobian, t, Factorization::kSparse);
  const GaussNewtonSystem envelope(
      jacobian, t, Factorization::kEnvelopeOrSparse, nullptr, time_order);
  ASSERT_TRUE(schur.structured());
  ASSERT_FALSE(sparse.structured());
  ASSERT_TRUE(envelope.envelope());
  const Eigen::MatrixXd h = Eigen::MatrixXd(
      Eigen::SparseMatrix<double>(jacobian.transpose()) * jacobian);
  const double expected = h.ldlt().vectorD().array().log().sum();
  EXPECT_GT(std::abs(expected), 1.0);
  for (const GaussNewtonSystem* system : {&schur, &sparse, &envelope}) {
    EXPECT_NEAR(system->LogDeterminant(), expected, 1e-9 * std::abs(expected));
  }
}

// Rows over separate runs of leading columns (two windows' features, as
// where windows blend), sparse enough for the row blocks: the Schur form
// solves the system the dense LDLT of J^T J solves.
TEST(GaussNewtonSystemTest, RowsOverSeparateRunsGiveTheSameSystem) {
  const int t = 80, landmarks = 6;
  std::mt19937 rng(21);
  std::normal_distribution<double> normal;
  std::vector<Eigen::Triplet<double>> entries;
  int row = 0;
  for (int i = 0; i + 23 < t; ++i) {
    for (int k = 0; k < 4; ++k, ++row) {
      for (const int column : {i, i + 1, i + 2, i + 20, i + 21, i + 23}) {
        entries.emplace_back(row, column, normal(rng));
      }
      const int landmark = t + 2 * (row % landmarks);
      entries.emplace_back(row, landmark, normal(rng));
      entries.emplace_back(row, landmark + 1, normal(rng));
    }
  }
  RowMajorSparse jacobian(row, t + 2 * landmarks);
  jacobian.setFromTriplets(entries.begin(), entries.end());
  const GaussNewtonSystem schur(jacobian, t, Factorization::kSchurOnly);
  ASSERT_TRUE(schur.positive_definite());
  const Eigen::MatrixXd h = Eigen::MatrixXd(
      Eigen::SparseMatrix<double>(jacobian.transpose()) * jacobian);
  const Eigen::VectorXd z = Eigen::VectorXd::LinSpaced(h.rows(), -1.0, 2.0);
  const Eigen::VectorXd expected = h.ldlt().solve(z);
  EXPECT_LT((schur.Solve(z) - expected).cwiseAbs().maxCoeff(),
            1e-9 * expected.cwiseAbs().maxCoeff());
}

// All columns at once give, bit for bit (a zero's sign aside), what Eigen's own
// solve gives one column at a time (the same operations in the same order).
TEST(GaussNewtonSystemTest, ManyColumnsSolveAsEigenSolvesEach) {
  const int t = 60;
  const RowMajorSparse jacobian = ChainWithLandmarks(t, 4, 11);
  const GaussNewtonSystem sparse(jacobian, t, Factorization::kSparse);
  const GaussNewtonSystem schur(jacobian, t, Factorization::kSchurOnly);
  ASSERT_TRUE(sparse.positive_definite());
  ASSERT_TRUE(schur.positive_definite());
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> eigen(
      Eigen::SparseMatrix<double>(jacobian.transpose()) * jacobian);
  std::mt19937 rng(5);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd z(jacobian.cols(), 7);
  for (Eigen::Index i = 0; i < z.size(); ++i) z.data()[i] = normal(rng);
  const Eigen::MatrixXd many = sparse.Solve(z);
  const Eigen::MatrixXd many_schur = schur.Solve(z);
  for (Eigen::Index k = 0; k < z.cols(); ++k) {
    const Eigen::VectorXd one = eigen.solve(z.col(k).eval());
    for (Eigen::Index i = 0; i < z.rows(); ++i) {
      ASSERT_EQ(many(i, k), one[i]) << "row " << i << ", column " << k;
    }
    EXPECT_LT((many_schur.col(k) - one).cwiseAbs().maxCoeff(),
              1e-9 * one.cwiseAbs().maxCoeff());
  }
}

// The envelope in a time order (the chain run backwards, the landmarks,
// seen all along, after it), against the dense LDLT; the solutions come back
// in the Jacobian's column order.
TEST(GaussNewtonSystemTest, EnvelopeInATimeOrderSolvesTheSameSystem) {
  const int t = 40, landmarks = 3;
  const RowMajorSparse jacobian = ChainWithLandmarks(t, landmarks, 7);
  std::vector<int> time_order(t + 2 * landmarks);
  for (int c = 0; c < t + 2 * landmarks; ++c) {
    time_order[c] = c < t ? t - 1 - c : c;
  }
  const GaussNewtonSystem envelope(
      jacobian, t, Factorization::kEnvelopeOrSparse, nullptr, time_order);
  ASSERT_TRUE(envelope.envelope());
  ASSERT_TRUE(envelope.positive_definite());
  EXPECT_FALSE(envelope.structured());
  const Eigen::MatrixXd h = Eigen::MatrixXd(
      Eigen::SparseMatrix<double>(jacobian.transpose()) * jacobian);
  Eigen::MatrixXd z(h.rows(), 3);
  z.col(0) = Eigen::VectorXd::LinSpaced(h.rows(), -1.0, 2.0);
  z.col(1) = Eigen::VectorXd::Ones(h.rows());
  z.col(2) = Eigen::VectorXd::LinSpaced(h.rows(), 3.0, -4.0);
  const Eigen::MatrixXd expected = h.ldlt().solve(z);
  const Eigen::MatrixXd solved = envelope.Solve(z);
  for (Eigen::Index k = 0; k < z.cols(); ++k) {
    const double scale = expected.col(k).cwiseAbs().maxCoeff();
    EXPECT_LT((solved.col(k) - expected.col(k)).cwiseAbs().maxCoeff(),
              1e-9 * scale)
        << k;
  }
}

// Where the envelope would cost more than kMaxEnvelopeWorkPerVariable a
// variable (every row over every column: n^2 / 6) and more than
// kMaxSmallEnvelopeWork in all (n^3 / 6), or no time order is given, the
// sparse LDLT solves.
TEST(GaussNewtonSystemTest, EnvelopeTooCostlyOrUnorderedFallsBackToSparse) {
  const int n = 700;  // 81667 multiply-adds a variable, 5.7e7 in all.
  std::mt19937 rng(4);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd dense(2 * n, n);
  for (Eigen::Index i = 0; i < dense.size(); ++i) dense.data()[i] = normal(rng);
  const RowMajorSparse jacobian = dense.sparseView();
  std::vector<int> identity(n);
  for (int c = 0; c < n; ++c) identity[c] = c;
  const GaussNewtonSystem costly(jacobian, n, Factorization::kEnvelopeOrSparse,
                                 nullptr, identity);
  const GaussNewtonSystem unordered(jacobian, n,
                                    Factorization::kEnvelopeOrSparse);
  const Eigen::VectorXd z = Eigen::VectorXd::LinSpaced(n, -1.0, 2.0);
  const Eigen::VectorXd expected = (dense.transpose() * dense).ldlt().solve(z);
  for (const GaussNewtonSystem* system : {&costly, &unordered}) {
    EXPECT_FALSE(system->envelope());
    EXPECT_FALSE(system->structured());
    ASSERT_TRUE(system->positive_definite());
    EXPECT_LT((system->Solve(z) - expected).cwiseAbs().maxCoeff(),
              1e-9 * expected.cwiseAbs().maxCoeff());
  }
  // At 20 columns (67 a variable) the same shape takes the envelope, and at
  // 300 (15000 a variable, but 4.5e6 in all) too.
  for (const int columns : {20, 300}) {
    const RowMajorSparse small = dense.leftCols(columns).sparseView();
    const GaussNewtonSystem envelope(
        small, columns, Factorization::kEnvelopeOrSparse, nullptr,
        std::vector<int>(identity.begin(), identity.begin() + columns));
    EXPECT_TRUE(envelope.envelope()) << columns;
  }
}

// A singular H (a column no row touches) fails the envelope's Cholesky;
// the sparse LDLT then decides, and finds it singular too.
TEST(GaussNewtonSystemTest, SingularEnvelopeFallsBackAndIsNotPositiveDefinite) {
  const int t = 12;
  RowMajorSparse jacobian = ChainWithLandmarks(t, 1, 3);
  jacobian.conservativeResize(jacobian.rows(), jacobian.cols() + 1);
  std::vector<int> time_order(jacobian.cols());
  for (int c = 0; c < jacobian.cols(); ++c) time_order[c] = c;
  const GaussNewtonSystem system(jacobian, t, Factorization::kEnvelopeOrSparse,
                                 nullptr, time_order);
  EXPECT_FALSE(system.envelope());
  EXPECT_FALSE(system.positive_definite());
}

// A kept analysis gives the bits a fresh factorisation gives, for systems of
// its pattern (new values) and of another (analysed again).
TEST(GaussNewtonSystemTest, KeptAnalysisChangesNoDigit) {
  const int t = 60;
  const std::vector<RowMajorSparse> jacobians = {
      ChainWithLandmarks(t, 4, 11), ChainWithLandmarks(t, 4, 12),
      ChainWithLandmarks(t, 5, 13), ChainWithLandmarks(t, 4, 14)};
  SparseAnalysis analysis;
  for (const RowMajorSparse& jacobian : jacobians) {
    const GaussNewtonSystem kept(jacobian, t, Factorization::kSparse,
                                 &analysis);
    const GaussNewtonSystem fresh(jacobian, t, Factorization::kSparse);
    ASSERT_TRUE(kept.positive_definite());
    const Eigen::SparseMatrix<double> h =
        Eigen::SparseMatrix<double>(jacobian.transpose()) * jacobian;
    EXPECT_EQ(
        analysis.inner,
        std::vector<int>(h.innerIndexPtr(), h.innerIndexPtr() + h.nonZeros()));
    const Eigen::MatrixXd z =
        Eigen::MatrixXd::Ones(jacobian.cols(), 2) * 0.5 +
        Eigen::VectorXd::LinSpaced(jacobian.cols(), -1.0, 2.0).replicate(1, 2);
    const Eigen::MatrixXd a = kept.Solve(z), b = fresh.Solve(z);
    for (Eigen::Index i = 0; i < a.size(); ++i) {
      ASSERT_EQ(a.data()[i], b.data()[i]) << i;
    }
  }
}

TEST(GaussNewtonSystemTest, SchurOnlyLeavesASystemWithoutTheFormUnfactorised) {
  // A row on two landmarks: not the Schur form.
  const int t = 10;
  RowMajorSparse jacobian = ChainWithLandmarks(t, 2, 8);
  jacobian.coeffRef(0, t + 2) = 1.0;
  const GaussNewtonSystem schur_only(jacobian, t, Factorization::kSchurOnly);
  EXPECT_FALSE(schur_only.structured());
  EXPECT_FALSE(schur_only.positive_definite());
  const GaussNewtonSystem fallback(jacobian, t, Factorization::kSchurOrSparse);
  EXPECT_FALSE(fallback.structured());
  EXPECT_TRUE(fallback.positive_definite());
}

// A 60-step run of the paper's simulation (seed `seed`, 12 landmarks) as
// `options` model it around a constant mean, the landmarks started 0.3 m
// off: built, nothing solved.
struct SmallProblem {
  Dataset dataset;
  std::unique_ptr<TrajectoryModel> model;
  std::unique_ptr<SlamProblem> problem;
};

// With `one_sighting_a_time`, only the first observation of each time is
// kept: no costs share a time, so none are compressed (BandedProblem).
void BuildSmallProblem(int seed, const SlamOptions& options,
                       SmallProblem* built, bool one_sighting_a_time = false) {
  SimulationOptions simulation = PaperOptions(seed);
  simulation.num_steps = 60;
  simulation.num_landmarks = 12;
  std::string error;
  ASSERT_TRUE(Simulate(simulation, &built->dataset, &error)) << error;
  if (one_sighting_a_time) {
    std::vector<Observation>& observations = built->dataset.observations;
    observations.erase(
        std::unique(observations.begin(), observations.end(),
                    [](const Observation& a, const Observation& b) {
                      return a.t == b.t;
                    }),
        observations.end());
  }
  const std::shared_ptr<const MeanFunction> mean =
      BuildPriorMean("constant", built->dataset, options.localization,
                     kPaperSplineSmoothing, &error);
  ASSERT_NE(mean, nullptr) << error;
  built->model = CreateTrajectoryModel(built->dataset, options, mean, &error);
  ASSERT_NE(built->model, nullptr) << error;
  std::map<LandmarkId, Eigen::Vector2d> landmarks;
  for (const Landmark& l : built->dataset.ground_truth_landmarks) {
    landmarks[l.id] = Eigen::Vector2d(l.x + 0.3, l.y - 0.3);
  }
  built->problem =
      std::make_unique<SlamProblem>(built->model.get(), options.problem);
  ASSERT_TRUE(built->problem->Build(built->dataset, landmarks, &error))
      << error;
}

// The columns of the covariance and the variance components: the model's
// blocks in its order, the calibrations, the landmarks by id, whatever the
// heap's order of their storage (Ceres lists blocks by address).
TEST(LandmarksLastTest, TakesTheProblemsOwnOrder) {
  SlamOptions options;
  options.prior = "wnoa";
  options.problem.range_calibration.estimate = true;
  options.problem.odometry_calibration.estimate = true;
  SmallProblem built;
  BuildSmallProblem(2, options, &built);
  ASSERT_NE(built.problem, nullptr);
  SlamProblem& problem = *built.problem;
  int num_leading = 0;
  const std::vector<double*> columns = LandmarksLast(&problem, &num_leading);
  std::vector<double*> expected;
  int leading = 0;
  for (int b = 0; b < built.model->num_blocks(); ++b) {
    expected.push_back(built.model->mutable_block(b));
    leading += built.model->block_size(b);
  }
  // The range calibration, then the odometry's: no shared model blocks.
  const BandedColumns band_columns = problem.BandColumns();
  for (double* calibration : band_columns.last) {
    expected.push_back(calibration);
    leading += 2;
  }
  ASSERT_EQ(expected.size(), built.model->num_blocks() + 2u);
  for (const auto& [id, position] : problem.landmarks()) {
    expected.push_back(problem.landmark_block(id));
  }
  EXPECT_EQ(columns, expected);
  EXPECT_EQ(num_leading, leading);
  EXPECT_EQ(static_cast<int>(columns.size()),
            problem.problem()->NumParameterBlocks());
}

// g^T H^-1 g / 2 at the problem's values from its dense Jacobian.
void DenseDecrease(SlamProblem* problem, double* decrease) {
  std::vector<ceres::ResidualBlockId> ids;
  problem->problem()->GetResidualBlocks(&ids);
  double cost = 0.0;
  Eigen::VectorXd residuals;
  RowMajorSparse sparse;
  std::string error;
  ASSERT_TRUE(
      Linearize(problem->problem(), ids, &cost, &residuals, &sparse, &error))
      << error;
  const Eigen::MatrixXd j = sparse;
  const Eigen::VectorXd g = j.transpose() * residuals;
  *decrease = 0.5 * g.dot((j.transpose() * j).ldlt().solve(g));
}

// g^T H^-1 g / 2 away from the minimum (landmarks 0.3 m off, nothing
// solved): WNOA states through the envelope, few feature weights through
// H's Schur form, and 200 + 200 + 200 weights seen four times a pose
// through the envelope (3 rows a time) give the dense value to rounding;
// the same weights seen once a pose, where neither the envelope nor the
// Schur form costs less than the conjugate gradients' bound, a lower bound
// from those (measured 0.41% below).
TEST(GaussNewtonDecreaseTest, IsTheDenseValueOrABoundBelowIt) {
  struct Case {
    std::string prior;
    int features;
    bool one_sighting_a_time;
    bool exact;
    double tolerance;
  };
  for (const Case& c :
       {Case{"wnoa", 12, false, true, 1e-9}, Case{"rff", 12, false, true, 1e-9},
        Case{"rff", 200, false, true, 1e-9},
        Case{"rff", 200, true, false, 1e-2}}) {
    SlamOptions options;
    options.prior = c.prior;
    options.features.num_position_features = c.features;
    options.features.num_heading_features = c.features;
    SmallProblem built;
    ASSERT_NO_FATAL_FAILURE(
        BuildSmallProblem(4, options, &built, c.one_sighting_a_time));
    SlamProblem& problem = *built.problem;
    double dense;
    ASSERT_NO_FATAL_FAILURE(DenseDecrease(&problem, &dense));
    bool exact = !c.exact;
    const double decrease = GaussNewtonDecrease(&problem, &exact);
    EXPECT_EQ(exact, c.exact) << c.prior << " " << c.features;
    std::printf("%s, %d features: %d parameters, decrease %.9g, dense %.9g\n",
                c.prior.c_str(), c.features, problem.problem()->NumParameters(),
                decrease, dense);
    EXPECT_GT(dense, 1.0) << c.prior;
    EXPECT_LE(decrease, dense * (1.0 + 1e-9)) << c.prior;
    EXPECT_NEAR(decrease, dense, c.tolerance * dense) << c.prior;
  }
}

// A WNOA problem solved with BANDED_CHOLESKY, which leaves its linearisation.
struct SolvedWnoaProblem : SmallProblem {
  SolverOptions solver;
  ceres::Solver::Options ceres_options;

  SlamResult Solve() {
    SlamResult result;
    std::string error;
    EXPECT_TRUE(RunSolve(solver, ceres_options, problem.get(), &result, &error,
                         /*keep_linearization=*/true))
        << error;
    return result;
  }
};

std::unique_ptr<SolvedWnoaProblem> SolvedWnoa() {
  auto solved = std::make_unique<SolvedWnoaProblem>();
  SlamOptions options;
  options.prior = "wnoa";
  BuildSmallProblem(6, options, solved.get());
  solved->solver.linear_solver = "BANDED_CHOLESKY";
  std::string error;
  EXPECT_TRUE(ToCeresOptions(solved->solver, &solved->ceres_options, &error))
      << error;
  return solved;
}

void ExpectSameSystem(const BandedSystem& a, const BandedSystem& b) {
  ASSERT_EQ(a.x.size(), b.x.size());
  EXPECT_TRUE((a.x.array() == b.x.array()).all());
  EXPECT_TRUE((a.gradient.array() == b.gradient.array()).all());
  ASSERT_EQ(a.factor->num_entries(), b.factor->num_entries());
  for (int i = 0; i < a.factor->size(); ++i) {
    for (int j = a.factor->first(i); j <= i; ++j) {
      ASSERT_EQ((*a.factor)(i, j), (*b.factor)(i, j)) << i << ", " << j;
    }
  }
}

// The solve's own H is the one a new linearisation at its values gives, bit
// for bit; it is taken once, and only while values and blocks are the same.
TEST(FactorizeBandedTest, TakesTheSolvesLinearizationOnlyWhileItHolds) {
  const std::unique_ptr<SolvedWnoaProblem> solved = SolvedWnoa();
  ASSERT_NE(solved->problem, nullptr);
  SlamProblem& problem = *solved->problem;
  BandedLinearization taken;
  EXPECT_FALSE(problem.TakeLinearization(&taken));  // Nothing solved yet.
  // A solve not asked to keep it (an incremental update) keeps none; asked
  // (below), the same solve does.
  SlamResult unkept;
  std::string error;
  ASSERT_TRUE(RunSolve(solved->solver, solved->ceres_options, &problem, &unkept,
                       &error))
      << error;
  EXPECT_FALSE(problem.has_linearization());

  solved->Solve();
  ASSERT_TRUE(problem.has_linearization());
  BandedSystem kept, fresh;
  ASSERT_TRUE(FactorizeBanded(&problem, &kept));
  EXPECT_FALSE(problem.has_linearization());  // Taken by the first.
  ASSERT_TRUE(FactorizeBanded(&problem, &fresh));
  ExpectSameSystem(kept, fresh);

  solved->Solve();
  ASSERT_TRUE(problem.TakeLinearization(&taken));
  ASSERT_NE(taken.hessian, nullptr);
  EXPECT_TRUE((taken.x.array() == taken.banded->Gather().array()).all());

  // Moved values, a block held constant, or a constant block moved, leave
  // it unused.
  double* landmark =
      problem.landmark_block(solved->dataset.ground_truth_landmarks.front().id);
  ASSERT_NE(landmark, nullptr);
  for (const int change : {0, 1, 2}) {
    solved->Solve();
    ASSERT_TRUE(problem.has_linearization()) << change;
    if (change == 0) landmark[0] += 1e-3;
    if (change == 1) problem.problem()->SetParameterBlockConstant(landmark);
    if (change == 2) landmark[1] += 1e-3;  // Constant since change 1.
    EXPECT_FALSE(problem.TakeLinearization(&taken)) << change;
    EXPECT_FALSE(problem.has_linearization()) << change;
  }
}

// The tolerance reaches the loop from the solver options: with a large one
// an early undamped step ends the solve, with 0 Ceres's rules do.
TEST(FactorizeBandedTest, DecrementToleranceReachesTheBandedLoop) {
  SlamResult result[2];
  for (const int cut : {0, 1}) {
    const std::unique_ptr<SolvedWnoaProblem> solved = SolvedWnoa();
    ASSERT_NE(solved->problem, nullptr);
    solved->ceres_options.initial_trust_region_radius = 1e8;
    solved->solver.decrement_tolerance = cut ? 1e9 : 0.0;
    result[cut] = solved->Solve();
  }
  const std::string rule = "Gauss-Newton decrement tolerance reached";
  EXPECT_NE(result[0].summary.message.rfind(rule, 0), 0u);
  EXPECT_EQ(result[1].summary.message.rfind(rule, 0), 0u)
      << result[1].summary.message;
  EXPECT_LT(result[1].summary.num_successful_steps + 2,
            result[0].summary.num_successful_steps);
}

// Feature windows solved by BANDED_CHOLESKY leave their H too: the
// decrease is then exact (the dense value to rounding), and the variance
// components' traces come from the same probes through the envelope as
// through the sparse path.
TEST(FactorizeBandedTest, FeatureWindowsSolvedBandedLeaveTheirH) {
  SlamOptions options;
  options.prior = "rff";
  // Blocks narrower than a panel's: without a kept H the dense reduced
  // system is the cheaper (ceres_solve.h, StepWork).
  options.features.num_position_features = 4;
  options.features.num_heading_features = 4;
  options.features.segment_length = 20.0;  // Three windows of 60 s.
  options.features.segment_overlap = 6.0;
  SmallProblem built;
  ASSERT_NO_FATAL_FAILURE(BuildSmallProblem(4, options, &built));
  SlamProblem& problem = *built.problem;
  SolverOptions solver;
  solver.linear_solver = "BANDED_CHOLESKY";
  solver.max_iterations = 2;  // Short of the minimum: a decrease is left.
  ceres::Solver::Options ceres_options;
  std::string error;
  ASSERT_TRUE(ToCeresOptions(solver, &ceres_options, &error)) << error;
  auto solve = [&] {
    SlamResult result;
    EXPECT_TRUE(RunSolve(solver, ceres_options, &problem, &result, &error,
                         /*keep_linearization=*/true))
        << error;
  };
  solve();
  ASSERT_TRUE(problem.has_linearization());

  double dense;
  ASSERT_NO_FATAL_FAILURE(DenseDecrease(&problem, &dense));
  bool exact = false;
  const double decrease = GaussNewtonDecrease(&problem, &exact);
  EXPECT_TRUE(exact);
  EXPECT_GT(dense, 1.0);
  EXPECT_NEAR(decrease, dense, 1e-9 * dense);
  // Without the kept H the feature model's Schur form gives it again.
  exact = false;
  EXPECT_NEAR(GaussNewtonDecrease(&problem, &exact), dense, 1e-9 * dense);
  EXPECT_TRUE(exact);

  // The envelope serves the traces while the kept H holds (BandedTraces
  // factorises it first), the sparse path after.
  solve();
  BandedSystem system;
  ASSERT_TRUE(FactorizeBanded(&problem, &system));
  solve();
  VarianceComponents banded, through_sparse;
  ASSERT_TRUE(EstimateVarianceComponents(&problem, VarianceComponentOptions(),
                                         &banded, &error))
      << error;
  ASSERT_FALSE(FactorizeBanded(&problem, &system));
  ASSERT_TRUE(EstimateVarianceComponents(&problem, VarianceComponentOptions(),
                                         &through_sparse, &error))
      << error;
  int estimated = 0;
  for (int group = 0; group < kNumVarianceGroups; ++group) {
    const VarianceComponent& a = banded[group];
    const VarianceComponent& b = through_sparse[group];
    EXPECT_EQ(a.rows, b.rows) << group;
    EXPECT_NEAR(a.sum_squares, b.sum_squares, 1e-9 * (1.0 + b.sum_squares))
        << group;
    EXPECT_NEAR(a.redundancy, b.redundancy, 1e-9 * (1.0 + b.rows)) << group;
    estimated += b.estimated;
  }
  EXPECT_NEAR(banded.log_det_hessian, through_sparse.log_det_hessian,
              1e-9 * std::abs(through_sparse.log_det_hessian));
  EXPECT_GE(estimated, 2);
}

}  // namespace
}  // namespace rff
