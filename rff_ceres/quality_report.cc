#include "rff_ceres/quality_report.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "rff_ceres/measurement_types.h"

namespace rff {
namespace {

// P(|r| > 3) for r ~ N(0, 1).
constexpr double kNormalBeyond3Sigma = 0.0026997960632601866;

// P(X >= k) for X ~ Poisson(lambda), the count of rare events among many.
double PoissonUpperTail(double lambda, int k) {
  double term = std::exp(-lambda);  // P(X = 0)
  double below = 0.0;
  for (int i = 0; i < k; ++i) {
    below += term;
    term *= lambda / (i + 1);
  }
  return std::max(0.0, 1.0 - below);
}

// Three significant digits, for messages.
std::string Short(double value) {
  std::ostringstream text;
  text << std::setprecision(3) << value;
  return text.str();
}

}  // namespace

double OutlierLevel(int n) {
  // P(|r| > level) = erfc(level / sqrt(2)), decreasing: bisection.
  const double tail = kOutlierCountProbability / std::max(n, 1);
  double low = 0.0, high = 40.0;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (low + high);
    (std::erfc(mid / std::sqrt(2.0)) > tail ? low : high) = mid;
  }
  return high;
}

QualityReport AssessQuality(
    const std::map<std::string, std::vector<double>>& residuals,
    const SolveFacts& facts) {
  QualityReport report;
  report.predicted_decrease = facts.predicted_decrease;
  auto solve_reason = [&report](const std::string& reason) {
    report.reasons.push_back(reason);
    report.solve_reasons.push_back(reason);
  };
  // A solve cut off by its iteration or time limit stands where the exact
  // Gauss-Newton decrease vouches for it, as a converged one does; a bound
  // from below cannot.
  const bool at_minimum = facts.predicted_decrease_exact &&
                          facts.predicted_decrease <= kMaxPredictedDecrease;
  if (!facts.converged && !at_minimum) {
    solve_reason("the solver stopped before convergence (" + facts.termination +
                 ")");
  }
  for (const std::string& reason : facts.mean_reasons) {
    solve_reason("its WNOA mean: " + reason);
  }
  if (facts.predicted_decrease > kMaxPredictedDecrease) {
    solve_reason("the Gauss-Newton model still expects the cost to fall by " +
                 Short(facts.predicted_decrease) + " (more than " +
                 Short(kMaxPredictedDecrease) +
                 "): the solve stopped short of its minimum");
  }
  for (const auto& [kind, values] : residuals) {
    if (values.empty()) continue;
    ResidualKindQuality q;
    q.kind = kind;
    q.residuals = static_cast<int>(values.size());
    const double outlier_level = OutlierLevel(q.residuals);
    int beyond = 0, inliers = 0;
    for (const double r : values) {
      q.chi2_per_residual += r * r;
      q.largest = std::max(q.largest, std::abs(r));
      if (std::abs(r) > 3.0) ++beyond;
      if (std::abs(r) <= outlier_level) {
        q.inlier_chi2_per_residual += r * r;
        ++inliers;
      }
    }
    q.chi2_per_residual /= q.residuals;
    if (inliers > 0) q.inlier_chi2_per_residual /= inliers;
    q.share_beyond_3_sigma = static_cast<double>(beyond) / q.residuals;
    const bool sensor = FindMeasurementKind(kind) != nullptr;
    const double judged =
        sensor ? q.inlier_chi2_per_residual : q.chi2_per_residual;
    if (judged > kMaxChi2PerResidual) {
      report.reasons.push_back(kind + " chi2/n " + Short(judged) +
                               (sensor ? " (inliers)" : "") + " > " +
                               Short(kMaxChi2PerResidual));
    }
    if (q.share_beyond_3_sigma > kMaxShareBeyond3Sigma &&
        PoissonUpperTail(kNormalBeyond3Sigma * q.residuals, beyond) <
            kOutlierCountProbability) {
      report.reasons.push_back(
          kind + " " + Short(100.0 * q.share_beyond_3_sigma) +
          "% beyond 3 sigma > " + Short(100.0 * kMaxShareBeyond3Sigma) + "%");
    }
    report.kinds.push_back(q);
  }
  if (facts.range_calibration_at_bound) {
    solve_reason("the range calibration (scale " +
                 Short(facts.range_calibration[0]) + ", offset " +
                 Short(facts.range_calibration[1]) +
                 " m) is held by its bound");
  }
  if (facts.odometry_calibration_at_bound) {
    solve_reason("the odometry calibration (scale " +
                 Short(facts.odometry_calibration[0]) + ", turn scale " +
                 Short(facts.odometry_calibration[1]) +
                 ") is held by its bound");
  }
  for (const std::string& winding : facts.heading_windings) {
    solve_reason("the heading winds against the odometry from " + winding);
  }
  if (!report.reasons.empty()) report.verdict = "suspect";
  return report;
}

std::string QualityLine(const QualityReport& report) {
  std::string line = report.verdict;
  for (std::size_t i = 0; i < report.reasons.size(); ++i) {
    line += (i == 0 ? ": " : "; ") + report.reasons[i];
  }
  return line;
}

}  // namespace rff
