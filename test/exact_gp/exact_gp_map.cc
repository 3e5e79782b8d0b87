#include "test/exact_gp/exact_gp_map.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <set>

#include "Eigen/Cholesky"
#include "Eigen/Dense"
#include "costs/angle.h"
#include "costs/bearing_cost.h"
#include "costs/range_cost.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/simulate_gp_draw.h"

namespace rff {
namespace {

// Dimensions of the stacked trajectory unknowns, in this order.
constexpr int kDims = 3;  // x, y, theta

// One residual's value and its Jacobian blocks: rows of the pose at one
// unknown time (may be absent) and of one landmark (may be absent).
struct ResidualBlock {
  int time = -1;      // Unknown-time index, or -1.
  int landmark = -1;  // Landmark index, or -1.
  Eigen::Vector2d r = Eigen::Vector2d::Zero();
  int rows = 0;  // 1 or 2 (pose priors are handled apart).
  Eigen::Matrix<double, 2, 3> d_pose = Eigen::Matrix<double, 2, 3>::Zero();
  Eigen::Matrix<double, 2, 2> d_landmark = Eigen::Matrix<double, 2, 2>::Zero();
};

// The problem in whitened coordinates p = (w_x, w_y, w_theta, landmarks).
class WhitenedProblem {
 public:
  WhitenedProblem(const Dataset& dataset, const ExactGpOptions& options,
                  std::vector<double> times)
      : dataset_(dataset), options_(options), times_(std::move(times)) {}

  bool Setup(const std::map<LandmarkId, Eigen::Vector2d>& initial_landmarks,
             std::string* error) {
    n_ = static_cast<int>(times_.size());
    for (int i = 0; i < n_; ++i) time_index_[times_[i]] = i;
    // Landmarks without a residual would leave J^T J singular: only the
    // observed or prior ones are unknowns.
    std::set<LandmarkId> used;
    for (const Observation& o : dataset_.observations) used.insert(o.id);
    for (const LandmarkPrior& p : dataset_.landmark_priors) used.insert(p.id);
    for (const LandmarkId id : used) {
      if (initial_landmarks.count(id) == 0) {
        *error = "landmark " + std::to_string(id) + " has no initial value";
        return false;
      }
      landmark_index_[id] = static_cast<int>(landmark_ids_.size());
      landmark_ids_.push_back(id);
    }
    m_ = static_cast<int>(landmark_ids_.size());
    if (!Factor(options_.position_kernel, &position_factor_, error) ||
        !Factor(options_.heading_kernel, &heading_factor_, error)) {
      return false;
    }
    mean_.setZero();
    if (options_.mean == "constant") {
      if (dataset_.pose_priors.empty()) {
        *error = "mean 'constant' needs a PRIOR_POSE";
        return false;
      }
      const PosePrior& first = *std::min_element(
          dataset_.pose_priors.begin(), dataset_.pose_priors.end(),
          [](const PosePrior& a, const PosePrior& b) {
            return a.pose.t < b.pose.t;
          });
      mean_ << first.pose.x, first.pose.y, first.pose.theta;
    } else if (options_.mean != "zero") {
      *error = "mean must be zero or constant, got '" + options_.mean + "'";
      return false;
    }
    return true;
  }

  int num_parameters() const { return kDims * n_ + 2 * m_; }
  int n() const { return n_; }
  const std::vector<LandmarkId>& landmark_ids() const { return landmark_ids_; }

  const Eigen::MatrixXd& factor(int dim) const {
    return dim < 2 ? position_factor_ : heading_factor_;
  }

  // Whitened coordinates of trajectory values f (N x 3): w_d = L_d^-1
  // (f_d - m_d).
  Eigen::VectorXd Whiten(const Eigen::MatrixXd& f,
                         const std::map<LandmarkId, Eigen::Vector2d>& l) const {
    Eigen::VectorXd p(num_parameters());
    for (int d = 0; d < kDims; ++d) {
      const Eigen::VectorXd centred =
          f.col(d) - Eigen::VectorXd::Constant(n_, mean_(d));
      p.segment(d * n_, n_) =
          factor(d).triangularView<Eigen::Lower>().solve(centred);
    }
    for (int j = 0; j < m_; ++j) {
      p.segment<2>(kDims * n_ + 2 * j) = l.at(landmark_ids_[j]);
    }
    return p;
  }

