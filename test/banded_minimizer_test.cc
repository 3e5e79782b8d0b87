#include "rff_ceres/banded_minimizer.h"

#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <vector>

#include "ceres/autodiff_cost_function.h"
#include "ceres/ceres.h"
#include "costs/pose_map.h"
#include "costs/pose_prior_cost.h"
#include "costs/range_bearing_cost.h"
#include "gtest/gtest.h"
#include "rff_ceres/banded_problem.h"
#include "rff_ceres/envelope_cholesky.h"

namespace rff {
namespace {

// r = (p_{k+1} - 2 p_k + p_{k-1}) / sigma: a smooth chain of 2D points.
struct SecondDifference {
  template <typename T>
  bool operator()(const T* a, const T* b, const T* c, T* r) const {
    for (int i = 0; i < 2; ++i) r[i] = (a[i] - 2.0 * b[i] + c[i]) / 0.1;
    return true;
  }
};

// r = (|p - l| - range) / sigma: nonlinear in both blocks.
struct Range {
  double range;
  template <typename T>
  bool operator()(const T* p, const T* l, T* r) const {
    const T dx = p[0] - l[0], dy = p[1] - l[1];
    r[0] = (sqrt(dx * dx + dy * dy) - range) / 0.05;
    return true;
  }
};

// r = (p - mean) / sigma.
struct Prior {
  double x, y, sigma;
  template <typename T>
  bool operator()(const T* p, T* r) const {
    r[0] = (p[0] - x) / sigma;
    r[1] = (p[1] - y) / sigma;
    return true;
  }
};

// A time-ordered problem: `n` points on a curve, ranges to 3 landmarks
// from every point, or with `local` to landmark j from the j-th third of
// the run only (every 7th `outlier` m off, under `loss`), priors on the
// first point and the landmarks; started away from the truth, the
// landmarks `landmark_error` m off.
struct ChainProblem {
  std::vector<Eigen::Vector2d> points, landmarks;
  std::unique_ptr<ceres::Problem> problem;

  ChainProblem(int n, ceres::LossFunction* loss, double outlier = 0.0,
               bool local = false, double landmark_error = 0.5) {
    ceres::Problem::Options options;
    options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    problem = std::make_unique<ceres::Problem>(options);
    const std::vector<Eigen::Vector2d> truth_landmarks = {
        {0.0, 5.0}, {8.0, -3.0}, {4.0, 9.0}};
    points.resize(n);
    landmarks = truth_landmarks;
    for (Eigen::Vector2d& l : landmarks) {
      l += landmark_error * Eigen::Vector2d(0.8, -0.6);
    }
    for (int k = 0; k < n; ++k) {
      const double t = 0.1 * k;
      const Eigen::Vector2d truth(t, std::sin(t));
      points[k] = truth + Eigen::Vector2d(0.3 * std::cos(3.0 * t), 0.2);
      for (int j = 0; j < 3; ++j) {
        if (local && (3 * k < j * n || 3 * k >= (j + 1) * n)) continue;
        const double range = (truth - truth_landmarks[j]).norm() +
                             (k % 7 == 3 ? outlier : 0.01 * std::sin(k + j));
        problem->AddResidualBlock(
            new ceres::AutoDiffCostFunction<Range, 1, 2, 2>(new Range{range}),
            loss, points[k].data(), landmarks[j].data());
      }
    }
    for (int k = 1; k + 1 < n; ++k) {
      problem->AddResidualBlock(
          new ceres::AutoDiffCostFunction<SecondDifference, 2, 2, 2, 2>(
              new SecondDifference),
          nullptr, points[k + 1].data(), points[k].data(),
          points[k - 1].data());
    }
    problem->AddResidualBlock(
        new ceres::AutoDiffCostFunction<Prior, 2, 2>(new Prior{0.0, 0.0, 0.01}),
        nullptr, points[0].data());
    for (int j = 0; j < 3; ++j) {
      problem->AddResidualBlock(
          new ceres::AutoDiffCostFunction<Prior, 2, 2>(
              new Prior{truth_landmarks[j].x(), truth_landmarks[j].y(), 1.0}),
          nullptr, landmarks[j].data());
    }
  }

