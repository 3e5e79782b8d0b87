#include "rff_ceres/hyperparameter_learning.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <set>

#include "glog/logging.h"
#include "rff_ceres/kernels/kernel.h"
#include "rff_ceres/pose_evidence.h"
#include "rff_ceres/se2.h"

namespace rff {
namespace {

// Below this spread (units^2) the initial trajectory is the mean itself.
constexpr double kMinSpread = 1e-4;

// The part of `dataset` up to `end` seconds: what the evidence is computed
// on. Landmarks outside it drop out unless they have a prior.
Dataset Window(const Dataset& dataset, double end) {
  Dataset window;
  window.pose_priors = dataset.pose_priors;
  window.pose_priors.erase(
      std::remove_if(window.pose_priors.begin(), window.pose_priors.end(),
                     [&](const PosePrior& p) { return p.pose.t > end; }),
      window.pose_priors.end());
  window.landmark_priors = dataset.landmark_priors;
  for (const Odometry& o : dataset.odometry) {
    if (o.t1 <= end) window.odometry.push_back(o);
  }
  for (const Observation& o : dataset.observations) {
    if (o.t <= end) window.observations.push_back(o);
  }
  return window;
}

// Parameters of the search: log lengthscale and log variance of the position
// and of the heading kernel.
using LogParameters = std::array<double, 4>;

LogParameters ToLog(const FeatureTrajectoryOptions& t) {
  return {std::log(t.position_kernel.lengthscale),
          std::log(t.position_kernel.variance),
          std::log(t.heading_kernel.lengthscale),
          std::log(t.heading_kernel.variance)};
}

void FromLog(const LogParameters& p, FeatureTrajectoryOptions* t) {
  t->position_kernel.lengthscale = std::exp(p[0]);
  t->position_kernel.variance = std::exp(p[1]);
  t->heading_kernel.lengthscale = std::exp(p[2]);
  t->heading_kernel.variance = std::exp(p[3]);
}

// Walks a grid of `step` from x0 (where f is f0) uphill for at most
// `max_steps` steps and, with `refine`, tries the vertex of the parabola
// through the best grid point and its neighbours. Returns the best value
// seen; f records its own best point.
double MaximizeAlongLine(const std::function<double(double)>& f, double x0,
                         double f0, double step, bool refine, int max_steps,
                         const std::function<double(double)>& clamp) {
  const double none = -std::numeric_limits<double>::infinity();
  double x = x0, fx = f0;
  double lo = clamp(x - step), hi = clamp(x + step);
  double f_hi = hi > x ? f(hi) : none;
  double f_lo = f_hi > fx ? none : (lo < x ? f(lo) : none);
  for (int k = 0; k < max_steps; ++k) {
    if (f_hi > fx && f_hi >= f_lo) {
      lo = x, f_lo = fx, x = hi, fx = f_hi;
      hi = clamp(x + step);
      f_hi = hi > x ? f(hi) : none;
    } else if (f_lo > fx) {
      hi = x, f_hi = fx, x = lo, fx = f_lo;
      lo = clamp(x - step);
      f_lo = lo < x ? f(lo) : none;
    } else {
      break;
    }
  }
  if (f_lo == none && lo < x && refine) f_lo = f(lo);
  const double curvature = f_lo + f_hi - 2.0 * fx;
  if (refine && std::isfinite(curvature) && curvature < 0.0) {
    fx = std::max(fx, f(clamp(x + 0.5 * step * (f_lo - f_hi) / curvature)));
  }
  return fx;
}

}  // namespace

void MatchVariancesToSpread(const MeanFunction& mean,
                            const std::vector<TimedPose>& initial,
                            FeatureTrajectoryOptions* trajectory) {
  if (initial.empty()) return;
  double position_spread = 0.0, heading_spread = 0.0;
  for (const TimedPose& p : initial) {
    const Eigen::Vector3d d =
        Eigen::Vector3d(p.x, p.y, p.theta) - mean.Evaluate(p.t);
    position_spread += 0.5 * d.head<2>().squaredNorm();
    heading_spread += std::pow(WrapAngle(d.z()), 2);
  }
  position_spread /= initial.size();
  heading_spread /= initial.size();
  if (position_spread > kMinSpread) {
    trajectory->position_kernel.variance = position_spread;
  }
  if (heading_spread > kMinSpread) {
    trajectory->heading_kernel.variance = heading_spread;
  }
}

bool LearnHyperparameters(
    const Dataset& dataset, std::shared_ptr<const MeanFunction> mean,
    const std::vector<TimedPose>& initial,
    const std::map<LandmarkId, Eigen::Vector2d>& landmarks,
    const ProblemOptions& problem_options, const LearningOptions& options,
    FeatureTrajectoryOptions* trajectory, LearningReport* report,
    std::string* error) {
  const auto start = std::chrono::steady_clock::now();
  *report = LearningReport();
  if (initial.empty()) {
    *error = "hyperparameter learning needs an initial trajectory";
    return false;
  }
  const double begin = initial.front().t;
  const double end = std::min(initial.back().t, begin + options.window);
  const Dataset window = Window(dataset, end);
  std::vector<TimedPose> window_initial;
  for (const TimedPose& p : initial) {
    if (p.t <= end) window_initial.push_back(p);
  }
  PoseLikelihood likelihood;
  if (!LinearizeInPoses(window, initial, landmarks, problem_options, *mean,
                        options.max_times, &likelihood, error)) {
    return false;
  }
  report->window_end = std::min(end, likelihood.times.back());

  FeatureTrajectoryOptions start_values = *trajectory;
  MatchVariancesToSpread(*mean, window_initial, &start_values);
  // The evidence of one candidate (and the data's level there); -inf where
  // a kernel cannot be built.
  auto log_evidence = [&](const LogParameters& p, Eigen::Vector3d* level) {
    FeatureTrajectoryOptions candidate = *trajectory;
    FromLog(p, &candidate);
    std::string why;
    const std::unique_ptr<Kernel> position =
        CreateKernel(candidate.position_kernel, &why);
    const std::unique_ptr<Kernel> heading =
        CreateKernel(candidate.heading_kernel, &why);
    if (!position || !heading) return -std::numeric_limits<double>::infinity();
    return PoseLogEvidence(likelihood, *position, *heading, level);
  };
  // The same, counted and logged: one step of the search.
  auto evidence = [&](const LogParameters& p) {
    ++report->evaluations;
    const double value = log_evidence(p, nullptr);
    VLOG(2) << "evidence at lengthscale " << std::exp(p[0]) << ", variance "
            << std::exp(p[1]) << ", heading lengthscale " << std::exp(p[2])
            << ", variance " << std::exp(p[3]) << ": " << value;
    return value;
  };

  const double min_log_lengthscale = std::log(options.min_lengthscale);
  const double max_log_lengthscale = std::log(std::max(end - begin, 1.0));
  auto clamp = [&](int i, double v) {
    return i % 2 == 0 ? std::clamp(v, min_log_lengthscale, max_log_lengthscale)
                      : std::clamp(v, std::log(options.min_variance),
                                   std::log(options.max_variance));
  };
  LogParameters best = ToLog(start_values);
  for (int i = 0; i < 4; ++i) best[i] = clamp(i, best[i]);
  double best_value = evidence(best);
  if (!std::isfinite(best_value)) {
    *error = "the evidence cannot be evaluated at the initial hyperparameters";
    return false;
  }
  // The evidence at `p`, keeping the best point.
  auto visit = [&](const LogParameters& p) {
    const double value = evidence(p);
    if (value > best_value) {
      best = p;
      best_value = value;
    }
    return value;
  };
  // Each kernel's lengthscale is searched with its variance profiled out
  // (maximised at every lengthscale): the evidence of a Matern kernel is
  // nearly flat along variance / lengthscale^(2 nu) = const, a ridge that a
  // search of one coordinate at a time cannot follow.
  double step = options.step;
  for (int sweep = 0; sweep < options.sweeps;
       ++sweep, step /= options.step_reduction) {
    for (const int kernel : {0, 2}) {
      auto profile = [&](double log_lengthscale) {
        LogParameters p = best;
        p[kernel] = log_lengthscale;
        const double value = visit(p);
        return MaximizeAlongLine(
            [&](double log_variance) {
              LogParameters q = p;
              q[kernel + 1] = log_variance;
              return visit(q);
            },
            p[kernel + 1], value, step, /*refine=*/true, options.max_steps,
            [&](double v) { return clamp(kernel + 1, v); });
      };
      // The start is profiled too: its variance may be far off the ridge.
      const double start_value = profile(best[kernel]);
      MaximizeAlongLine(profile, best[kernel], start_value, step,
                        /*refine=*/true, options.max_steps,
                        [&](double v) { return clamp(kernel, v); });
    }
  }
  log_evidence(best, &report->level);
  FromLog(best, trajectory);
  report->log_evidence = best_value;
  report->seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
          .count();
  return true;
}

}  // namespace rff