  // Trajectory values f (N x 3) of whitened coordinates.
  Eigen::MatrixXd Trajectory(const Eigen::VectorXd& p) const {
    Eigen::MatrixXd f(n_, kDims);
    for (int d = 0; d < kDims; ++d) {
      f.col(d) =
          factor(d).triangularView<Eigen::Lower>() * p.segment(d * n_, n_) +
          Eigen::VectorXd::Constant(n_, mean_(d));
    }
    return f;
  }

  Eigen::Vector2d Landmark(const Eigen::VectorXd& p, int j) const {
    return p.segment<2>(kDims * n_ + 2 * j);
  }

  // C(p); with `gradient` and `hessian` not null, also J^T r and J^T J.
  bool Evaluate(const Eigen::VectorXd& p, double* cost,
                Eigen::VectorXd* gradient, Eigen::MatrixXd* hessian) const {
    const Eigen::MatrixXd f = Trajectory(p);
    const bool derivatives = gradient != nullptr;
    // Measurement terms in (f, l) coordinates: per-time 3 x 3 blocks of
    // H_f, the f-gradient, the f-l coupling and the landmark blocks.
    std::vector<Eigen::Matrix3d> h_ff;
    Eigen::MatrixXd g_f, h_fl, h_ll;
    Eigen::VectorXd g_l;
    if (derivatives) {
      h_ff.assign(n_, Eigen::Matrix3d::Zero());
      g_f = Eigen::MatrixXd::Zero(n_, kDims);
      h_fl = Eigen::MatrixXd::Zero(kDims * n_, 2 * m_);
      h_ll = Eigen::MatrixXd::Zero(2 * m_, 2 * m_);
      g_l = Eigen::VectorXd::Zero(2 * m_);
    }
    double total = 0.5 * p.head(kDims * n_).squaredNorm();
    auto accumulate = [&](const ResidualBlock& b) {
      const auto r = b.r.head(b.rows);
      total += 0.5 * r.squaredNorm();
      if (!derivatives) return;
      if (b.time >= 0) {
        const auto jp = b.d_pose.topRows(b.rows);
        h_ff[b.time] += jp.transpose() * jp;
        g_f.row(b.time) += (jp.transpose() * r).transpose();
        if (b.landmark >= 0) {
          const auto jl = b.d_landmark.topRows(b.rows);
          const Eigen::Matrix<double, 3, 2> coupling = jp.transpose() * jl;
          for (int d = 0; d < kDims; ++d) {
            h_fl.block<1, 2>(d * n_ + b.time, 2 * b.landmark) +=
                coupling.row(d);
          }
        }
      }
      if (b.landmark >= 0) {
        const auto jl = b.d_landmark.topRows(b.rows);
        h_ll.block<2, 2>(2 * b.landmark, 2 * b.landmark) += jl.transpose() * jl;
        g_l.segment<2>(2 * b.landmark) += jl.transpose() * r;
      }
    };

    for (const Observation& o : dataset_.observations) {
      ResidualBlock b;
      b.time = time_index_.at(o.t);
      b.landmark = landmark_index_.at(o.id);
      const Eigen::Vector3d pose = f.row(b.time).transpose();
      const Eigen::Vector2d l = Landmark(p, b.landmark);
      Eigen::Vector3d d_pose;
      Eigen::Vector2d d_landmark;
      if (o.HasRange()) {
        double range;
        RangeAndGradient(pose, l, &range, &d_pose, &d_landmark);
        const double inverse = 1.0 / o.sigma_range;
        b.r(b.rows) = (range - o.range) * inverse;
        b.d_pose.row(b.rows) = d_pose.transpose() * inverse;
        b.d_landmark.row(b.rows) = d_landmark.transpose() * inverse;
        ++b.rows;
      }
      if (o.HasBearing()) {
        double bearing;
        if (!BearingAndGradient(pose, l, &bearing, &d_pose, &d_landmark)) {
          return false;
        }
        const double inverse = 1.0 / o.sigma_bearing;
        b.r(b.rows) = WrapAngle(bearing - o.bearing) * inverse;
        b.d_pose.row(b.rows) = d_pose.transpose() * inverse;
        b.d_landmark.row(b.rows) = d_landmark.transpose() * inverse;
        ++b.rows;
      }
      accumulate(b);
    }
    for (const LandmarkPrior& prior : dataset_.landmark_priors) {
      ResidualBlock b;
      b.landmark = landmark_index_.at(prior.id);
      b.rows = 2;
      b.r = (Landmark(p, b.landmark) - Eigen::Vector2d(prior.x, prior.y)) /
            prior.sigma;
      b.d_landmark = Eigen::Matrix2d::Identity() / prior.sigma;
      accumulate(b);
    }
    // PRIOR_POSE: three rows on one pose (as PosePriorCost).
    for (const PosePrior& prior : dataset_.pose_priors) {
      const int i = time_index_.at(prior.pose.t);
      const Eigen::Vector3d inverse(1.0 / prior.sigma_xy, 1.0 / prior.sigma_xy,
                                    1.0 / prior.sigma_theta);
      Eigen::Vector3d error =
          f.row(i).transpose() -
          Eigen::Vector3d(prior.pose.x, prior.pose.y, prior.pose.theta);
      error.z() = WrapAngle(error.z());
      const Eigen::Vector3d r = inverse.cwiseProduct(error);
      total += 0.5 * r.squaredNorm();
      if (derivatives) {
        h_ff[i] += inverse.cwiseAbs2().asDiagonal();
        g_f.row(i) += inverse.cwiseProduct(r).transpose();
      }
    }
    *cost = total;
    if (!derivatives) return std::isfinite(total);

    // Chain rule through f_d = m_d + L_d w_d: g_w = w + L^T g_f,
    // H_ww = I + L^T H_f L (block (d, e) = L_d^T diag(H_f,de) L_e),
    // H_wl = L^T H_fl.
    const int size = num_parameters();
    gradient->resize(size);
    hessian->setZero(size, size);
    for (int d = 0; d < kDims; ++d) {
      const auto l_d = factor(d).triangularView<Eigen::Lower>();
      gradient->segment(d * n_, n_) =
          p.segment(d * n_, n_) + l_d.transpose() * g_f.col(d);
      for (int e = d; e < kDims; ++e) {
        Eigen::VectorXd h_de(n_);
        for (int i = 0; i < n_; ++i) h_de(i) = h_ff[i](d, e);
        if (h_de.isZero(0.0)) continue;
        const Eigen::MatrixXd scaled =
            h_de.asDiagonal() *
            Eigen::MatrixXd(factor(e).triangularView<Eigen::Lower>());
        const Eigen::MatrixXd block = l_d.transpose() * scaled;
        hessian->block(d * n_, e * n_, n_, n_) = block;
        if (e != d) hessian->block(e * n_, d * n_, n_, n_) = block.transpose();
      }
      const Eigen::MatrixXd coupling =
          l_d.transpose() * h_fl.middleRows(d * n_, n_);
      hessian->block(d * n_, kDims * n_, n_, 2 * m_) = coupling;
      hessian->block(kDims * n_, d * n_, 2 * m_, n_) = coupling.transpose();
    }
    hessian->topLeftCorner(kDims * n_, kDims * n_).diagonal().array() += 1.0;
    hessian->bottomRightCorner(2 * m_, 2 * m_) = h_ll;
    gradient->tail(2 * m_) = g_l;
    return std::isfinite(total) && gradient->allFinite();
  }

