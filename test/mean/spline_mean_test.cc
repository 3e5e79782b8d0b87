#include "rff_ceres/mean/spline_mean.h"

#include <cmath>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace rff {
namespace {

using ::testing::HasSubstr;

TEST(CubicSmoothingSplineTest, ThreePointHandCase) {
  // One interior knot: R = 2/3, Q = (1, -2, 1), Q^T y = -2, Q^T Q = 6, so
  // with p = 0.5 (alpha = 1) gamma = -2 / (2/3 + 6) = -0.3 and
  // g = y - Q gamma = (0.3, 0.4, 0.3).
  CubicSmoothingSpline spline;
  std::string error;
  ASSERT_TRUE(spline.Fit({0, 1, 2}, {0, 1, 0}, {1, 1, 1}, 0.5, &error))
      << error;
  EXPECT_NEAR(spline.values()[0], 0.3, 1e-12);
  EXPECT_NEAR(spline.values()[1], 0.4, 1e-12);
  EXPECT_NEAR(spline.values()[2], 0.3, 1e-12);
  EXPECT_NEAR(spline.second_derivatives()[1], -0.3, 1e-12);
  EXPECT_NEAR(spline.Evaluate(1.0), 0.4, 1e-12);
  // Symmetric about t = 1, so the slope there is zero; f'' is linear per
  // interval, so the roughness is 2 * (0.09 / 3).
  EXPECT_NEAR(spline.Derivative(1.0), 0.0, 1e-12);
  EXPECT_NEAR(spline.Roughness(), 0.06, 1e-12);
}

TEST(CubicSmoothingSplineTest, PEqualOneInterpolates) {
  const std::vector<double> t = {0, 0.5, 2, 3, 3.2, 5};
  const std::vector<double> y = {1, -2, 0.5, 4, 3, -1};
  CubicSmoothingSpline spline;
  std::string error;
  ASSERT_TRUE(spline.Fit(t, y, {1, 2, 1, 3, 1, 1}, 1.0, &error)) << error;
  for (std::size_t i = 0; i < t.size(); ++i) {
    EXPECT_NEAR(spline.Evaluate(t[i]), y[i], 1e-10) << i;
  }
  // Natural: no curvature at the ends.
  EXPECT_EQ(spline.second_derivatives().front(), 0.0);
  EXPECT_EQ(spline.second_derivatives().back(), 0.0);
}

TEST(CubicSmoothingSplineTest, PEqualZeroIsTheWeightedLeastSquaresLine) {
  // Unweighted: slope 4 / 5 = 0.8, intercept 1.5 - 0.8 * 1.5 = 0.3.
  CubicSmoothingSpline spline;
  std::string error;
  ASSERT_TRUE(spline.Fit({0, 1, 2, 3}, {0, 2, 1, 3}, {1, 1, 1, 1}, 0.0, &error))
      << error;
  EXPECT_NEAR(spline.Evaluate(0.0), 0.3, 1e-12);
  EXPECT_NEAR(spline.Evaluate(3.0), 2.7, 1e-12);
  EXPECT_NEAR(spline.Derivative(1.7), 0.8, 1e-12);
  // Weighted: all weight on t = 0 and t = 3 gives the line through them.
  ASSERT_TRUE(
      spline.Fit({0, 1, 2, 3}, {0, 2, 1, 3}, {1e9, 1, 1, 1e9}, 0.0, &error));
  EXPECT_NEAR(spline.Evaluate(1.0), 1.0, 1e-6);
  // A tiny p approaches the line continuously.
  ASSERT_TRUE(
      spline.Fit({0, 1, 2, 3}, {0, 2, 1, 3}, {1, 1, 1, 1}, 1e-9, &error));
  EXPECT_NEAR(spline.Evaluate(0.0), 0.3, 1e-6);
  EXPECT_NEAR(spline.Evaluate(3.0), 2.7, 1e-6);
}

TEST(CubicSmoothingSplineTest, SmallerPIsSmootherAndFitsLess) {
  std::vector<double> t, y, w;
  for (int i = 0; i < 200; ++i) {
    t.push_back(0.5 * i + 0.1 * std::sin(i));
    y.push_back(std::sin(0.2 * t.back()) + 0.3 * std::cos(7.0 * i));
    w.push_back(1.0);
  }
  double last_roughness = 1e300, last_misfit = -1.0;
  for (const double p : {0.999, 0.98, 0.5, 0.05}) {
    CubicSmoothingSpline spline;
    std::string error;
    ASSERT_TRUE(spline.Fit(t, y, w, p, &error)) << error;
    double misfit = 0.0;
    for (std::size_t i = 0; i < t.size(); ++i) {
      misfit += std::pow(y[i] - spline.values()[i], 2);
      EXPECT_NEAR(spline.Evaluate(t[i]), spline.values()[i], 1e-9);
    }
    EXPECT_LT(spline.Roughness(), last_roughness) << p;
    EXPECT_GT(misfit, last_misfit) << p;
    last_roughness = spline.Roughness();
    last_misfit = misfit;
    // The derivative agrees with a central difference.
    const double h = 1e-5;
    EXPECT_NEAR(
        spline.Derivative(33.3),
        (spline.Evaluate(33.3 + h) - spline.Evaluate(33.3 - h)) / (2 * h),
        1e-6);
  }
}

TEST(CubicSmoothingSplineTest, ReproducesALineForAnyP) {
  for (const double p : {0.0, 0.3, 0.98, 1.0}) {
    CubicSmoothingSpline spline;
    std::string error;
    ASSERT_TRUE(
        spline.Fit({0, 1, 3, 4}, {1, 3, 7, 9}, {1, 5, 1, 2}, p, &error));
    EXPECT_NEAR(spline.Evaluate(2.0), 5.0, 1e-10) << p;
    EXPECT_NEAR(spline.Evaluate(5.0), 11.0, 1e-10) << p;  // Extends linearly.
  }
}

TEST(CubicSmoothingSplineTest, RejectsBadInput) {
  CubicSmoothingSpline spline;
  std::string error;
  EXPECT_FALSE(spline.Fit({0, 1, 1}, {0, 0, 0}, {1, 1, 1}, 0.5, &error));
  EXPECT_EQ(error,
            "smoothing spline: times must increase strictly, but t[2] = 1 <= "
            "1");
  EXPECT_FALSE(spline.Fit({0, 1}, {0, 0}, {1, 1}, 1.5, &error));
  EXPECT_EQ(error, "smoothing spline: smoothing p must be in [0, 1], got 1.5");
  EXPECT_FALSE(spline.Fit({0, 1}, {0, 0}, {1, 0}, 0.5, &error));
  EXPECT_THAT(error, HasSubstr("point 1"));
  EXPECT_FALSE(spline.Fit({}, {}, {}, 0.5, &error));
  EXPECT_THAT(error, HasSubstr("at least one"));
}

TEST(SplineMeanTest, UnwrapsTheHeadingAcrossPi) {
  std::vector<TimedPose> poses;
  for (int i = 0; i < 20; ++i) {
    const double theta = 3.0 + 0.05 * i;  // Passes pi at i = 3.
    poses.push_back(
        {double(i), double(i), 0.0, std::remainder(theta, 2 * M_PI)});
  }
  std::string error;
  std::shared_ptr<const MeanFunction> mean =
      RefitSplineMean(poses, {}, 0.98, &error);
  ASSERT_NE(mean, nullptr) << error;
  // A straight line in every coordinate is reproduced exactly.
  EXPECT_NEAR(mean->Evaluate(10.5).z(), 3.0 + 0.05 * 10.5, 1e-9);
  EXPECT_NEAR(mean->Evaluate(10.5).x(), 10.5, 1e-9);
  // Held constant outside the poses.
  EXPECT_NEAR(mean->Evaluate(-5.0).x(), 0.0, 1e-9);
  EXPECT_NEAR(mean->Evaluate(50.0).x(), 19.0, 1e-9);
}

TEST(SplineMeanTest, HeavierWeightsAreFollowedMoreClosely) {
  std::vector<TimedPose> poses;
  for (int i = 0; i < 11; ++i) poses.push_back({double(i), 0.0, 0.0, 0.0});
  poses[5].x = 1.0;
  std::vector<double> weights(11, 1.0);
  std::string error;
  const auto light = RefitSplineMean(poses, weights, 0.5, &error);
  weights[5] = 100.0;
  const auto heavy = RefitSplineMean(poses, weights, 0.5, &error);
  ASSERT_NE(light, nullptr);
  ASSERT_NE(heavy, nullptr);
  EXPECT_GT(heavy->Evaluate(5.0).x(), light->Evaluate(5.0).x());
  EXPECT_LT(light->Evaluate(5.0).x(), 1.0);
  EXPECT_FALSE(RefitSplineMean(poses, {1.0, 2.0}, 0.5, &error));
  EXPECT_EQ(error, "spline mean: 2 weights for 11 poses");
}

TEST(DataFitWeightsTest, InverseOfTheMeanSquaredWhitenedResidualPlusOne) {
  Dataset dataset;
  Observation o;
  o.type = ObservationType::kRangeBearing;
  o.t = 1.0;
  o.id = 3;
  o.range = 4.0;  // True distance 5: residual 1 / 0.5 = 2 sigma.
  o.bearing = 0.0;
  o.sigma_range = 0.5;
  o.sigma_bearing = 0.1;
  dataset.observations.push_back(o);
  o.t = 3.0;
  o.range = 5.0;  // Exact.
  dataset.observations.push_back(o);
  const std::vector<TimedPose> estimate = {
      {1.0, 0, 0, 0}, {2.0, 0, 0, 0}, {3.0, 0, 0, 0}};
  const std::map<LandmarkId, Eigen::Vector2d> landmarks = {
      {3, Eigen::Vector2d(5.0, 0.0)}};
  const std::vector<double> w = DataFitWeights(dataset, estimate, landmarks);
  ASSERT_EQ(w.size(), 3u);
  EXPECT_NEAR(w[0], 1.0 / ((4.0 + 0.0) / 2.0 + 1.0), 1e-12);  // 1/3
  EXPECT_NEAR(w[2], 1.0, 1e-12);
  EXPECT_NEAR(w[1], 1.0, 1e-12);  // No observation: the median of {1/3, 1}.
}

}  // namespace
}  // namespace rff