  // Landmarks last, or each placed after its sightings.
  BandedColumns Columns(bool place_landmarks = false) {
    BandedColumns columns;
    for (Eigen::Vector2d& p : points) columns.timed.push_back(p.data());
    for (Eigen::Vector2d& l : landmarks) {
      (place_landmarks ? columns.placed : columns.last).push_back(l.data());
    }
    return columns;
  }

  Eigen::VectorXd Values() const {
    Eigen::VectorXd v(2 * (points.size() + landmarks.size()));
    int i = 0;
    for (const auto* set : {&points, &landmarks}) {
      for (const Eigen::Vector2d& p : *set) v.segment<2>(2 * i++) = p;
    }
    return v;
  }
};

ceres::Solver::Options SparseCholesky() {
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  options.max_num_iterations = 100;
  options.function_tolerance = 1e-10;
  return options;
}

// `problem` laid out as `columns` and minimised by the banded loop.
void Minimize(const ceres::Solver::Options& options,
              const BandedColumns& columns, ceres::Problem* problem,
              ceres::Solver::Summary* summary,
              double decrement_tolerance = 0.0) {
  BandedProblem banded(*problem, columns);
  MinimizeBanded(options, &banded, problem, summary, decrement_tolerance);
}

// The envelope's size with `problem` laid out as `columns`.
BandedSize SizeOf(const ceres::Problem& problem, const BandedColumns& columns) {
  return BandedProblem(problem, columns).Size();
}

// Ceres's own trust-region loop and the banded one take the same steps:
// iteration by iteration the same acceptance, cost, step quality and
// radius. Returns the banded summary.
ceres::Solver::Summary ExpectSameAsCeres(
    ceres::LossFunction* loss, double outlier, bool local = false,
    double landmark_error = 0.5,
    const std::function<void(ChainProblem*)>& adjust = nullptr) {
  ChainProblem ceres_side(80, loss, outlier, local, landmark_error),
      banded_side(80, loss, outlier, local, landmark_error);
  if (adjust) {
    adjust(&ceres_side);
    adjust(&banded_side);
  }
  ceres::Solver::Summary expected, actual;
  ceres::Solve(SparseCholesky(), ceres_side.problem.get(), &expected);
  std::string why;
  EXPECT_TRUE(
      BandedSolvable(*banded_side.problem, banded_side.Columns(local), &why))
      << why;
  Minimize(SparseCholesky(), banded_side.Columns(local),
           banded_side.problem.get(), &actual);
  EXPECT_EQ(expected.termination_type, ceres::CONVERGENCE) << expected.message;
  EXPECT_EQ(actual.termination_type, expected.termination_type);
  EXPECT_EQ(actual.num_successful_steps, expected.num_successful_steps);
  EXPECT_EQ(actual.num_unsuccessful_steps, expected.num_unsuccessful_steps);
  EXPECT_EQ(actual.iterations.size(), expected.iterations.size());
  for (std::size_t i = 0;
       i < std::min(actual.iterations.size(), expected.iterations.size());
       ++i) {
    const ceres::IterationSummary& a = actual.iterations[i];
    const ceres::IterationSummary& e = expected.iterations[i];
    EXPECT_EQ(a.step_is_successful, e.step_is_successful) << i;
    EXPECT_NEAR(a.cost, e.cost, 1e-9 * e.cost) << i;
    // Near convergence the cost change is a difference of nearly equal
    // costs, and its ratio to the model's decrease carries their rounding.
    if (std::abs(e.cost_change) > 1e-6 * e.cost) {
      EXPECT_NEAR(a.relative_decrease, e.relative_decrease, 1e-6) << i;
    }
    EXPECT_NEAR(a.trust_region_radius, e.trust_region_radius,
                1e-6 * e.trust_region_radius)
        << i;
  }
  EXPECT_NEAR(actual.final_cost, expected.final_cost,
              1e-9 * expected.final_cost);
  const Eigen::VectorXd a = banded_side.Values(), e = ceres_side.Values();
  EXPECT_LT((a - e).lpNorm<Eigen::Infinity>(), 1e-9);
  // The solve moved far from the start: the comparison is not vacuous.
  EXPECT_GT(
      (e - ChainProblem(80, loss, outlier, local, landmark_error).Values())
          .lpNorm<Eigen::Infinity>(),
      0.2);
  return actual;
}

TEST(BandedMinimizerTest, MatchesCeresWithoutALoss) {
  ExpectSameAsCeres(nullptr, 0.0);
}

TEST(BandedMinimizerTest, MatchesCeresWithCauchysClampedCorrection) {
  ceres::CauchyLoss loss(1.0);
  ExpectSameAsCeres(&loss, 2.0);
}

// TolerantLoss has rho'' > 0: the full second-order (Triggs) correction.
TEST(BandedMinimizerTest, MatchesCeresWithTheFullCorrection) {
  ceres::TolerantLoss loss(4.0, 1.0);
  ExpectSameAsCeres(&loss, 0.0);
}

// Landmarks started 6 m off: the first steps overshoot and are rejected,
// the radius shrinks and grows again as Ceres's does.
TEST(BandedMinimizerTest, MatchesCeresThroughRejectedSteps) {
  const ceres::Solver::Summary summary =
      ExpectSameAsCeres(nullptr, 0.0, false, /*landmark_error=*/6.0);
  EXPECT_GT(summary.num_unsuccessful_steps, 0);
}

// Landmarks seen from a third of the run each, placed after their
// sightings: the same steps, and an envelope that no longer spans the run.
TEST(BandedMinimizerTest, MatchesCeresWithLandmarksPlacedAfterTheirSightings) {
  ExpectSameAsCeres(nullptr, 0.0, /*local=*/true);
  ChainProblem chain(90, nullptr, 0.0, /*local=*/true);
  std::string why;
  ASSERT_TRUE(BandedSolvable(*chain.problem, chain.Columns(true), &why));
  const BandedSize placed = SizeOf(*chain.problem, chain.Columns(true));
  const BandedSize last = SizeOf(*chain.problem, chain.Columns(false));
  // The points' rows: 1 + 2 + 3 + 4 + 88 * (5 + 6) = 978. Last, landmark
  // j's rows reach back to its first sighting: 181 + 182, 123 + 124,
  // 65 + 66. Placed, each spans its 30 points (61 + 62), and the two points
  // after it reach back over it (8 more each, the last landmark has none).
  EXPECT_EQ(last.entries, 978 + 741);
  EXPECT_EQ(placed.entries, 978 + 3 * 123 + 2 * 8);
}

// Constant blocks, a residual on constant blocks only (cost 5e5, which
// Ceres keeps out of its tolerance tests as the fixed cost) and a block in
// no residual (Ceres drops it; in the parameter norm it would stop the
// solve early): the same steps as Ceres.
TEST(BandedMinimizerTest, MatchesCeresWithFixedCostAndAnUnusedBlock) {
  auto build = [](ChainProblem* chain, Eigen::Vector2d* unused) {
    for (int k = 0; k < 5; ++k) {
      chain->problem->SetParameterBlockConstant(chain->points[k].data());
    }
    chain->problem->AddResidualBlock(
        new ceres::AutoDiffCostFunction<Prior, 2, 2>(new Prior{1e3, 0.0, 1.0}),
        nullptr, chain->points[0].data());
    chain->problem->AddParameterBlock(unused->data(), 2);
  };
  ChainProblem ceres_side(60, nullptr), banded_side(60, nullptr);
  Eigen::Vector2d ceres_unused(1e6, 1e6), banded_unused(1e6, 1e6);
  build(&ceres_side, &ceres_unused);
  build(&banded_side, &banded_unused);
  ceres::Solver::Summary expected, actual;
  ceres::Solver::Options options = SparseCholesky();
  options.function_tolerance = 1e-8;
  ceres::Solve(options, ceres_side.problem.get(), &expected);
  BandedColumns columns = banded_side.Columns();
  columns.last.push_back(banded_unused.data());
  Minimize(options, columns, banded_side.problem.get(), &actual);
  ASSERT_EQ(expected.termination_type, ceres::CONVERGENCE);
  EXPECT_EQ(actual.termination_type, ceres::CONVERGENCE);
  EXPECT_EQ(actual.iterations.size(), expected.iterations.size());
  EXPECT_NEAR(actual.fixed_cost, expected.fixed_cost, 1e-9);
  EXPECT_GT(actual.fixed_cost, 4e5);
  EXPECT_NEAR(actual.final_cost, expected.final_cost,
              1e-9 * expected.final_cost);
  EXPECT_LT(
      (banded_side.Values() - ceres_side.Values()).lpNorm<Eigen::Infinity>(),
      1e-9);
  EXPECT_EQ(banded_unused, Eigen::Vector2d(1e6, 1e6));
}

// Outliers at the knee of a Cauchy loss: a long tail of small steps (21,
// each a third of the one before: the Gauss-Newton model's surplus
// curvature there), which the decrement tolerance cuts once the steps are
// undamped, within it of the minimum; while the damping still counts (the
// radius capped) it waits.
TEST(BandedMinimizerTest, StopsAtTheDecrementToleranceOnceUndamped) {
  ceres::CauchyLoss loss(1.0);
  ceres::Solver::Options options = SparseCholesky();
  options.function_tolerance = 1e-12;
  options.parameter_tolerance = 1e-12;
  options.initial_trust_region_radius = 1e8;
  auto solve = [&](double tolerance, ceres::Solver::Summary* summary) {
    ChainProblem chain(80, &loss, 0.08);
    Minimize(options, chain.Columns(), chain.problem.get(), summary, tolerance);
  };
  ceres::Solver::Summary full, cut, damped, damped_full;
  solve(0.0, &full);
  solve(1e-3, &cut);
  ASSERT_EQ(full.termination_type, ceres::CONVERGENCE);
  EXPECT_EQ(full.message.rfind("Function tolerance reached", 0), 0u)
      << full.message;
  EXPECT_EQ(cut.termination_type, ceres::CONVERGENCE);
  EXPECT_EQ(cut.message.rfind("Gauss-Newton decrement tolerance reached", 0),
            0u)
      << cut.message;
  EXPECT_LT(cut.iterations.size() + 3, full.iterations.size());
  EXPECT_GE(cut.final_cost, full.final_cost);
  EXPECT_LE(cut.final_cost, full.final_cost + 1e-3);

  options.initial_trust_region_radius = 1e4;
  options.max_trust_region_radius = 1e6;
  solve(0.0, &damped_full);
  solve(1e-3, &damped);
  EXPECT_EQ(damped.iterations.size(), damped_full.iterations.size());
  EXPECT_EQ(damped.message, damped_full.message);
}

TEST(BandedMinimizerTest, NothingToSolveIsConvergedAtTheFixedCost) {
  ChainProblem chain(5, nullptr);
  for (Eigen::Vector2d& p : chain.points) {
    chain.problem->SetParameterBlockConstant(p.data());
  }
  for (Eigen::Vector2d& l : chain.landmarks) {
    chain.problem->SetParameterBlockConstant(l.data());
  }
  ceres::Solver::Summary expected, actual;
  ceres::Solve(SparseCholesky(), chain.problem.get(), &expected);
  Minimize(SparseCholesky(), chain.Columns(), chain.problem.get(), &actual);
  EXPECT_EQ(actual.termination_type, ceres::CONVERGENCE);
  EXPECT_EQ(actual.message, expected.message);
  EXPECT_EQ(actual.iterations.size(), 0u);
  EXPECT_NEAR(actual.final_cost, expected.final_cost,
              1e-12 * expected.final_cost);
  EXPECT_GT(actual.final_cost, 0.0);
}

TEST(BandedMinimizerTest, StopsAtTheIterationCapAndOnACallback) {
  ChainProblem chain(40, nullptr);
  ceres::Solver::Options options = SparseCholesky();
  options.max_num_iterations = 2;
  ceres::Solver::Summary summary;
  Minimize(options, chain.Columns(), chain.problem.get(), &summary);
  EXPECT_EQ(summary.termination_type, ceres::NO_CONVERGENCE);
  EXPECT_EQ(summary.message,
            "Maximum number of iterations reached. Number of iterations: 2.");
  EXPECT_EQ(summary.iterations.size(), 3u);

  struct Abort : ceres::IterationCallback {
    ceres::CallbackReturnType operator()(
        const ceres::IterationSummary& s) override {
      return s.iteration == 1 ? ceres::SOLVER_ABORT : ceres::SOLVER_CONTINUE;
    }
  } abort;
  options = SparseCholesky();
  options.callbacks.push_back(&abort);
  const Eigen::VectorXd start = chain.Values();
  Minimize(options, chain.Columns(), chain.problem.get(), &summary);
  EXPECT_EQ(summary.termination_type, ceres::USER_FAILURE);
  EXPECT_EQ(summary.message, "User callback returned SOLVER_ABORT.");
  EXPECT_EQ(summary.iterations.size(), 2u);
  // A failed solve leaves the starting values, as Ceres does.
  EXPECT_EQ(chain.Values(), start);
}

// Bounds that hold at the solution (point 15's y at most 0.8, where the
// truth has 0.997; landmark 0's x at least 0.3, where it has 0): each step
// clamped onto them as Ceres's ParameterBlock::Plus clamps it, the same
// steps.
TEST(BandedMinimizerTest, MatchesCeresWithBoundsThatHold) {
  auto bound = [](ChainProblem* chain) {
    chain->problem->SetParameterUpperBound(chain->points[15].data(), 1, 0.8);
    chain->problem->SetParameterLowerBound(chain->landmarks[0].data(), 0, 0.3);
  };
  ExpectSameAsCeres(nullptr, 0.0, false, 0.5, bound);
  ChainProblem chain(80, nullptr);
  bound(&chain);
  ceres::Solver::Summary summary;
  Minimize(SparseCholesky(), chain.Columns(), chain.problem.get(), &summary);
  EXPECT_EQ(chain.points[15].y(), 0.8);
  EXPECT_EQ(chain.landmarks[0].x(), 0.3);
}

TEST(BandedMinimizerTest, RefusesAnIncompleteOrder) {
  ChainProblem chain(10, nullptr);
  std::string why;
  BandedColumns columns = chain.Columns();
  columns.last.pop_back();
  EXPECT_FALSE(BandedSolvable(*chain.problem, columns, &why));
  EXPECT_EQ(why, "the columns do not hold every parameter block once");
  columns = chain.Columns();
  columns.last.push_back(columns.timed[0]);
  columns.last.erase(columns.last.begin());
  EXPECT_FALSE(BandedSolvable(*chain.problem, columns, &why));
  EXPECT_EQ(why, "the columns do not hold every parameter block once");
}

TEST(BandedMinimizerTest, SizesTheEnvelopeOfABandWithABorder) {
  ChainProblem chain(10, nullptr);
  std::string why;
  ASSERT_TRUE(BandedSolvable(*chain.problem, chain.Columns(), &why));
  const BandedSize size = SizeOf(*chain.problem, chain.Columns());
  // Point k's rows reach back to point k - 2 (the second differences): row
  // i stores min(i, 4 + i % 2) + 1 columns. Landmarks: full rows.
  std::int64_t expected = 0;
  for (int i = 0; i < 20; ++i) expected += std::min(i, 4 + i % 2) + 1;
  for (int i = 20; i < 26; ++i) expected += i + 1;
  EXPECT_EQ(size.entries, expected);
}

// r = (w_a . c + w_b . d - l_x^2 / 10 - target) / sigma and
// its twin on the landmark's other axis: an observation of a landmark from
// a time in a feature window (w_a, 12 weights) or, with w_b, in the overlap
// of two.
struct WindowObservation {
  double target, phase;
  template <typename T>
  bool Residual(const T* a, const T* b, const T* l, T* r) const {
    T sum_x = -l[0] * l[0] / 10.0, sum_y = a[1] * l[1] / 5.0;
    for (int i = 0; i < 12; ++i) {
      sum_x += a[i] * std::cos(phase + i);
      sum_y += a[i] * std::sin(phase * i);
      if (b != nullptr) {
        sum_x += b[i] * std::sin(phase - i);
        sum_y -= b[i] * std::cos(phase + 2.0 * i);
      }
    }
    r[0] = (sum_x - target) / 0.1;
    r[1] = (sum_y + l[1] - target) / 0.2;
    return true;
  }
  template <typename T>
  bool operator()(const T* a, const T* l, T* r) const {
    return Residual<T>(a, nullptr, l, r);
  }
  template <typename T>
  bool operator()(const T* a, const T* b, const T* l, T* r) const {
    return Residual(a, b, l, r);
  }
};

// r = w / sigma: the weights' whitening prior, 12 rows on one block.
struct WeightPrior {
  template <typename T>
  bool operator()(const T* w, T* r) const {
    for (int i = 0; i < 12; ++i) r[i] = w[i] / 2.0;
    return true;
  }
};

// Windows of 12 weights, as wide as the panel takes (feature windows):
// `per_window` observations from each window and two from each overlap, every
// second one through a Cauchy loss, of landmarks that come and go (each
// with a prior).
struct WindowProblem {
  std::vector<std::vector<double>> windows;
  std::vector<Eigen::Vector2d> landmarks;
  std::unique_ptr<ceres::Problem> problem;
  ceres::CauchyLoss loss{1.0};

