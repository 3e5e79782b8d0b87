#include "rff_ceres/wnoa_trajectory.h"

#include <algorithm>
#include <cmath>

#include "costs/wnoa_initial_state_cost.h"
#include "costs/wnoa_prior_cost.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/option_error.h"

namespace rff {
namespace {

// The 6-vector that reads a * p_c + b * v_c from a state.
std::shared_ptr<const Eigen::VectorXd> RowPhi(int coordinate, double a,
                                              double b) {
  auto phi = std::make_shared<Eigen::VectorXd>(
      Eigen::VectorXd::Zero(WnoaTrajectory::kStateSize));
  (*phi)(coordinate) = a;
  (*phi)(coordinate + 3) = b;
  return phi;
}

// The velocities that minimise the WNOA energy sum_k e_k^T Q_k^-1 e_k of one
// coordinate with its positions held (wnoa_prior_cost.h; q_c cancels): a
// symmetric tridiagonal system, solved by elimination. Central differences
// would disagree across states microseconds apart, where Q^-1 ~ dt^-3 turns
// that into a prior cost of 10^5 and a solve that leaves its start.
std::vector<double> SmoothestVelocities(const std::vector<double>& times,
                                        const std::vector<double>& positions) {
  const int n = static_cast<int>(times.size());
  std::vector<double> diagonal(n, 0.0), upper(n, 0.0), rhs(n, 0.0);
  for (int k = 0; k + 1 < n; ++k) {
    const double dt = times[k + 1] - times[k];
    const double d = positions[k + 1] - positions[k];
    // e = (d - dt v_k, v_k+1 - v_k); Q^-1 = [12/dt^3 -6/dt^2; -6/dt^2 4/dt].
    const double a = 12.0 / (dt * dt * dt), b = -6.0 / (dt * dt), c = 4.0 / dt;
    // e = r0 + J (v_k, v_k+1) with r0 = (d, 0), J = [-dt 0; -1 1].
    const Eigen::Matrix2d q_inverse =
        (Eigen::Matrix2d() << a, b, b, c).finished();
    const Eigen::Matrix2d jacobian =
        (Eigen::Matrix2d() << -dt, 0.0, -1.0, 1.0).finished();
    const Eigen::Matrix2d h = jacobian.transpose() * q_inverse * jacobian;
    const Eigen::Vector2d g =
        jacobian.transpose() * q_inverse * Eigen::Vector2d(d, 0.0);
    diagonal[k] += h(0, 0);
    diagonal[k + 1] += h(1, 1);
    upper[k] += h(0, 1);
    rhs[k] -= g(0);
    rhs[k + 1] -= g(1);
  }
  std::vector<double> velocity(n, 0.0);
  if (n < 2) return velocity;
  for (int k = 1; k < n; ++k) {  // Forward elimination (the matrix is SPD).
    const double factor = upper[k - 1] / diagonal[k - 1];
    diagonal[k] -= factor * upper[k - 1];
    rhs[k] -= factor * rhs[k - 1];
  }
  velocity[n - 1] = rhs[n - 1] / diagonal[n - 1];
  for (int k = n - 2; k >= 0; --k) {
    velocity[k] = (rhs[k] - upper[k] * velocity[k + 1]) / diagonal[k];
  }
  return velocity;
}

}  // namespace

std::unique_ptr<WnoaTrajectory> WnoaTrajectory::Create(
    const WnoaOptions& options, std::shared_ptr<const MeanFunction> mean,
    std::vector<double> state_times, std::string* error) {
  if (!CheckPositiveOption(options.position_qc, "wnoa_position_qc", error) ||
      !CheckPositiveOption(options.heading_qc, "wnoa_heading_qc", error) ||
      !CheckPositiveOption(options.initial_position_sigma,
                           "wnoa_initial_position_sigma", error) ||
      !CheckPositiveOption(options.initial_heading_sigma,
                           "wnoa_initial_heading_sigma", error) ||
      !CheckPositiveOption(options.initial_velocity_sigma,
                           "wnoa_initial_velocity_sigma", error) ||
      !CheckPositiveOption(options.initial_angular_velocity_sigma,
                           "wnoa_initial_angular_velocity_sigma", error) ||
      !CheckNonNegativeOption(options.min_state_spacing,
                              "wnoa_min_state_spacing", error)) {
    return nullptr;
  }
  if (!mean) {
    *error = "wnoa needs a prior mean, got none";
    return nullptr;
  }
  if (state_times.empty()) {
    *error = "wnoa needs at least one state time, got none";
    return nullptr;
  }
  for (const double t : state_times) {
    if (!std::isfinite(t)) {
      *error = "wnoa state times must be finite, got " + FormatNumber(t);
      return nullptr;
    }
  }
  std::sort(state_times.begin(), state_times.end());
  state_times.erase(std::unique(state_times.begin(), state_times.end()),
                    state_times.end());

  std::unique_ptr<WnoaTrajectory> model(new WnoaTrajectory);
  model->options_ = options;
  model->mean_ = std::move(mean);
  // The first time of each cluster is kept: kept times are at least
  // min_state_spacing apart (the last time too, or it is dropped).
  for (const double t : state_times) {
    if (model->times_.empty() ||
        t - model->times_.back() >= options.min_state_spacing) {
      model->times_.push_back(t);
    }
  }
  model->states_.assign(kStateSize * model->times_.size(), 0.0);
  for (int c = 0; c < 3; ++c) model->unit_phi_[c] = RowPhi(c, 1.0, 0.0);
  return model;
}

int WnoaTrajectory::num_blocks() const {
  return static_cast<int>(times_.size());
}

double* WnoaTrajectory::mutable_block(int block) {
  return states_.data() + kStateSize * block;
}

const MeanFunction& WnoaTrajectory::mean() const { return *mean_; }

void WnoaTrajectory::set_mean(std::shared_ptr<const MeanFunction> mean) {
  mean_ = std::move(mean);
}

const std::vector<double>& WnoaTrajectory::state_times() const {
  return times_;
}

void WnoaTrajectory::SetStatesFromPoses(const std::vector<TimedPose>& poses) {
  const PiecewiseLinearMean target(poses);
  const int n = static_cast<int>(times_.size());
  std::vector<Eigen::Vector3d> deviation(n);
  for (int i = 0; i < n; ++i) {
    deviation[i] = target.Evaluate(times_[i]) - mean_->Evaluate(times_[i]);
    deviation[i].z() = WrapAngle(deviation[i].z());
    if (i > 0) {  // Continuous heading deviation between states.
      deviation[i].z() = deviation[i - 1].z() +
                         WrapAngle(deviation[i].z() - deviation[i - 1].z());
    }
  }
  for (int c = 0; c < 3; ++c) {
    std::vector<double> positions(n);
    for (int i = 0; i < n; ++i) positions[i] = deviation[i][c];
    const std::vector<double> velocity = SmoothestVelocities(times_, positions);
    for (int i = 0; i < n; ++i) {
      mutable_block(i)[c] = positions[i];
      mutable_block(i)[3 + c] = velocity[i];
    }
  }
}

void WnoaTrajectory::InterpolationMatrices(double elapsed, double dt,
                                           Eigen::Matrix2d* lambda,
                                           Eigen::Matrix2d* psi) {
  // Psi = Q_tau Phi(t_{i+1}, tau)^T Q_i^-1 and Lambda = Phi(tau, t_i) -
  // Psi Phi(dt) multiplied out: the cubic Hermite basis, with no inverse of
  // the ill-conditioned Q_i.
  const double s = elapsed / dt;
  const double r = 1.0 - s;
  const double h01 = s * s * (3.0 - 2.0 * s);
  *lambda << 1.0 - h01, elapsed * r * r, -6.0 * s * r / dt, r * (1.0 - 3.0 * s);
  *psi << h01, -elapsed * s * r, 6.0 * s * r / dt, s * (3.0 * s - 2.0);
}

const WnoaTrajectory::Interpolation& WnoaTrajectory::InterpolationAt(
    double t) const {
  auto it = cache_->find(t);
  if (it != cache_->end()) return it->second;
  Interpolation interpolation;
  // Only differences of nearby times enter the coefficients, computed from
  // the raw times: as precise as shifting to t_0 first, and exact at t_i.
  const int last = num_blocks() - 1;
  const auto upper = std::upper_bound(times_.begin(), times_.end(), t);
  const int i = static_cast<int>(upper - times_.begin()) - 1;
  if (i < 0 || i >= last || t == times_[i]) {
    // Outside the span: constant velocity from the nearest end state, p +
    // (t - t_end) v; at a state time that is the state's position alone.
    const int block = i < 0 ? 0 : i;
    const double elapsed = t - times_[block];
    interpolation.num_blocks = 1;
    interpolation.blocks[0] = block;
    for (int c = 0; c < 3; ++c) {
      interpolation.phi[0][c] =
          elapsed == 0.0 ? unit_phi_[c] : RowPhi(c, 1.0, elapsed);
    }
  } else {
    Eigen::Matrix2d lambda, psi;
    InterpolationMatrices(t - times_[i], times_[i + 1] - times_[i], &lambda,
                          &psi);
    interpolation.num_blocks = 2;
    interpolation.blocks = {i, i + 1};
    for (int c = 0; c < 3; ++c) {
      interpolation.phi[0][c] = RowPhi(c, lambda(0, 0), lambda(0, 1));
      interpolation.phi[1][c] = RowPhi(c, psi(0, 0), psi(0, 1));
    }
  }
  return cache_->emplace(t, std::move(interpolation)).first->second;
}

Eigen::Vector3d WnoaTrajectory::Pose(double t) const {
  // TrajectoryModel::Pose's sums over PoseAt's terms, in their order.
  Eigen::Vector3d pose = mean_->Evaluate(t);
  const Interpolation& interpolation = InterpolationAt(t);
  for (int k = 0; k < interpolation.num_blocks; ++k) {
    const Eigen::Map<const Eigen::VectorXd> state(
        block(interpolation.blocks[k]), kStateSize);
    for (int c = 0; c < 3; ++c) pose[c] += interpolation.phi[k][c]->dot(state);
  }
  return pose;
}

void WnoaTrajectory::AdoptCaches(const TrajectoryModel& previous) {
  const auto* wnoa = dynamic_cast<const WnoaTrajectory*>(&previous);
  if (wnoa != nullptr && wnoa->times_ == times_) cache_ = wnoa->cache_;
}

bool WnoaTrajectory::AdoptScales(TrajectoryModel* rescaled) {
  const auto* wnoa = dynamic_cast<const WnoaTrajectory*>(rescaled);
  if (wnoa == nullptr || wnoa->times_ != times_ || wnoa->mean_ != mean_) {
    return false;
  }
  const WnoaOptions& o = wnoa->options_;
  // The initial-state prior and the states stay as they are.
  if (o.initial_position_sigma != options_.initial_position_sigma ||
      o.initial_heading_sigma != options_.initial_heading_sigma ||
      o.initial_velocity_sigma != options_.initial_velocity_sigma ||
      o.initial_angular_velocity_sigma !=
          options_.initial_angular_velocity_sigma ||
      o.min_state_spacing != options_.min_state_spacing) {
    return false;
  }
  options_.position_qc = o.position_qc;
  options_.heading_qc = o.heading_qc;
  return true;
}

void WnoaTrajectory::UpdatePriorCosts(
    const std::vector<ceres::CostFunction*>& costs) const {
  for (ceres::CostFunction* cost : costs) {
    if (auto* motion = dynamic_cast<WnoaPriorCost*>(cost)) {
      motion->SetQc(options_.position_qc, options_.position_qc,
                    options_.heading_qc);
    }
  }
}

PoseMap WnoaTrajectory::PoseAt(double t) const {
  PoseMap map;
  map.mean = mean_->Evaluate(t);
  const Interpolation& interpolation = InterpolationAt(t);
  map.terms.reserve(3 * interpolation.num_blocks);  // One allocation.
  for (int k = 0; k < interpolation.num_blocks; ++k) {
    for (int c = 0; c < 3; ++c) {
      map.terms.push_back(
          {interpolation.blocks[k], c, interpolation.phi[k][c]});
    }
  }
  return map;
}

std::vector<TrajectoryModel::PriorScale> WnoaTrajectory::PriorRowScales(
    const std::vector<double*>& blocks, int num_rows) const {
  if (blocks.size() != 2) return std::vector<PriorScale>(num_rows, PriorScale::kNone);
  const PriorScale p = PriorScale::kPosition, h = PriorScale::kHeading;
  return {p, p, h, p, p, h};
}

void WnoaTrajectory::AddPriorCosts(ceres::Problem* problem, int begin,
                                   int end) {
  if (begin == 0 && end > 0) {
    WnoaInitialStateCost::Vector6 sigma;
    sigma << options_.initial_position_sigma, options_.initial_position_sigma,
        options_.initial_heading_sigma, options_.initial_velocity_sigma,
        options_.initial_velocity_sigma,
        options_.initial_angular_velocity_sigma;
    problem->AddResidualBlock(new WnoaInitialStateCost(sigma), nullptr,
                              mutable_block(0));
  }
  for (int i = std::max(begin, 1) - 1; i + 1 < end; ++i) {
    problem->AddResidualBlock(
        new WnoaPriorCost(times_[i + 1] - times_[i], options_.position_qc,
                          options_.position_qc, options_.heading_qc),
        nullptr, mutable_block(i), mutable_block(i + 1));
  }
}

}  // namespace rff