 private:
  // Lower Cholesky factor of the kernel matrix with jitter.
  bool Factor(const KernelOptions& kernel_options, Eigen::MatrixXd* factor,
              std::string* error) const {
    const std::unique_ptr<Kernel> kernel = CreateKernel(kernel_options, error);
    if (!kernel) return false;
    Eigen::MatrixXd k(n_, n_);
    for (int i = 0; i < n_; ++i) {
      for (int j = 0; j <= i; ++j) {
        k(i, j) = k(j, i) = kernel->Evaluate(times_[i] - times_[j]);
      }
    }
    k.diagonal().array() += options_.jitter * kernel->variance();
    const Eigen::LLT<Eigen::MatrixXd> llt(k);
    if (llt.info() != Eigen::Success) {
      *error = "the " + kernel->name() +
               " kernel matrix is not positive definite (lengthscale " +
               FormatNumber(kernel->lengthscale()) + ")";
      return false;
    }
    *factor = llt.matrixL();
    return true;
  }

  const Dataset& dataset_;
  ExactGpOptions options_;
  std::vector<double> times_;
  int n_ = 0;
  int m_ = 0;
  std::map<double, int> time_index_;
  std::map<LandmarkId, int> landmark_index_;
  std::vector<LandmarkId> landmark_ids_;
  Eigen::MatrixXd position_factor_, heading_factor_;
  Eigen::Vector3d mean_ = Eigen::Vector3d::Zero();
};

// Laplace covariance of (w, l) is H^-1 (H the Gauss-Newton Hessian at the
// MAP); Cov(f_d(t_i), f_e(t_i)) = L_d(i, :) Cov(w_d, w_e) L_e(i, :)^T.
bool PoseCovariances(const WhitenedProblem& problem,
                     const Eigen::MatrixXd& hessian,
                     std::vector<Eigen::Matrix3d>* covariances,
                     std::string* error) {
  const Eigen::LLT<Eigen::MatrixXd> llt(hessian);
  if (llt.info() != Eigen::Success) {
    *error = "the Gauss-Newton Hessian is not positive definite";
    return false;
  }
  const int n = problem.n();
  const Eigen::MatrixXd inverse =
      llt.solve(Eigen::MatrixXd::Identity(hessian.rows(), hessian.cols()));
  covariances->assign(n, Eigen::Matrix3d::Zero());
  for (int d = 0; d < kDims; ++d) {
    for (int e = d; e < kDims; ++e) {
      const Eigen::MatrixXd left =
          problem.factor(d).triangularView<Eigen::Lower>() *
          inverse.block(d * n, e * n, n, n);
      const Eigen::VectorXd diagonal =
          left.cwiseProduct(problem.factor(e)).rowwise().sum();
      for (int i = 0; i < n; ++i) {
        (*covariances)[i](d, e) = (*covariances)[i](e, d) = diagonal(i);
      }
    }
  }
  return true;
}

}  // namespace

bool PositionNees(const Dataset& dataset, const ExactGpResult& result,
                  double* nees, std::string* error) {
  if (result.pose_covariances.size() != result.trajectory.size()) {
    *error = "the result has no pose covariances";
    return false;
  }
  std::vector<double> times;
  for (const TimedPose& p : result.trajectory) times.push_back(p.t);
  std::vector<TimedPose> truth;
  if (!InterpolateTrajectory(dataset.ground_truth, times, &truth, error,
                             "estimate")) {
    return false;
  }
  double sum = 0.0;
  for (std::size_t i = 0; i < times.size(); ++i) {
    const Eigen::Vector2d e(result.trajectory[i].x - truth[i].x,
                            result.trajectory[i].y - truth[i].y);
    const Eigen::Matrix2d sigma =
        result.pose_covariances[i].topLeftCorner<2, 2>();
    sum += e.dot(sigma.ldlt().solve(e));
  }
  *nees = sum / times.size();
  return true;
}

std::vector<double> ExactGpTimes(const Dataset& dataset) {
  std::vector<double> times;
  for (const Observation& o : dataset.observations) times.push_back(o.t);
  for (const TimedPose& p : dataset.ground_truth) times.push_back(p.t);
  for (const PosePrior& p : dataset.pose_priors) times.push_back(p.pose.t);
  std::sort(times.begin(), times.end());
  times.erase(std::unique(times.begin(), times.end()), times.end());
  return times;
}

bool InitialGuessFromGroundTruth(
    const Dataset& dataset, const std::vector<double>& times,
    std::vector<Eigen::Vector3d>* poses,
    std::map<LandmarkId, Eigen::Vector2d>* landmarks, std::string* error) {
  std::vector<TimedPose> interpolated;
  if (!InterpolateTrajectory(dataset.ground_truth, times, &interpolated, error,
                             "unknown")) {
    return false;
  }
  poses->clear();
  double heading = 0.0;
  for (std::size_t k = 0; k < interpolated.size(); ++k) {
    const TimedPose& p = interpolated[k];
    heading = k == 0 ? p.theta : heading + WrapAngle(p.theta - heading);
    poses->emplace_back(p.x, p.y, heading);
  }
  landmarks->clear();
  for (const Landmark& l : dataset.ground_truth_landmarks) {
    (*landmarks)[l.id] = Eigen::Vector2d(l.x, l.y);
  }
  return true;
}

bool SolveExactGpMap(
    const Dataset& dataset, const ExactGpOptions& options,
    const std::vector<Eigen::Vector3d>& initial_poses,
    const std::map<LandmarkId, Eigen::Vector2d>& initial_landmarks,
    ExactGpResult* result, std::string* error) {
  *result = ExactGpResult();
  if (!dataset.odometry.empty()) {
    *error = "the exact-GP reference does not model odometry";
    return false;
  }
  const std::vector<double> times = ExactGpTimes(dataset);
  if (initial_poses.size() != times.size()) {
    *error = "expected " + std::to_string(times.size()) +
             " initial poses, got " + std::to_string(initial_poses.size());
    return false;
  }
  WhitenedProblem problem(dataset, options, times);
  if (!problem.Setup(initial_landmarks, error)) return false;
  Eigen::MatrixXd f(times.size(), kDims);
  for (std::size_t i = 0; i < times.size(); ++i) {
    f.row(i) = initial_poses[i].transpose();
  }
  Eigen::VectorXd p = problem.Whiten(f, initial_landmarks);

  // Levenberg-Marquardt (Nielsen's damping update): the step solves
  // (H + lambda diag(H)) delta = -g; a step that lowers C is taken and
  // lambda shrinks, otherwise lambda grows and the step is tried again.
  double cost;
  Eigen::VectorXd gradient;
  Eigen::MatrixXd hessian;
  if (!problem.Evaluate(p, &cost, &gradient, &hessian)) {
    *error = "the initial value gives a non-finite cost";
    return false;
  }
  result->initial_cost = cost;
  double lambda = 1e-6;
  double growth = 2.0;
  int iteration = 0;
  for (; iteration < options.max_iterations; ++iteration) {
    if (gradient.lpNorm<Eigen::Infinity>() <= options.gradient_tolerance) break;
    Eigen::MatrixXd damped = hessian;
    damped.diagonal() += lambda * hessian.diagonal();
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(damped);
    if (ldlt.info() != Eigen::Success) {
      *error = "the damped normal equations could not be factorised";
      return false;
    }
    const Eigen::VectorXd step = ldlt.solve(-gradient);
    const Eigen::VectorXd candidate = p + step;
    double candidate_cost;
    const bool finite =
        problem.Evaluate(candidate, &candidate_cost, nullptr, nullptr);
    // Gain ratio: actual over predicted decrease of the quadratic model.
    const double predicted =
        -(gradient.dot(step) + 0.5 * step.dot(hessian * step));
    if (finite && candidate_cost < cost) {
      const double rho = (cost - candidate_cost) / std::max(predicted, 1e-300);
      p = candidate;
      if (!problem.Evaluate(p, &cost, &gradient, &hessian)) {
        *error = "non-finite derivatives at an accepted step";
        return false;
      }
      lambda *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3));
      growth = 2.0;
    } else {
      lambda *= growth;
      growth *= 2.0;
      if (lambda > 1e12) break;  // No descent at any damping: stalled.
    }
  }
  result->iterations = iteration;
  result->cost = cost;
  result->gradient_max_norm = gradient.lpNorm<Eigen::Infinity>();
  result->converged = result->gradient_max_norm <= options.gradient_tolerance;

  if (options.compute_covariance &&
      !PoseCovariances(problem, hessian, &result->pose_covariances, error)) {
    return false;
  }
  f = problem.Trajectory(p);
  for (std::size_t i = 0; i < times.size(); ++i) {
    result->trajectory.push_back(
        {times[i], f(i, 0), f(i, 1), WrapAngle(f(i, 2))});
  }
  for (int j = 0; j < static_cast<int>(problem.landmark_ids().size()); ++j) {
    Landmark l;
    l.id = problem.landmark_ids()[j];
    l.x = problem.Landmark(p, j).x();
    l.y = problem.Landmark(p, j).y();
    result->landmarks.push_back(l);
  }
  return true;
}

bool SetTruthKernels(const Dataset& dataset, ExactGpOptions* options,
                     std::string* error) {
  for (const auto& [key, value] : dataset.metadata) {
    if (key == "truth") {
      return ParseGpDrawTruth(value, &options->position_kernel,
                              &options->heading_kernel, error);
    }
  }
  *error = "the dataset has no '# truth:' line";
  return false;
}

bool SolveExactGpMapFromGroundTruth(const Dataset& dataset,
                                    const ExactGpOptions& options,
                                    ExactGpResult* result,
                                    Evaluation* evaluation,
                                    std::string* error) {
  const std::vector<double> times = ExactGpTimes(dataset);
  std::vector<Eigen::Vector3d> poses;
  std::map<LandmarkId, Eigen::Vector2d> landmarks;
  if (!InitialGuessFromGroundTruth(dataset, times, &poses, &landmarks, error) ||
      !SolveExactGpMap(dataset, options, poses, landmarks, result, error)) {
    return false;
  }
  return Evaluate(dataset.ground_truth, dataset.ground_truth_landmarks,
                  result->trajectory, &result->landmarks, EvaluationOptions(),
                  evaluation, error);
}

}  // namespace rff