  explicit WindowProblem(int n, int per_window = 3)
      : windows(n), landmarks(n / 2 + 1) {
    ceres::Problem::Options options;
    options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    problem = std::make_unique<ceres::Problem>(options);
    for (int k = 0; k < n; ++k) {
      for (int i = 0; i < 12; ++i) windows[k].push_back(0.1 * std::sin(k + i));
      problem->AddResidualBlock(
          new ceres::AutoDiffCostFunction<WeightPrior, 12, 12>(new WeightPrior),
          nullptr, windows[k].data());
    }
    for (std::size_t j = 0; j < landmarks.size(); ++j) {
      landmarks[j] = Eigen::Vector2d(std::cos(j), 1.0 + std::sin(2.0 * j));
      problem->AddResidualBlock(
          new ceres::AutoDiffCostFunction<Prior, 2, 2>(
              new Prior{landmarks[j].x() + 0.3, landmarks[j].y() - 0.2, 1.0}),
          nullptr, landmarks[j].data());
    }
    int count = 0;
    for (int k = 0; k < n; ++k) {
      for (int o = 0; o < per_window + (k + 1 < n ? 2 : 0); ++o, ++count) {
        auto* observation =
            new WindowObservation{std::sin(0.7 * count), 0.3 * count};
        ceres::LossFunction* robust = count % 2 == 0 ? &loss : nullptr;
        double* landmark = landmarks[(k + o % 2) / 2].data();
        if (o < per_window) {
          problem->AddResidualBlock(
              new ceres::AutoDiffCostFunction<WindowObservation, 2, 12, 2>(
                  observation),
              robust, windows[k].data(), landmark);
        } else {  // In the overlap with the next window.
          problem->AddResidualBlock(
              new ceres::AutoDiffCostFunction<WindowObservation, 2, 12, 12, 2>(
                  observation),
              robust, windows[k].data(), windows[k + 1].data(), landmark);
        }
      }
    }
  }

