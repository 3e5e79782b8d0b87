// Shared scaffolding of the cost tests: random pose maps, an automatic
// differentiation twin of every cost (written independently of the analytic
// code), and a comparison of residuals and Jacobians.
#ifndef RFF_TEST_COSTS_COST_TEST_UTIL_H_
#define RFF_TEST_COSTS_COST_TEST_UTIL_H_

#include <memory>
#include <random>
#include <utility>
#include <vector>

#include "Eigen/Core"
#include "ceres/cost_function.h"
#include "ceres/dynamic_autodiff_cost_function.h"
#include "costs/pose_map.h"
#include "gtest/gtest.h"

namespace rff {
namespace testing {

// Block sizes of the random maps: x and y weights, heading weights.
inline std::vector<int> RandomBlockSizes() { return {5, 5, 4}; }

// A pose map over blocks {0, 1, 2} with random features, where block 0 also
// feeds y (so the Jacobian accumulation over several terms is exercised).
inline PoseMap RandomPoseMap(std::mt19937* rng) {
  std::normal_distribution<double> normal;
  auto random_vector = [&](int n) {
    auto v = std::make_shared<Eigen::VectorXd>(n);
    for (int i = 0; i < n; ++i) (*v)(i) = normal(*rng);
    return std::shared_ptr<const Eigen::VectorXd>(v);
  };
  PoseMap map;
  map.mean << 3.0 * normal(*rng), 3.0 * normal(*rng), normal(*rng);
  const std::vector<int> sizes = RandomBlockSizes();
  map.terms.push_back({0, 0, random_vector(sizes[0])});
  map.terms.push_back({1, 1, random_vector(sizes[1])});
  map.terms.push_back({2, 2, random_vector(sizes[2])});
  map.terms.push_back({0, 1, random_vector(sizes[0])});
  return map;
}

// The pose of `map` for any scalar type (the autodiff twin of EvaluatePose).
template <typename T>
Eigen::Matrix<T, 3, 1> PoseOf(const PoseMap& map, T const* const* p) {
  Eigen::Matrix<T, 3, 1> pose = map.mean.cast<T>();
  for (const PoseTerm& term : map.terms) {
    for (int i = 0; i < term.phi->size(); ++i) {
      pose[term.coordinate] += (*term.phi)(i)*p[term.block][i];
    }
  }
  return pose;
}

// The landmark's offset from the pose's position, (l_x - x, l_y - y).
template <typename T>
std::pair<T, T> LandmarkOffset(const Eigen::Matrix<T, 3, 1>& pose,
                               const T* landmark) {
  return {landmark[0] - pose[0], landmark[1] - pose[1]};
}

// The twins' wrap: a formula of its own (atan2 of sin and cos), not
// WrapAngle, so that they do not share the code they check.
template <typename T>
T Wrap(const T& angle) {
  using std::atan2;
  using std::cos;
  using std::sin;
  return atan2(sin(angle), cos(angle));
}

// r = L e for a 3-vector e (the whitening of the odometry twins).
template <typename T>
void Whiten3(const Eigen::Matrix3d& sqrt_information, const T* e, T* r) {
  for (int i = 0; i < 3; ++i) {
    r[i] = T(0.0);
    for (int k = 0; k < 3; ++k) r[i] += sqrt_information(i, k) * e[k];
  }
}

// Evaluates both costs at `parameters` and compares residuals and every
// Jacobian (relative tolerance on the larger magnitude).
inline void ExpectSameCost(const ceres::CostFunction& analytic,
                           const ceres::CostFunction& autodiff,
                           const std::vector<std::vector<double>>& parameters,
                           double tolerance = 1e-9) {
  ASSERT_EQ(analytic.num_residuals(), autodiff.num_residuals());
  ASSERT_EQ(analytic.parameter_block_sizes(), autodiff.parameter_block_sizes());
  const int m = analytic.num_residuals();
  const std::vector<int32_t>& sizes = analytic.parameter_block_sizes();
  std::vector<const double*> blocks;
  for (const auto& p : parameters) blocks.push_back(p.data());
  std::vector<double> r1(m), r2(m);
  std::vector<std::vector<double>> j1(sizes.size()), j2(sizes.size());
  std::vector<double*> j1p, j2p;
  for (size_t i = 0; i < sizes.size(); ++i) {
    j1[i].assign(m * sizes[i], -7.0);  // Garbage: Evaluate must overwrite.
    j2[i].assign(m * sizes[i], 0.0);
    j1p.push_back(j1[i].data());
    j2p.push_back(j2[i].data());
  }
  ASSERT_TRUE(analytic.Evaluate(blocks.data(), r1.data(), j1p.data()));
  ASSERT_TRUE(autodiff.Evaluate(blocks.data(), r2.data(), j2p.data()));
  for (int r = 0; r < m; ++r) {
    EXPECT_NEAR(r1[r], r2[r], tolerance * (1.0 + std::abs(r2[r])));
  }
  for (size_t i = 0; i < sizes.size(); ++i) {
    for (size_t k = 0; k < j1[i].size(); ++k) {
      EXPECT_NEAR(j1[i][k], j2[i][k], tolerance * (1.0 + std::abs(j2[i][k])))
          << "block " << i << " entry " << k;
    }
  }
  // Residuals alone (no Jacobians requested) agree too.
  std::vector<double> r3(m);
  ASSERT_TRUE(analytic.Evaluate(blocks.data(), r3.data(), nullptr));
  for (int r = 0; r < m; ++r) EXPECT_EQ(r3[r], r1[r]);
  // A cost seen through pose maps: its gradients at the poses, through its
  // maps, give the same Jacobians.
  const auto* mapped = dynamic_cast<const PoseMapped*>(&analytic);
  if (mapped == nullptr) return;
  const int poses = mapped->num_pose_maps();
  std::vector<double> r4(m), on_poses(3 * m * poses), on_landmark(2 * m);
  ASSERT_TRUE(mapped->EvaluateAtPoses(blocks.data(), r4.data(), on_poses.data(),
                                      on_landmark.data()));
  std::vector<std::vector<double>> through_maps(sizes.size());
  for (size_t i = 0; i < sizes.size(); ++i) {
    through_maps[i].assign(m * sizes[i], 0.0);
  }
  for (int k = 0; k < poses; ++k) {
    for (const PoseTerm& term : mapped->pose_map(k).terms) {
      for (int r = 0; r < m; ++r) {
        const double g = on_poses[3 * m * k + 3 * r + term.coordinate];
        for (int e = 0; e < term.phi->size(); ++e) {
          through_maps[term.block][r * sizes[term.block] + e] +=
              g * (*term.phi)[e];
        }
      }
    }
  }
  if (mapped->has_landmark()) through_maps.back() = on_landmark;
  for (int r = 0; r < m; ++r) EXPECT_EQ(r4[r], r1[r]);
  for (size_t i = 0; i < sizes.size(); ++i) {
    for (size_t k = 0; k < j1[i].size(); ++k) {
      EXPECT_NEAR(through_maps[i][k], j1[i][k],
                  1e-12 * (1.0 + std::abs(j1[i][k])))
          << "block " << i << " entry " << k;
    }
  }
}

// Random values for blocks of the given sizes.
inline std::vector<std::vector<double>> RandomParameters(
    const std::vector<int32_t>& sizes, std::mt19937* rng, double scale = 0.5) {
  std::normal_distribution<double> normal;
  std::vector<std::vector<double>> parameters;
  for (int size : sizes) {
    std::vector<double> p(size);
    for (double& v : p) v = scale * normal(*rng);
    parameters.push_back(p);
  }
  return parameters;
}

// Wraps a functor with `operator()(T const* const*, T*)` in a dynamic autodiff
// cost with the same blocks as `analytic`.
template <typename Functor>
std::unique_ptr<ceres::CostFunction> MakeAutoDiff(
    Functor* functor, const ceres::CostFunction& analytic) {
  auto* cost = new ceres::DynamicAutoDiffCostFunction<Functor, 4>(
      functor, ceres::TAKE_OWNERSHIP);
  for (int size : analytic.parameter_block_sizes()) {
    cost->AddParameterBlock(size);
  }
  cost->SetNumResiduals(analytic.num_residuals());
  return std::unique_ptr<ceres::CostFunction>(cost);
}

}  // namespace testing
}  // namespace rff

#endif  // RFF_TEST_COSTS_COST_TEST_UTIL_H_
