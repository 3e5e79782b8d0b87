// Cubic smoothing splines and the paper's iterated spline prior mean
// (section III-B.2): between outer solves the estimated trajectory is
// smoothed by a spline whose data weights follow the data fit, and the
// spline becomes the new prior mean.
#ifndef RFF_CERES_MEAN_SPLINE_MEAN_H_
#define RFF_CERES_MEAN_SPLINE_MEAN_H_

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "Eigen/Core"
#include "rff_ceres/mean/mean_function.h"
#include "rff_ceres/types.h"

namespace rff {

// The natural cubic spline f minimising De Boor's (csaps) objective
//
//   p * sum_i w_i (y_i - f(t_i))^2 + (1 - p) * integral f''(t)^2 dt,
//
// so p = 1 interpolates and p = 0 is the weighted least-squares line. Solved
// in Reinsch's form (R + (1-p)/p Q^T W^-1 Q) gamma = Q^T y, a pentadiagonal
// system factorised in O(n).
class CubicSmoothingSpline {
 public:
  // `t` strictly increasing and finite, `y` finite, `w` finite and > 0, all of
  // one size >= 1; p in [0, 1]. Returns false with a message otherwise.
  bool Fit(const std::vector<double>& t, const std::vector<double>& y,
           const std::vector<double>& w, double p, std::string* error);

  // f and f' at t; linear (the natural spline's extension) outside the knots.
  double Evaluate(double t) const;
  double Derivative(double t) const;

  const std::vector<double>& knots() const { return t_; }
  // f(t_i) and f''(t_i) at the knots (f'' is 0 at the two ends).
  const std::vector<double>& values() const { return g_; }
  const std::vector<double>& second_derivatives() const { return gamma_; }
  // integral of f''^2 over the knot span.
  double Roughness() const;

 private:
  std::size_t Interval(double t) const;
  std::vector<double> t_, g_, gamma_;
};

// The mean x(t), y(t), theta(t) of three smoothing splines, or, when built
// with heading_from_velocity, theta(t) = atan2(y'(t), x'(t)) (unwrapped),
// for data whose measurements do not give the heading. Held constant before
// the first and after the last knot.
class SplineMean : public MeanFunction {
 public:
  Eigen::Vector3d Evaluate(double t) const override;

  // Fits the three splines to `poses` (strictly increasing times; headings
  // are unwrapped along the sequence first) with per-pose weights (empty:
  // all 1) and smoothing p.
  static std::shared_ptr<SplineMean> Fit(const std::vector<TimedPose>& poses,
                                         const std::vector<double>& weights,
                                         double smoothing, std::string* error);

  // Builds the mean from fitted coordinate splines; `theta` is ignored when
  // heading_from_velocity.
  SplineMean(CubicSmoothingSpline x, CubicSmoothingSpline y,
             CubicSmoothingSpline theta, bool heading_from_velocity);

 private:
  double Heading(double t) const;
  CubicSmoothingSpline x_, y_, theta_;
  bool heading_from_velocity_ = false;
  double t_begin_ = 0.0, t_end_ = 0.0;
  // Velocity headings sampled at the knots and unwrapped, so that atan2 does
  // not jump by 2 pi between them.
  std::vector<double> velocity_heading_;
};

// Paper III-B.2, one outer round: the spline through the current estimate
// `estimate` (strictly increasing times), weighted by `residual_weights`
// (one per pose, > 0; empty: uniform), normalised to mean 1 so that p keeps
// csaps's meaning, with smoothing p (the paper: 0.98). The solver sets the
// result as the new mean (FeatureTrajectory::set_mean), zeroes the weights
// and solves again.
std::shared_ptr<const MeanFunction> RefitSplineMean(
    const std::vector<TimedPose>& estimate,
    const std::vector<double>& residual_weights, double smoothing,
    std::string* error);

// Data-fit weights for RefitSplineMean, "inversely proportional to the
// data-fit error": for each pose of `estimate`, 1 / (mean squared whitened
// residual of the observations at that time + 1), so a pose whose
// measurements are explained to 1 sigma gets weight 1/2 and one that misfits
// gets little. Poses without observations (or whose landmark is not in
// `landmarks`) get the median weight of the others (1 if none).
std::vector<double> DataFitWeights(
    const Dataset& dataset, const std::vector<TimedPose>& estimate,
    const std::map<LandmarkId, Eigen::Vector2d>& landmarks);

}  // namespace rff

#endif  // RFF_CERES_MEAN_SPLINE_MEAN_H_