  BandedColumns Columns() {
    BandedColumns columns;
    for (std::vector<double>& w : windows) columns.timed.push_back(w.data());
    for (Eigen::Vector2d& l : landmarks) columns.placed.push_back(l.data());
    return columns;
  }
};

// H, g and the cost `banded` linearises to at its variables' values are
// those of Ceres's own Jacobian of `problem`, in the banded column order.
void ExpectCeresLinearization(ceres::Problem& problem,
                              const BandedColumns& columns,
                              BandedProblem& banded) {
  const Eigen::VectorXd x = banded.Gather();
  EnvelopeMatrix h(banded.envelope_first());
  Eigen::VectorXd g;
  double cost;
  ASSERT_TRUE(banded.Linearize(x, &cost, &g, &h));
  ceres::Problem::EvaluateOptions options;
  options.parameter_blocks = BandedBlockOrder(problem, columns);
  double expected_cost;
  std::vector<double> residuals;
  ceres::CRSMatrix crs;
  ASSERT_TRUE(
      problem.Evaluate(options, &expected_cost, &residuals, nullptr, &crs));
  Eigen::MatrixXd jacobian = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
  for (int r = 0; r < crs.num_rows; ++r) {
    for (int k = crs.rows[r]; k < crs.rows[r + 1]; ++k) {
      jacobian(r, crs.cols[k]) = crs.values[k];
    }
  }
  const Eigen::MatrixXd expected_h = jacobian.transpose() * jacobian;
  const Eigen::VectorXd expected_g =
      jacobian.transpose() *
      Eigen::Map<const Eigen::VectorXd>(residuals.data(), residuals.size());
  EXPECT_NEAR(cost, expected_cost, 1e-12 * expected_cost);
  const double scale = expected_h.cwiseAbs().maxCoeff();
  for (int i = 0; i < banded.num_columns(); ++i) {
    EXPECT_NEAR(g[i], expected_g[i], 1e-12 * scale) << i;
    for (int j = 0; j <= i; ++j) {
      const double stored = j >= h.first(i) ? h(i, j) : 0.0;
      EXPECT_NEAR(stored, expected_h(i, j), 1e-12 * scale) << i << ", " << j;
    }
  }
}

// The panel's products (wide windows' rows multiplied out together) give
// Ceres's own J^T J and J^T r, through the losses' corrections; 150
// observations a window fill the panel past kMaxPanelRows.
TEST(BandedMinimizerTest, PanelProductsAreThoseOfTheJacobian) {
  static_assert(kMinPanelWidth <= 12 && kMaxPanelRows < 2 * 150 + 12);
  WindowProblem windows(12, 150);
  BandedProblem banded(*windows.problem, windows.Columns());
  ASSERT_EQ(banded.num_columns(), 12 * 12 + 2 * 7);
  ExpectCeresLinearization(*windows.problem, windows.Columns(), banded);
}

// Windows of x, y and theta weights (12 each) seen through pose maps, as
// feature trajectories are. At each of 5 times a window: one range-bearing,
// or three of different landmarks, every third under a Cauchy loss (rho''
// < 0) and every third under a tolerant one (rho'' > 0: the full
// correction); at the window's second time also a pose prior; four at the
// last time, blended with the next window's features. The last landmark
// is held constant.
struct PoseWindowProblem {
  static constexpr int kD = 12;
  std::vector<std::vector<double>> weights;  // x, y, theta of each window.
  std::vector<Eigen::Vector2d> landmarks;
  std::unique_ptr<ceres::Problem> problem;
  ceres::CauchyLoss cauchy{1.0};
  ceres::TolerantLoss tolerant{0.5, 0.5};

