#include "rff_ceres/mean/spline_mean.h"

#include <algorithm>
#include <cmath>

#include "Eigen/SparseCholesky"
#include "Eigen/SparseCore"
#include "rff_ceres/io/text_parser.h"

namespace rff {

bool CubicSmoothingSpline::Fit(const std::vector<double>& t,
                               const std::vector<double>& y,
                               const std::vector<double>& w, double p,
                               std::string* error) {
  const std::size_t n = t.size();
  if (n == 0 || y.size() != n || w.size() != n) {
    *error =
        "smoothing spline: need equally many times, values and weights "
        "(at least one), got " +
        std::to_string(t.size()) + ", " + std::to_string(y.size()) + ", " +
        std::to_string(w.size());
    return false;
  }
  if (!(p >= 0.0 && p <= 1.0)) {
    *error = "smoothing spline: smoothing p must be in [0, 1], got " +
             FormatNumber(p);
    return false;
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(t[i]) || !std::isfinite(y[i]) || !std::isfinite(w[i]) ||
        !(w[i] > 0.0)) {
      *error = "smoothing spline: point " + std::to_string(i) +
               " has a non-finite time or value or a weight that is not "
               "positive";
      return false;
    }
    if (i > 0 && !(t[i] > t[i - 1])) {
      *error = "smoothing spline: times must increase strictly, but t[" +
               std::to_string(i) + "] = " + FormatNumber(t[i]) +
               " <= " + FormatNumber(t[i - 1]);
      return false;
    }
  }
  t_ = t;
  g_ = y;
  gamma_.assign(n, 0.0);
  if (n <= 2) return true;  // The line through them is already optimal.

  if (p == 0.0) {
    // The limit p -> 0: the weighted least-squares line.
    double sw = 0, st = 0, sy = 0;
    for (std::size_t i = 0; i < n; ++i) {
      sw += w[i];
      st += w[i] * t[i];
      sy += w[i] * y[i];
    }
    const double tm = st / sw, ym = sy / sw;
    double stt = 0, sty = 0;
    for (std::size_t i = 0; i < n; ++i) {
      stt += w[i] * (t[i] - tm) * (t[i] - tm);
      sty += w[i] * (t[i] - tm) * (y[i] - ym);
    }
    const double slope = sty / stt;
    for (std::size_t i = 0; i < n; ++i) g_[i] = ym + slope * (t[i] - tm);
    return true;
  }

