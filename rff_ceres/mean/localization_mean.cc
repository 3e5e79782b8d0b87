#include "rff_ceres/mean/localization_mean.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "Eigen/Dense"
#include "ceres/tiny_solver.h"
#include "costs/bearing_cost.h"
#include "costs/range_cost.h"
#include "glog/logging.h"
#include "rff_ceres/dead_reckoning.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/mean/spline_mean.h"
#include "rff_ceres/option_error.h"

namespace rff {
namespace {

// Ranges below this count as this in the bearing's share of the landmark's
// spread (s / r), which would otherwise be unbounded at the landmark.
constexpr double kMinSpreadRange = 1e-6;

// A fix whose information has an eigenvalue below this share of its largest
// is degenerate (collinear landmarks, parallel bearings): no fix.
constexpr double kMinInformationRatio = 1e-9;

// The lowest weight a spline point keeps: a point Cauchy-rejected to weight
// 0 would leave the spline's system singular where it stood alone.
constexpr double kMinSplineWeight = 1e-12;

// Range-only headings: the direction of motion over a window of 2 x this
// (seconds), taken only where the robot moved at least kMinHeadingTravel
// metres in it; each such heading is worth kTravelHeadingVariance (rad^2),
// and without any the correction is 0 with variance 1.
constexpr double kHeadingHalfWindow = 5.0;
constexpr double kMinHeadingTravel = 0.5;
constexpr double kTravelHeadingVariance = 0.1;

// An observation with its landmark found: a fix's refinement evaluates
// the same observations at every step.
struct MapObservation {
  const Observation* observation;
  const KnownLandmark* landmark;
};

std::vector<MapObservation> FindLandmarks(
    const std::vector<Observation>& observations,
    const std::map<LandmarkId, KnownLandmark>& landmarks) {
  std::vector<MapObservation> found;
  found.reserve(observations.size());
  for (const Observation& o : observations) {
    const auto known = landmarks.find(o.id);
    if (known != landmarks.end()) found.push_back({&o, &known->second});
  }
  return found;
}

// The measured values among `observations` (equations for the unknowns,
// and MapResiduals' rows whatever the pose) and the bearings among them.
struct MeasuredValues {
  int equations = 0, bearings = 0;
};
MeasuredValues CountMeasuredValues(
    const std::vector<MapObservation>& observations) {
  MeasuredValues count;
  for (const MapObservation& m : observations) {
    count.equations += m.observation->HasRange() + m.observation->HasBearing();
    count.bearings += m.observation->HasBearing();
  }
  return count;
}

// MapResiduals' rows of `observations` at `p`, into `rows`.
void AppendMapResiduals(const std::vector<MapObservation>& observations,
                        const Eigen::Vector3d& p,
                        std::vector<MapResidualRow>* rows) {
  for (const auto& [observation, landmark] : observations) {
    const Observation& o = *observation;
    const KnownLandmark& l = *landmark;
    // The measurement models of the solver's costs (costs/range_cost.h,
    // costs/bearing_cost.h), with the landmark's prior spread added.
    double range;
    Eigen::Vector3d d_range;
    Eigen::Vector2d d_landmark;
    RangeAndGradient(p, l.position, &range, &d_range, &d_landmark);
    if (o.HasRange()) {
      const double sigma =
          std::sqrt(o.sigma_range * o.sigma_range + l.sigma * l.sigma);
      MapResidualRow row;
      row.residual = (range - o.range) / sigma;
      row.jacobian = row.measurement_jacobian = d_range.transpose() / sigma;
      rows->push_back(row);
    }
    double bearing;
    Eigen::Vector3d d_bearing;
    if (!o.HasBearing()) continue;
    MapResidualRow row;  // Zero where the landmark sits on the robot.
    if (BearingAndGradient(p, l.position, &bearing, &d_bearing, &d_landmark)) {
      // The landmark's spread seen from range r subtends s / r radians.
      const double spread = l.sigma / std::max(range, kMinSpreadRange);
      const double sigma =
          std::sqrt(o.sigma_bearing * o.sigma_bearing + spread * spread);
      row.residual = WrapAngle(bearing - o.bearing) / sigma;
      row.jacobian = row.measurement_jacobian = d_bearing.transpose() / sigma;
      // The sigma moves with the range: d(w / sigma) adds
      // (w / sigma) (s / r)^2 / (sigma^2 r) dr. Left out, Gauss-Newton stops
      // short of the minimum wherever the spread dominates the sigma.
      if (range > kMinSpreadRange) {
        row.jacobian += row.residual * spread * spread /
                        (sigma * sigma * range) * d_range.transpose();
      }
    }
    rows->push_back(row);
  }
}

}  // namespace

std::vector<MapResidualRow> MapResiduals(
    const std::vector<Observation>& observations,
    const std::map<LandmarkId, KnownLandmark>& landmarks,
    const Eigen::Vector3d& p) {
  std::vector<MapResidualRow> rows;
  AppendMapResiduals(FindLandmarks(observations, landmarks), p, &rows);
  return rows;
}

namespace {

// The heading variance of a fix that did not measure it (range-only, or
// the heading held): far beyond a turn, so the smoother ignores it.
constexpr double kUnmeasuredHeadingVariance = 1e6;

// One pose against the map as a ceres::TinySolver function of its free
// unknowns: x, y, and theta unless `kFree` is 2 (the heading held at the
// start's). MapResiduals keeps one row per measured value at every pose.
template <int kFree>
class PoseFit {
 public:
  using Scalar = double;
  enum { NUM_RESIDUALS = Eigen::Dynamic, NUM_PARAMETERS = kFree };