  explicit PoseWindowProblem(int n) : weights(3 * n), landmarks(4) {
    ceres::Problem::Options options;
    options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    problem = std::make_unique<ceres::Problem>(options);
    for (std::size_t b = 0; b < weights.size(); ++b) {
      for (int i = 0; i < kD; ++i) weights[b].push_back(0.05 * std::sin(b + i));
    }
    for (std::size_t j = 0; j < landmarks.size(); ++j) {
      landmarks[j] = 4.0 * Eigen::Vector2d(std::cos(j), std::sin(j));
    }
    int count = 0;
    for (int k = 0; k < n; ++k) {
      for (int t = 0; t < 5; ++t) {
        PoseMap map;
        map.mean = Eigen::Vector3d(0.1 * k, 0.2, 0.3);
        const bool blended = t == 4 && k + 1 < n;
        std::vector<double*> blocks;
        for (int w = k; w <= (blended ? k + 1 : k); ++w) {
          auto position = std::make_shared<Eigen::VectorXd>(kD);
          auto heading = std::make_shared<Eigen::VectorXd>(kD);
          for (int i = 0; i < kD; ++i) {
            (*position)[i] = std::cos(0.3 * (5 * k + t) + i + w);
            (*heading)[i] = std::sin(0.2 * (5 * k + t) - i + w);
          }
          const int first = 3 * (w - k);
          map.terms.push_back({first, 0, position});
          map.terms.push_back({first + 1, 1, position});
          map.terms.push_back({first + 2, 2, heading});
          for (int c = 0; c < 3; ++c)
            blocks.push_back(weights[3 * w + c].data());
        }
        if (t == 1) {
          problem->AddResidualBlock(
              new PosePriorCost(map, Eigen::Vector3d(0.1 * k, 0.2, 0.3),
                                Eigen::Vector3d(0.5, 0.5, 0.1)),
              nullptr, blocks);
        }
        const int costs = t % 3 == 0 ? 1 : (t == 4 ? 4 : 3);
        for (int o = 0; o < costs; ++o, ++count) {
          ceres::LossFunction* losses[] = {nullptr, &cauchy, &tolerant};
          blocks.push_back(landmarks[(k + o) % landmarks.size()].data());
          problem->AddResidualBlock(
              new RangeBearingCost(map, 3.0 + 0.1 * std::sin(count),
                                   0.2 * std::cos(count), 0.1, 0.05),
              losses[count % 3], blocks);
          blocks.pop_back();
        }
      }
    }
    problem->SetParameterBlockConstant(landmarks.back().data());
  }