  const double alpha = (1.0 - p) / p;
  const int m = static_cast<int>(n) - 2;  // Interior knots 1 .. n-2.
  std::vector<double> h(n - 1);
  for (std::size_t i = 0; i + 1 < n; ++i) h[i] = t[i + 1] - t[i];
  // Q(i, j): column j (interior knot j) has 1/h[j-1], -1/h[j-1] - 1/h[j],
  // 1/h[j] at knots j-1, j, j+1.
  auto q = [&](std::size_t i, std::size_t j) {
    if (i + 1 == j) return 1.0 / h[j - 1];
    if (i == j) return -1.0 / h[j - 1] - 1.0 / h[j];
    if (i == j + 1) return 1.0 / h[j];
    return 0.0;
  };
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(5 * m + 9 * n);
  for (int k = 0; k < m; ++k) {
    const std::size_t j = k + 1;
    triplets.emplace_back(k, k, (h[j - 1] + h[j]) / 3.0);
    if (k + 1 < m) {
      triplets.emplace_back(k, k + 1, h[j] / 6.0);
      triplets.emplace_back(k + 1, k, h[j] / 6.0);
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    const double d = alpha / w[i];
    for (std::size_t a = (i > 0 ? i - 1 : 0); a <= i + 1; ++a) {
      if (a < 1 || a > n - 2) continue;
      for (std::size_t b = (i > 0 ? i - 1 : 0); b <= i + 1; ++b) {
        if (b < 1 || b > n - 2) continue;
        triplets.emplace_back(a - 1, b - 1, d * q(i, a) * q(i, b));
      }
    }
  }
  Eigen::SparseMatrix<double> matrix(m, m);
  matrix.setFromTriplets(triplets.begin(), triplets.end());
  Eigen::VectorXd rhs(m);
  for (int k = 0; k < m; ++k) {
    const std::size_t j = k + 1;
    rhs(k) = (y[j + 1] - y[j]) / h[j] - (y[j] - y[j - 1]) / h[j - 1];
  }
  // Banded and SPD: natural ordering keeps the factor banded, O(n).
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower,
                        Eigen::NaturalOrdering<int>>
      solver(matrix);
  if (solver.info() != Eigen::Success) {
    *error = "smoothing spline: the banded system could not be factorised";
    return false;
  }
  const Eigen::VectorXd gamma = solver.solve(rhs);
  for (int k = 0; k < m; ++k) gamma_[k + 1] = gamma(k);
  for (std::size_t i = 0; i < n; ++i) {
    double qg = 0.0;
    for (std::size_t j = (i > 1 ? i - 1 : 1); j <= std::min(i + 1, n - 2);
         ++j) {
      qg += q(i, j) * gamma_[j];
    }
    g_[i] = y[i] - alpha / w[i] * qg;
  }
  return true;
}

std::size_t CubicSmoothingSpline::Interval(double t) const {
  const auto upper = std::upper_bound(t_.begin(), t_.end(), t);
  std::size_t i = upper - t_.begin();
  i = i == 0 ? 0 : i - 1;
  return std::min(i, t_.size() - 2);
}

double CubicSmoothingSpline::Evaluate(double t) const {
  if (t_.size() == 1) return g_[0];
  if (t <= t_.front())
    return g_.front() + Derivative(t_.front()) * (t - t_.front());
  if (t >= t_.back())
    return g_.back() + Derivative(t_.back()) * (t - t_.back());
  const std::size_t i = Interval(t);
  const double h = t_[i + 1] - t_[i];
  const double b = (t - t_[i]) / h, a = 1.0 - b;
  return a * g_[i] + b * g_[i + 1] +
         ((a * a * a - a) * gamma_[i] + (b * b * b - b) * gamma_[i + 1]) * h *
             h / 6.0;
}

double CubicSmoothingSpline::Derivative(double t) const {
  if (t_.size() == 1) return 0.0;
  t = std::clamp(t, t_.front(), t_.back());
  const std::size_t i = Interval(t);
  const double h = t_[i + 1] - t_[i];
  const double b = (t - t_[i]) / h, a = 1.0 - b;
  return (g_[i + 1] - g_[i]) / h - (3.0 * a * a - 1.0) / 6.0 * h * gamma_[i] +
         (3.0 * b * b - 1.0) / 6.0 * h * gamma_[i + 1];
}

double CubicSmoothingSpline::Roughness() const {
  // f'' is linear on each interval.
  double sum = 0.0;
  for (std::size_t i = 0; i + 1 < t_.size(); ++i) {
    const double a = gamma_[i], b = gamma_[i + 1];
    sum += (t_[i + 1] - t_[i]) * (a * a + a * b + b * b) / 3.0;
  }
  return sum;
}

SplineMean::SplineMean(CubicSmoothingSpline x, CubicSmoothingSpline y,
                       CubicSmoothingSpline theta, bool heading_from_velocity)
    : x_(std::move(x)),
      y_(std::move(y)),
      theta_(std::move(theta)),
      heading_from_velocity_(heading_from_velocity) {
  t_begin_ = x_.knots().front();
  t_end_ = x_.knots().back();
  if (heading_from_velocity_) {
    for (const double t : x_.knots()) {
      double heading = std::atan2(y_.Derivative(t), x_.Derivative(t));
      if (!velocity_heading_.empty()) {
        heading = velocity_heading_.back() +
                  WrapAngle(heading - velocity_heading_.back());
      }
      velocity_heading_.push_back(heading);
    }
  }
}

double SplineMean::Heading(double t) const {
  if (!heading_from_velocity_) return theta_.Evaluate(t);
  const std::vector<double>& knots = x_.knots();
  const auto upper = std::upper_bound(knots.begin(), knots.end(), t);
  const std::size_t i = upper == knots.begin() ? 0 : upper - knots.begin() - 1;
  const double heading = std::atan2(y_.Derivative(t), x_.Derivative(t));
  return velocity_heading_[i] + WrapAngle(heading - velocity_heading_[i]);
}

Eigen::Vector3d SplineMean::Evaluate(double t) const {
  t = std::clamp(t, t_begin_, t_end_);
  return {x_.Evaluate(t), y_.Evaluate(t), Heading(t)};
}

std::shared_ptr<SplineMean> SplineMean::Fit(const std::vector<TimedPose>& poses,
                                            const std::vector<double>& weights,
                                            double smoothing,
                                            std::string* error) {
  if (poses.empty()) {
    *error = "spline mean: no poses to fit";
    return nullptr;
  }
  if (!weights.empty() && weights.size() != poses.size()) {
    *error = "spline mean: " + std::to_string(weights.size()) +
             " weights for " + std::to_string(poses.size()) + " poses";
    return nullptr;
  }
  std::vector<double> t, x, y, theta;
  for (const TimedPose& p : poses) {
    t.push_back(p.t);
    x.push_back(p.x);
    y.push_back(p.y);
    theta.push_back(theta.empty()
                        ? p.theta
                        : theta.back() + WrapAngle(p.theta - theta.back()));
  }
  std::vector<double> w = weights;
  if (w.empty()) w.assign(poses.size(), 1.0);
  double sum = 0.0;
  for (const double v : w) sum += v;
  if (std::isfinite(sum) && sum > 0.0) {
    for (double& v : w) v *= w.size() / sum;
  }
  CubicSmoothingSpline sx, sy, st;
  if (!sx.Fit(t, x, w, smoothing, error) ||
      !sy.Fit(t, y, w, smoothing, error) ||
      !st.Fit(t, theta, w, smoothing, error)) {
    *error = "spline mean: " + *error;
    return nullptr;
  }
  return std::make_shared<SplineMean>(std::move(sx), std::move(sy),
                                      std::move(st), false);
}

std::shared_ptr<const MeanFunction> RefitSplineMean(
    const std::vector<TimedPose>& estimate,
    const std::vector<double>& residual_weights, double smoothing,
    std::string* error) {
  return SplineMean::Fit(estimate, residual_weights, smoothing, error);
}

std::vector<double> DataFitWeights(
    const Dataset& dataset, const std::vector<TimedPose>& estimate,
    const std::map<LandmarkId, Eigen::Vector2d>& landmarks) {
  std::vector<double> sum(estimate.size(), 0.0);
  std::vector<int> count(estimate.size(), 0);
  for (const Observation& o : dataset.observations) {
    const auto pose =
        std::lower_bound(estimate.begin(), estimate.end(), o.t,
                         [](const TimedPose& p, double t) { return p.t < t; });
    const auto landmark = landmarks.find(o.id);
    if (pose == estimate.end() || pose->t != o.t ||
        landmark == landmarks.end()) {
      continue;
    }
    const Eigen::Vector2d d =
        landmark->second - Eigen::Vector2d(pose->x, pose->y);
    const std::size_t i = pose - estimate.begin();
    if (o.HasRange()) {
      const double r = (d.norm() - o.range) / o.sigma_range;
      sum[i] += r * r;
      ++count[i];
    }
    if (o.HasBearing()) {
      const double b =
          WrapAngle(std::atan2(d.y(), d.x()) - pose->theta - o.bearing) /
          o.sigma_bearing;
      sum[i] += b * b;
      ++count[i];
    }
  }
  std::vector<double> weights(estimate.size(), 0.0), known;
  for (std::size_t i = 0; i < estimate.size(); ++i) {
    if (count[i] > 0) {
      weights[i] = 1.0 / (sum[i] / count[i] + 1.0);
      known.push_back(weights[i]);
    }
  }
  double fill = 1.0;
  if (!known.empty()) {
    std::nth_element(known.begin(), known.begin() + known.size() / 2,
                     known.end());
    fill = known[known.size() / 2];
  }
  for (std::size_t i = 0; i < estimate.size(); ++i) {
    if (count[i] == 0) weights[i] = fill;
  }
  return weights;
}

}  // namespace rff
