// Is the solution believable? The whitened residuals r = L^T (z - h(x)) of a
// correct model at its MAP are close to N(0, 1): per observation kind the
// normalised chi-square sum(r^2) / n is near 1 and about 0.27% of them lie
// beyond 3 sigma. A wrong basin (a mirrored or rotated map, a landmark on
// the wrong side) shows as a kind far above both. A sensor's kinds
// (measurement_types.h) are judged on the chi-square of their inliers (|r|
// within OutlierLevel) and on the share of their outliers: gross outliers
// of data association, which a robust loss sets aside, do not make a good
// fit "suspect" while they are few. The other kinds (odometry, priors) are
// judged on all their residuals: a motion model broken by hundreds of
// sigma at a few places is a wrong solution. The report gives both per kind
// and a verdict: "ok", or "suspect" with the reasons.
#ifndef RFF_CERES_QUALITY_REPORT_H_
#define RFF_CERES_QUALITY_REPORT_H_

#include <map>
#include <string>
#include <vector>

#include "Eigen/Core"

namespace rff {

// Above these a kind's fit is not what its sigmas promise. Real sensors'
// sigmas are rarely exact, so the bounds leave a factor of a few.
inline constexpr double kMaxChi2PerResidual = 4.0;
inline constexpr double kMaxShareBeyond3Sigma = 0.05;
// A few outliers among a few residuals are chance: the share counts only
// when that many beyond 3 sigma would be rarer than this under N(0, 1).
inline constexpr double kOutlierCountProbability = 1e-3;
// A minimum leaves the Gauss-Newton model nothing to gain: a solve that
// "converged" with more than this still ahead (a chi-square of 2 between
// the estimate and the model's minimum, 1.4 standard deviations along the
// step) stopped on a flat step short of it.
inline constexpr double kMaxPredictedDecrease = 1.0;

// The |r| that n draws of N(0, 1) all stay within with probability
// 1 - kOutlierCountProbability (n * P(|r| > level) = that probability): a
// residual beyond it is an outlier, not chance. About 5.3 for n = 10^4.
double OutlierLevel(int n);

struct ResidualKindQuality {
  std::string kind;  // "range", "odometry", "landmark prior", ...
  int residuals = 0;
  double chi2_per_residual = 0.0;     // sum(r^2) / n
  // The same over the inliers, |r| <= OutlierLevel(n); 0 without any.
  double inlier_chi2_per_residual = 0.0;
  double share_beyond_3_sigma = 0.0;  // |r| > 3, as a fraction
  double largest = 0.0;               // max |r|
};

struct QualityReport {
  std::vector<ResidualKindQuality> kinds;  // Sorted by kind.
  std::string verdict = "ok";              // "ok", "suspect" or "not judged"
  std::vector<std::string> reasons;        // Why "suspect", one line each.
  // Those of `reasons` about the solve rather than its residuals (where it
  // stopped, its calibrations' bounds, its heading): what a correction to
  // it keeps (SolveFacts::mean_reasons).
  std::vector<std::string> solve_reasons;
  double predicted_decrease = 0.0;         // SolveFacts's, NaN if unknown.
  bool suspect() const { return verdict != "ok"; }
};

// What AssessQuality needs beyond the residuals.
struct SolveFacts {
  bool converged = true;  // Ceres reported CONVERGENCE.
  std::string termination;
  // The cost the Gauss-Newton model still expects to gain at the solution,
  // g^T H^-1 g / 2, or a lower bound of it; NaN where it is not known (an
  // evaluation fails, H not positive definite, incremental updates).
  double predicted_decrease = 0.0;
  // Whether predicted_decrease is the decrease itself, not a lower bound.
  bool predicted_decrease_exact = false;
  // Range self-calibration: (scale, offset), (1, 0) when not estimated, and
  // whether a bound of slam_problem.h holds it.
  Eigen::Vector2d range_calibration = Eigen::Vector2d(1.0, 0.0);
  bool range_calibration_at_bound = false;
  // Odometry self-calibration: (translation scale, turn scale), (1, 1) when
  // not estimated, and whether a bound holds it.
  Eigen::Vector2d odometry_calibration = Eigen::Vector2d(1.0, 1.0);
  bool odometry_calibration_at_bound = false;
  // Stretches where the heading winds whole turns against the odometry
  // (heading_winding.h): a local minimum.
  std::vector<std::string> heading_windings;
  // The solve reasons of the WNOA solve that is the estimate's prior mean:
  // the correction starts from it, and where it keeps (near) none of the
  // variance it is that solve (its residuals are judged again as the
  // estimate's).
  std::vector<std::string> mean_reasons;
};

// `residuals`: whitened residuals by kind (SlamProblem::
// WhitenedResidualsByKind at the solution).
QualityReport AssessQuality(
    const std::map<std::string, std::vector<double>>& residuals,
    const SolveFacts& facts);

// One line for people: "ok" or "suspect: <reasons joined by '; '>".
std::string QualityLine(const QualityReport& report);

}  // namespace rff

#endif  // RFF_CERES_QUALITY_REPORT_H_