  BandedColumns Columns() {
    BandedColumns columns;
    for (std::vector<double>& w : weights) columns.timed.push_back(w.data());
    for (Eigen::Vector2d& l : landmarks) columns.placed.push_back(l.data());
    return columns;
  }
};

// Costs at one time with more than 3 rows in all enter the panel as at
// most 3 rows; H and g stay Ceres's.
TEST(BandedMinimizerTest, CompressedPoseRunsGiveTheProductsOfTheJacobian) {
  static_assert(kMinPanelWidth <= PoseWindowProblem::kD);
  PoseWindowProblem windows(6);
  BandedProblem banded(*windows.problem, windows.Columns());
  // The times with three or four range-bearings (6 or 8 rows; 9 with the
  // pose prior) each make a run; those with one (2 rows) are left.
  EXPECT_EQ(banded.compressed_runs(), 6 * 3);
  ExpectCeresLinearization(*windows.problem, windows.Columns(), banded);
}

// A linearisation that fails part way (a weight of the last window not
// finite) leaves rows in the panel; the next one starts clean: the same H
// and g bit for bit as a layout that never failed.
TEST(BandedMinimizerTest, APanelLeftByAFailedLinearizationIsDropped) {
  WindowProblem windows(6, 40);
  BandedProblem banded(*windows.problem, windows.Columns()),
      clean(*windows.problem, windows.Columns());
  const Eigen::VectorXd x = banded.Gather();
  Eigen::VectorXd bad = x, g, expected_g;
  bad[5 * 12] = std::numeric_limits<double>::quiet_NaN();
  EnvelopeMatrix h(banded.envelope_first()), expected_h(clean.envelope_first());
  double cost, expected_cost;
  ASSERT_FALSE(banded.Linearize(bad, &cost, &g, &h));
  ASSERT_TRUE(banded.Linearize(x, &cost, &g, &h));
  ASSERT_TRUE(clean.Linearize(x, &expected_cost, &expected_g, &expected_h));
  EXPECT_EQ(cost, expected_cost);
  EXPECT_TRUE((g.array() == expected_g.array()).all());
  for (int i = 0; i < h.size(); ++i) {
    for (int j = h.first(i); j <= i; ++j) {
      ASSERT_EQ(h(i, j), expected_h(i, j)) << i << ", " << j;
    }
  }
}

// And the banded loop takes Ceres's steps on it.
TEST(BandedMinimizerTest, MatchesCeresOnFeatureWindows) {
  WindowProblem ceres_side(12), banded_side(12);
  ceres::Solver::Summary expected, actual;
  ceres::Solve(SparseCholesky(), ceres_side.problem.get(), &expected);
  Minimize(SparseCholesky(), banded_side.Columns(), banded_side.problem.get(),
           &actual);
  EXPECT_EQ(expected.termination_type, ceres::CONVERGENCE) << expected.message;
  EXPECT_EQ(actual.termination_type, expected.termination_type);
  EXPECT_EQ(actual.iterations.size(), expected.iterations.size());
  // Not vacuous: 1894 -> 59 in 88 iterations.
  EXPECT_GT(expected.iterations.size(), 50u);
  EXPECT_LT(expected.final_cost, 0.05 * expected.initial_cost);
  EXPECT_NEAR(actual.final_cost, expected.final_cost,
              1e-9 * expected.final_cost);
  for (std::size_t k = 0; k < ceres_side.windows.size(); ++k) {
    for (int i = 0; i < 12; ++i) {
      EXPECT_NEAR(banded_side.windows[k][i], ceres_side.windows[k][i], 1e-9)
          << k << " " << i;
    }
  }
}

}  // namespace
}  // namespace rff