  PoseFit(const std::vector<MapObservation>& observations,
          const Eigen::Vector3d& start)
      : observations_(observations),
        start_(start),
        num_rows_(CountMeasuredValues(observations_).equations) {}

  int NumResiduals() const { return num_rows_; }

  bool operator()(const double* x, double* residuals, double* jacobian) const {
    const Eigen::Vector3d pose = Pose(x);
    if (!pose.allFinite()) {
      // A NaN cost makes TinySolver reject the step (it ignores false).
      std::fill_n(residuals, num_rows_,
                  std::numeric_limits<double>::quiet_NaN());
      return false;
    }
    rows_.clear();
    AppendMapResiduals(observations_, pose, &rows_);
    DCHECK_EQ(static_cast<int>(rows_.size()), num_rows_);
    for (int r = 0; r < num_rows_; ++r) {
      residuals[r] = rows_[r].residual;
      if (jacobian == nullptr) continue;
      for (int c = 0; c < kFree; ++c) {
        jacobian[r + c * num_rows_] = rows_[r].jacobian(c);  // Column-major.
      }
    }
    return true;
  }

  Eigen::Vector3d Pose(const double* x) const {
    Eigen::Vector3d pose = start_;
    for (int c = 0; c < kFree; ++c) pose[c] = x[c];
    return pose;
  }

