#include "costs/folded_prior_cost.h"

#include <random>
#include <vector>

#include "ceres/cost_function.h"
#include "gtest/gtest.h"
#include "rff_ceres/folded_prior.h"
#include "test/costs/cost_test_util.h"

namespace rff {
namespace {

struct FoldedPriorAutoDiff {
  Eigen::MatrixXd a;
  Eigen::VectorXd offset;
  double constant;
  std::vector<int> sizes;
  template <typename T>
  bool operator()(T const* const* p, T* r) const {
    for (int i = 0; i < a.rows(); ++i) {
      r[i] = T(-offset[i]);
      int column = 0;
      for (std::size_t j = 0; j < sizes.size(); ++j) {
        for (int k = 0; k < sizes[j]; ++k) {
          r[i] += a(i, column + k) * p[j][k];
        }
        column += sizes[j];
      }
    }
    r[a.rows()] = T(constant);
    return true;
  }
};

TEST(FoldedPriorCostTest, AnalyticJacobianMatchesAutoDiff) {
  std::mt19937 rng(3);
  const std::vector<int> sizes = {2, 3, 2};
  const Eigen::MatrixXd a = Eigen::MatrixXd::Random(5, 7);
  const Eigen::VectorXd offset = Eigen::VectorXd::Random(5);
  const FoldedPriorCost cost(a, offset, 0.7, sizes);
  auto autodiff = testing::MakeAutoDiff(
      new FoldedPriorAutoDiff{a, offset, 0.7, sizes}, cost);
  testing::ExpectSameCost(
      cost, *autodiff,
      testing::RandomParameters(cost.parameter_block_sizes(), &rng));
}

// Linear residuals r_i = A_i x - z_i are their own Gauss-Newton quadratic:
// folded at any points, in any order, beside a block held constant, the
// prior's cost is theirs everywhere.
TEST(FoldedPriorTest, LinearResidualsFoldExactly) {
  std::mt19937 rng(11);
  std::normal_distribution<double> normal;
  // Blocks: a "pose" held constant (3), two landmarks (2), a calibration (2),
  // at coordinates far from zero (the sums must not cancel there).
  std::vector<std::vector<double>> values = {
      {5.0, -2.0, 0.3}, {310.0, -95.0}, {-240.0, 120.0}, {1.0, 0.05}};
  const std::vector<int> sizes = {3, 2, 2, 2};
  struct Residual {
    std::vector<int> blocks;
    std::vector<Eigen::MatrixXd> a;
    Eigen::VectorXd z;
  };
  std::vector<Residual> residuals;
  for (int i = 0; i < 12; ++i) {
    Residual r;
    r.blocks = {0, 1 + i % 2, 3};
    for (const int b : r.blocks) {
      r.a.push_back(Eigen::MatrixXd::Random(2, sizes[b]));
    }
    r.z = Eigen::VectorXd::Random(2) * 100.0;
    residuals.push_back(r);
  }
  auto evaluate = [&](const Residual& r) {
    Eigen::VectorXd e = -r.z;
    for (std::size_t k = 0; k < r.blocks.size(); ++k) {
      e += r.a[k] * Eigen::Map<const Eigen::VectorXd>(
                        values[r.blocks[k]].data(), sizes[r.blocks[k]]);
    }
    return e;
  };
  auto total = [&] {
    double cost = 0.0;
    for (const Residual& r : residuals) cost += 0.5 * evaluate(r).squaredNorm();
    return cost;
  };
  FoldedPrior prior;
  auto fold = [&](const Residual& r) {
    std::vector<double*> blocks;
    std::vector<int> block_sizes;
    std::vector<double*> jacobians;
    std::vector<
        Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>
        rows;
    for (std::size_t k = 0; k < r.blocks.size(); ++k) {
      blocks.push_back(values[r.blocks[k]].data());
      block_sizes.push_back(sizes[r.blocks[k]]);
      rows.emplace_back(r.a[k]);
    }
    for (std::size_t k = 0; k < r.blocks.size(); ++k) {
      jacobians.push_back(r.blocks[k] == 0 ? nullptr : rows[k].data());
    }
    const Eigen::VectorXd e = evaluate(r);
    prior.Add(blocks, block_sizes, jacobians, e.data(), 2,
              0.5 * e.squaredNorm());
  };
  auto move = [&] {
    for (int b = 1; b < 4; ++b) {
      for (double& v : values[b]) v += normal(rng);
    }
  };
  // Half folded at one point, the rest at another.
  for (int i = 0; i < 6; ++i) fold(residuals[i]);
  move();
  for (int i = 6; i < 12; ++i) fold(residuals[i]);
  ASSERT_EQ(prior.num_folded(), 12);
  // The constant block stays out: landmarks and calibration, 6 columns.
  ASSERT_EQ(prior.blocks().size(), 3u);
  EXPECT_EQ(prior.blocks()[0], values[1].data());
  const std::unique_ptr<FoldedPriorCost> cost = prior.MakeCost();
  for (int trial = 0; trial < 5; ++trial) {
    move();
    std::vector<const double*> at;
    for (double* block : prior.blocks()) at.push_back(block);
    std::vector<double> r(cost->num_residuals());
    ASSERT_TRUE(cost->Evaluate(at.data(), r.data(), nullptr));
    const double folded =
        0.5 * Eigen::Map<Eigen::VectorXd>(r.data(), r.size()).squaredNorm();
    EXPECT_NEAR(folded, total(), 1e-9 * total()) << "trial " << trial;
  }
}

}  // namespace
}  // namespace rff