 private:
  const std::vector<MapObservation>& observations_;
  const Eigen::Vector3d start_;
  const int num_rows_;
  mutable std::vector<MapResidualRow> rows_;  // Kept between steps.
};

// A fit of two or three unknowns converges in a few steps from a seed in its
// basin; the cap only ends a degenerate geometry's slow crawl.
constexpr int kMaxRefineIterations = 50;

// A minimum a start reached, and the Gauss-Newton information of the pose
// there (J^T J of its whitened rows; a held heading's row and column unused).
struct Minimum {
  double cost = 0.0;
  Eigen::Vector3d pose;
  Eigen::Matrix3d information;
};

// A start is taken to end at a minimum already found once its iterate is
// within this of it in the fit's whitened units, (x - m)^T I (x - m): its
// cost then differs from the minimum's by about as much, where the selection
// below tells minima apart by kAmbiguousChi2 = 4. Most turned starts end at
// the prediction's minimum, and the last of their steps crawl (the
// Gauss-Newton Hessian misses the curvature the landmarks' spread adds).
constexpr double kSameMinimumChi2 = 1e-2;
// Steps between the tests of a start against the minima found.
constexpr int kStepsBetweenTests = 4;

Minimum MinimumAt(const std::vector<MapObservation>& observations,
                  const Eigen::Vector3d& pose) {
  Minimum m;
  m.pose = pose;
  m.information.setZero();
  std::vector<MapResidualRow> rows;
  AppendMapResiduals(observations, pose, &rows);
  for (const MapResidualRow& r : rows) {
    m.cost += r.residual * r.residual;
    m.information += r.jacobian.transpose() * r.jacobian;
  }
  return m;
}

// The first of `found` whose whitened distance from `pose` over the first
// kFree unknowns is within kSameMinimumChi2, or -1.
template <int kFree>
int SameMinimum(const std::vector<Minimum>& found,
                const Eigen::Vector3d& pose) {
  for (std::size_t i = 0; i < found.size(); ++i) {
    Eigen::Vector3d d = pose - found[i].pose;
    d.z() = WrapAngle(d.z());
    const Eigen::Matrix<double, kFree, 1> free = d.head<kFree>();
    const double chi2 =
        free.dot(found[i].information.topLeftCorner<kFree, kFree>() * free);
    if (chi2 <= kSameMinimumChi2) return static_cast<int>(i);
  }
  return -1;
}

// Refines `pose` over its first kFree unknowns; returns the index in `found`
// of the minimum it was found to head for (leaving `pose` where the test
// took it), or -1 where it converged (or stopped) on its own.
template <int kFree>
int RefineFree(const std::vector<MapObservation>& observations,
               const std::vector<Minimum>& found, Eigen::Vector3d* pose) {
  const PoseFit<kFree> fit(observations, *pose);
  using Solver = ceres::TinySolver<PoseFit<kFree>>;
  Solver solver;
  // Costs are chi-square sums of order the rows: stop at changes and steps
  // far below any that matters to a fix.
  solver.options.function_tolerance = 1e-9;
  solver.options.parameter_tolerance = 1e-10;
  Eigen::Matrix<double, kFree, 1> x = pose->head<kFree>();
  if (found.empty()) {
    solver.options.max_num_iterations = kMaxRefineIterations;
    solver.Solve(fit, &x);
    if (x.allFinite()) *pose = fit.Pose(x.data());
    return -1;
  }
  // In runs of kStepsBetweenTests steps (TinySolver's iterations count from
  // 1), each run from the last one's point.
  solver.options.max_num_iterations = kStepsBetweenTests + 1;
  for (int steps = 0; steps < kMaxRefineIterations;
       steps += kStepsBetweenTests) {
    const typename Solver::Summary& summary = solver.Solve(fit, &x);
    if (!x.allFinite()) return -1;
    *pose = fit.Pose(x.data());
    if (summary.status != Solver::HIT_MAX_ITERATIONS) return -1;
    const int same = SameMinimum<kFree>(found, *pose);
    if (same >= 0) return same;
  }
  return -1;
}

// Levenberg-Marquardt (ceres::TinySolver) from `pose` over the free unknowns
// (`free_heading` false holds theta), leaving the pose in `pose`: RefineFree.
int Refine(const std::vector<MapObservation>& observations, bool free_heading,
           const std::vector<Minimum>& found, Eigen::Vector3d* pose) {
  return free_heading ? RefineFree<3>(observations, found, pose)
                      : RefineFree<2>(observations, found, pose);
}

// LocalizePose on the observations whose landmarks are found: looked up
// once for every start's refinement.
bool LocalizeAgainst(const std::vector<MapObservation>& usable,
                     const std::vector<Eigen::Vector3d>& seeds,
                     const double* fixed_heading, double fixed_heading_sigma,
                     PoseFix* fix) {
  const auto [equations, bearings] = CountMeasuredValues(usable);
  if (usable.empty() || seeds.empty()) return false;
  const bool free_heading = bearings > 0 && fixed_heading == nullptr;
  const int unknowns = free_heading ? 3 : 2;
  if (equations < unknowns) return false;

  // Every start converges to some minimum; near-degenerate geometries (two
  // close landmarks) have several that fit about equally well, so among the
  // minima within kAmbiguousChi2 of the best take the one nearest the first
  // seed (the prediction).
  constexpr double kAmbiguousChi2 = 4.0;
  std::vector<Minimum> minima;
  double lowest = std::numeric_limits<double>::infinity();
  for (Eigen::Vector3d pose : seeds) {
    if (fixed_heading != nullptr) pose.z() = *fixed_heading;
    // A start heading for a minimum already found adds nothing.
    if (Refine(usable, free_heading, minima, &pose) >= 0) continue;
    Minimum minimum = MinimumAt(usable, pose);
    if (!std::isfinite(minimum.cost) || !pose.allFinite()) continue;
    lowest = std::min(lowest, minimum.cost);
    minima.push_back(minimum);
  }
  if (minima.empty()) return false;
  double best_cost = 0.0, nearest = std::numeric_limits<double>::infinity();
  Eigen::Vector3d best = seeds.front();
  for (const Minimum& m : minima) {
    if (m.cost > lowest + kAmbiguousChi2) continue;
    // Metres, and a radian of heading counted as a metre.
    const double distance =
        (m.pose.head<2>() - seeds.front().head<2>()).norm() +
        (free_heading ? std::abs(WrapAngle(m.pose.z() - seeds.front().z()))
                      : 0);
    if (distance < nearest) {
      nearest = distance;
      best_cost = m.cost;
      best = m.pose;
    }
  }

  // Information of the free unknowns; a degenerate geometry (collinear
  // landmarks, parallel bearings) leaves it singular.
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  std::vector<MapResidualRow> rows;
  AppendMapResiduals(usable, best, &rows);
  for (const MapResidualRow& r : rows) {
    h += r.measurement_jacobian.transpose() * r.measurement_jacobian;
  }
  const Eigen::MatrixXd hn = h.topLeftCorner(unknowns, unknowns);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(hn);
  const Eigen::VectorXd values = eigen.eigenvalues();
  if (!(values(0) > kMinInformationRatio * values(unknowns - 1)) ||
      !(values(0) > 0.0)) {
    return false;
  }
  fix->covariance = Eigen::Matrix3d::Zero();
  if (fixed_heading != nullptr && bearings > 0) {
    // Marginalise the held heading with its prior: the position inherits
    // range * heading error across the line of sight.
    Eigen::Matrix3d with_prior = h;
    with_prior(2, 2) += 1.0 / (fixed_heading_sigma * fixed_heading_sigma);
    fix->covariance = with_prior.inverse();
  } else {
    fix->covariance.topLeftCorner(unknowns, unknowns) = hn.inverse();
  }
  if (!free_heading) fix->covariance(2, 2) = kUnmeasuredHeadingVariance;
  fix->pose.x = best.x();
  fix->pose.y = best.y();
  fix->pose.theta = WrapAngle(best.z());
  fix->has_heading = free_heading;
  fix->chi2 = best_cost;
  fix->dof = equations - unknowns;
  return true;
}

}  // namespace

bool LocalizePose(const std::vector<Observation>& observations,
                  const std::map<LandmarkId, KnownLandmark>& landmarks,
                  const std::vector<Eigen::Vector3d>& seeds,
                  const double* fixed_heading, double fixed_heading_sigma,
                  PoseFix* fix) {
  return LocalizeAgainst(FindLandmarks(observations, landmarks), seeds,
                         fixed_heading, fixed_heading_sigma, fix);
}

namespace {

// The csaps p for data weighted by inverse variances and a roughness penalty
// of 1/q: sum w (y - f)^2 + (1/q) int f''^2 is p/(1-p) = q.
double SmoothingFromNoiseDensity(double q) { return q / (1.0 + q); }

// Robust smoothing spline: Cauchy reweighting of the points whose residual
// is many standard deviations. `variance` per point; the same robust weight
// is applied to every coordinate of a point (x and y together).
bool RobustFit(const std::vector<double>& t,
               const std::vector<std::vector<double>>& values,
               const std::vector<std::vector<double>>& variances, double q,
               const LocalizationOptions& options,
               std::vector<CubicSmoothingSpline>* splines, std::string* error) {
  const std::size_t n = t.size();
  const std::size_t dims = values.size();
  std::vector<double> robust(n, 1.0);
  splines->assign(dims, CubicSmoothingSpline());
  const double p = SmoothingFromNoiseDensity(q);
  for (int iteration = 0; iteration <= options.robust_iterations; ++iteration) {
    for (std::size_t k = 0; k < dims; ++k) {
      std::vector<double> w(n);
      for (std::size_t i = 0; i < n; ++i) {
        w[i] = std::max(robust[i] / variances[k][i], kMinSplineWeight);
      }
      if (!(*splines)[k].Fit(t, values[k], w, p, error)) return false;
    }
    for (std::size_t i = 0; i < n; ++i) {
      double u2 = 0.0;
      for (std::size_t k = 0; k < dims; ++k) {
        const double r = values[k][i] - (*splines)[k].Evaluate(t[i]);
        u2 += r * r / variances[k][i];
      }
      u2 /= dims * options.robust_scale * options.robust_scale;
      robust[i] = 1.0 / (1.0 + u2);
    }
  }
  return true;
}

// Points of one smoothed coordinate set, merged by time (information
// weighted), so that the spline's times increase strictly.
struct Series {
  std::vector<double> t;
  std::vector<std::vector<double>> values, variances;

  explicit Series(std::size_t dims) : values(dims), variances(dims) {}
  void Add(double time, const std::vector<double>& v,
           const std::vector<double>& var) {
    if (!t.empty() && t.back() == time) {
      for (std::size_t k = 0; k < v.size(); ++k) {
        const double a = 1.0 / variances[k].back(), b = 1.0 / var[k];
        values[k].back() = (a * values[k].back() + b * v[k]) / (a + b);
        variances[k].back() = 1.0 / (a + b);
      }
      return;
    }
    t.push_back(time);
    for (std::size_t k = 0; k < v.size(); ++k) {
      values[k].push_back(v[k]);
      variances[k].push_back(var[k]);
    }
  }
};

// Time-sorted PRIOR_POSE and fix points in one list.
struct Point {
  double t;
  Eigen::Vector3d pose;
  Eigen::Vector3d variance;  // x, y, theta
  bool has_heading;
};

std::vector<Point> Points(const Dataset& dataset,
                          const std::vector<PoseFix>& fixes) {
  std::vector<Point> points;
  for (const PosePrior& p : dataset.pose_priors) {
    const double vxy = p.sigma_xy * p.sigma_xy;
    points.push_back({p.pose.t,
                      {p.pose.x, p.pose.y, p.pose.theta},
                      {vxy, vxy, p.sigma_theta * p.sigma_theta},
                      true});
  }
  for (const PoseFix& f : fixes) {
    points.push_back(
        {f.pose.t,
         {f.pose.x, f.pose.y, f.pose.theta},
         {f.covariance(0, 0), f.covariance(1, 1), f.covariance(2, 2)},
         f.has_heading});
  }
  std::stable_sort(points.begin(), points.end(),
                   [](const Point& a, const Point& b) { return a.t < b.t; });
  return points;
}

// Seeds for one time: the prediction, and for measurements with bearings
// the prediction turned by multiples of 45 degrees, each also moved to where
// the range-bearing measurements of landmarks found (`usable`) put it under
// that heading.
std::vector<Eigen::Vector3d> Seeds(const std::vector<Observation>& observations,
                                   const std::vector<MapObservation>& usable,
                                   const Eigen::Vector3d& prediction) {
  std::vector<Eigen::Vector3d> seeds = {prediction};
  bool bearings = false;
  for (const Observation& o : observations) bearings |= o.HasBearing();
  std::vector<MapObservation> range_bearings;
  for (const MapObservation& m : usable) {
    if (m.observation->HasRange() && m.observation->HasBearing()) {
      range_bearings.push_back(m);
    }
  }
  for (int k = 0; k < 8; ++k) {
    Eigen::Vector3d seed = prediction;
    seed.z() += k * M_PI / 4.0;
    if (bearings && k > 0) seeds.push_back(seed);
    if (range_bearings.empty()) continue;
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    for (const auto& [o, l] : range_bearings) {
      const double angle = seed.z() + o->bearing;
      sum += l->position -
             o->range * Eigen::Vector2d(std::cos(angle), std::sin(angle));
    }
    seed.head<2>() = sum / static_cast<double>(range_bearings.size());
    seeds.push_back(seed);
  }
  return seeds;
}

}  // namespace

bool CheckLocalizationOptions(const LocalizationOptions& options,
                              std::string* error) {
  for (const auto& [name, value] :
       {std::make_pair("position_smoothing", options.position_smoothing),
        std::make_pair("heading_smoothing", options.heading_smoothing),
        std::make_pair("correction_smoothing", options.correction_smoothing),
        std::make_pair("held_heading_sigma", options.held_heading_sigma)}) {
    if (!CheckPositiveOption(
            value, (std::string("localization_") + name).c_str(), error)) {
      return false;
    }
  }
  return true;
}

std::shared_ptr<const MeanFunction> BuildLocalizationMean(
    const Dataset& dataset, const LocalizationOptions& options,
    LocalizationReport* report, std::string* error) {
  *report = LocalizationReport();
  if (!CheckLocalizationOptions(options, error)) return nullptr;
  const std::string prefix = "prior mean 'localization': ";
  std::map<LandmarkId, KnownLandmark> landmarks;
  for (const LandmarkPrior& l : dataset.landmark_priors) {
    landmarks[l.id] = {Eigen::Vector2d(l.x, l.y), l.sigma};
  }
  if (landmarks.empty()) {
    *error = prefix +
             "the dataset has no PRIOR_LANDMARK records to localise against";
    return nullptr;
  }
  if (dataset.pose_priors.empty()) {
    *error = prefix + "the dataset has no PRIOR_POSE record";
    return nullptr;
  }
  const PosePrior& first = EarliestPosePrior(dataset);

  // Dead reckoning, when fused: the fixes then only correct its drift.
  std::unique_ptr<PiecewiseLinearMean> dead_reckoning;
  DeadReckoningResult dr;
  if (options.use_odometry && !dataset.odometry.empty()) {
    DeadReckoningOptions dr_options;
    dr_options.hold_through_gaps = true;
    if (!DeadReckon(dataset, dr_options, &dr, error)) {
      *error = prefix + *error;
      return nullptr;
    }
    dead_reckoning = std::make_unique<PiecewiseLinearMean>(dr.poses);
    report->fused_odometry = true;
  }

  // Localise each distinct observation time, seeded from a running
  // prediction: base(t) + state, base being dead reckoning (the state is then
  // its correction) or zero (the state is the pose). The state is a random
  // walk filtered through the fixes, one scalar Kalman filter per component,
  // so that one poor fix does not derail the seeds and held headings after
  // it.
  Eigen::Vector3d state = Eigen::Vector3d::Zero();
  Eigen::Vector3d state_variance;
  Eigen::Vector3d walk;
  if (dead_reckoning) {
    walk << options.walk_correction_position, options.walk_correction_position,
        options.walk_correction_heading;
  } else {
    state << first.pose.x, first.pose.y, first.pose.theta;
    walk << options.walk_position, options.walk_position, options.walk_heading;
  }
  state_variance << first.sigma_xy * first.sigma_xy,
      first.sigma_xy * first.sigma_xy, first.sigma_theta * first.sigma_theta;
  double state_time = first.pose.t;
  auto base = [&](double t) {
    return dead_reckoning ? dead_reckoning->Evaluate(t)
                          : Eigen::Vector3d::Zero().eval();
  };
  const std::vector<Observation>& all = dataset.observations;
  for (std::size_t begin = 0; begin < all.size();) {
    std::size_t end = begin;
    while (end < all.size() && all[end].t == all[begin].t) ++end;
    const std::vector<Observation> at(all.begin() + begin, all.begin() + end);
    const double t = all[begin].t;
    begin = end;
    ++report->times;

    const Eigen::Vector3d prediction = base(t) + state;
    const std::vector<MapObservation> usable = FindLandmarks(at, landmarks);
    const auto [equations, bearings] = CountMeasuredValues(usable);
    // Too few equations for (x, y, theta): hold the predicted heading.
    const bool hold_heading = bearings > 0 && equations < 3;
    const double heading = prediction.z();
    PoseFix fix;
    if (!LocalizeAgainst(usable, Seeds(at, usable, prediction),
                         hold_heading ? &heading : nullptr,
                         options.held_heading_sigma, &fix)) {
      continue;
    }
    fix.pose.t = t;
    if (fix.dof > 0 && fix.chi2 / fix.dof > options.max_chi2_per_dof) {
      ++report->rejected;
      continue;
    }
    report->fixes.push_back(fix);

    Eigen::Vector3d measured =
        Eigen::Vector3d(fix.pose.x, fix.pose.y, fix.pose.theta) - base(t);
    measured.z() = state.z() + WrapAngle(measured.z() - state.z());
    const double elapsed = std::abs(t - state_time);
    state_time = t;
    for (int k = 0; k < 3; ++k) {
      state_variance(k) += walk(k) * elapsed;
      if (k == 2 && !fix.has_heading) continue;
      const double gain =
          state_variance(k) / (state_variance(k) + fix.covariance(k, k));
      state(k) += gain * (measured(k) - state(k));
      state_variance(k) *= 1.0 - gain;
    }
  }
  report->localized = static_cast<int>(report->fixes.size());
  if (report->fixes.empty()) {
    *error = prefix + "none of the " + std::to_string(report->times) +
             " observation times could be localised against the " +
             std::to_string(landmarks.size()) +
             " landmark priors (too few observations of landmarks with "
             "priors at each time, or none that fit)";
    return nullptr;
  }

  const std::vector<Point> points = Points(dataset, report->fixes);
  bool any_heading = false;
  for (const PoseFix& f : report->fixes) any_heading |= f.has_heading;
  report->heading_from_velocity = !any_heading;

  if (!dead_reckoning) {
    Series position(2), heading(1);
    for (const Point& p : points) {
      position.Add(p.t, {p.pose.x(), p.pose.y()},
                   {p.variance.x(), p.variance.y()});
      if (p.has_heading) {
        double theta = p.pose.z();
        if (!heading.t.empty()) {
          theta = heading.values[0].back() +
                  WrapAngle(theta - heading.values[0].back());
        }
        heading.Add(p.t, {theta}, {p.variance.z()});
      }
    }
    std::vector<CubicSmoothingSpline> xy, theta;
    if (!RobustFit(position.t, position.values, position.variances,
                   options.position_smoothing, options, &xy, error)) {
      *error = prefix + *error;
      return nullptr;
    }
    if (any_heading) {
      if (!RobustFit(heading.t, heading.values, heading.variances,
                     options.heading_smoothing, options, &theta, error)) {
        *error = prefix + *error;
        return nullptr;
      }
    } else {
      theta.emplace_back();
    }
    return std::make_shared<SplineMean>(xy[0], xy[1], theta[0], !any_heading);
  }

  // With odometry: smooth the correction fix - dead reckoning, which drifts
  // slowly, and add it to dead reckoning at every node.
  Series position(2), heading(1);
  for (const Point& p : points) {
    const Eigen::Vector3d base = dead_reckoning->Evaluate(p.t);
    position.Add(p.t, {p.pose.x() - base.x(), p.pose.y() - base.y()},
                 {p.variance.x(), p.variance.y()});
    if (p.has_heading) {
      heading.Add(p.t, {WrapAngle(p.pose.z() - base.z())}, {p.variance.z()});
    }
  }
  std::vector<CubicSmoothingSpline> dxy, dtheta;
  if (!RobustFit(position.t, position.values, position.variances,
                 options.correction_smoothing, options, &dxy, error)) {
    *error = prefix + *error;
    return nullptr;
  }
  // Held at the end values outside the fixes (no extrapolation of drift).
  auto at = [](const CubicSmoothingSpline& s, double t) {
    return s.Evaluate(std::clamp(t, s.knots().front(), s.knots().back()));
  };
  if (!any_heading) {
    // Range-only: the heading correction is the turn between the dead
    // reckoned and the corrected direction of motion over a few seconds.
    heading = Series(1);
    const double half = kHeadingHalfWindow;
    for (const double t : position.t) {
      const Eigen::Vector3d a = dead_reckoning->Evaluate(t - half);
      const Eigen::Vector3d b = dead_reckoning->Evaluate(t + half);
      const Eigen::Vector2d v_dr = b.head<2>() - a.head<2>();
      const Eigen::Vector2d v =
          v_dr + Eigen::Vector2d(at(dxy[0], t + half) - at(dxy[0], t - half),
                                 at(dxy[1], t + half) - at(dxy[1], t - half));
      if (v_dr.norm() < kMinHeadingTravel || v.norm() < kMinHeadingTravel) {
        continue;
      }
      heading.Add(t,
                  {WrapAngle(std::atan2(v.y(), v.x()) -
                             std::atan2(v_dr.y(), v_dr.x()))},
                  {kTravelHeadingVariance});
    }
    if (heading.t.empty()) heading.Add(position.t.front(), {0.0}, {1.0});
  }
  if (!RobustFit(heading.t, heading.values, heading.variances,
                 options.correction_smoothing, options, &dtheta, error)) {
    *error = prefix + *error;
    return nullptr;
  }
  std::vector<TimedPose> poses;
  for (const TimedPose& p : dr.poses) {
    poses.push_back({p.t, p.x + at(dxy[0], p.t), p.y + at(dxy[1], p.t),
                     WrapAngle(p.theta + at(dtheta[0], p.t))});
  }
  return std::make_shared<PiecewiseLinearMean>(poses);
}

}  // namespace rff
