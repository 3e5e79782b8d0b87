#include "rff_ceres/state_trajectory.h"

#include <algorithm>
#include <cmath>
#include <typeinfo>

#include "rff_ceres/io/text_parser.h"

namespace rff {

std::vector<double> SmoothestChain(
    int n, const std::function<void(int, Eigen::Matrix2d*, Eigen::Vector2d*)>&
               interval) {
  std::vector<double> diagonal(n, 0.0), upper(n, 0.0), rhs(n, 0.0);
  for (int k = 0; k + 1 < n; ++k) {
    Eigen::Matrix2d h;
    Eigen::Vector2d g;
    interval(k, &h, &g);
    diagonal[k] += h(0, 0);
    diagonal[k + 1] += h(1, 1);
    upper[k] += h(0, 1);
    rhs[k] -= g(0);
    rhs[k + 1] -= g(1);
  }
  std::vector<double> x(std::max(n, 0), 0.0);
  if (n < 2) return x;
  for (int k = 1; k < n; ++k) {  // Forward elimination (the matrix is SPD).
    const double factor = upper[k - 1] / diagonal[k - 1];
    diagonal[k] -= factor * upper[k - 1];
    rhs[k] -= factor * rhs[k - 1];
  }
  x[n - 1] = rhs[n - 1] / diagonal[n - 1];
  for (int k = n - 2; k >= 0; --k) {
    x[k] = (rhs[k] - upper[k] * x[k + 1]) / diagonal[k];
  }
  return x;
}

bool StateTrajectory::ThinStateTimes(const std::string& name,
                                     const MeanFunction* mean,
                                     std::vector<double> state_times,
                                     double min_spacing,
                                     std::vector<double>* kept,
                                     std::string* error) {
  if (mean == nullptr) {
    *error = name + " needs a prior mean, got none";
    return false;
  }
  if (state_times.empty()) {
    *error = name + " needs at least one state time, got none";
    return false;
  }
  for (const double t : state_times) {
    if (!std::isfinite(t)) {
      *error = name + " state times must be finite, got " + FormatNumber(t);
      return false;
    }
  }
  std::sort(state_times.begin(), state_times.end());
  state_times.erase(std::unique(state_times.begin(), state_times.end()),
                    state_times.end());
  // The first time of each cluster is kept: kept times are at least
  // min_spacing apart (the last time too, or it is dropped).
  kept->clear();
  for (const double t : state_times) {
    if (kept->empty() || t - kept->back() >= min_spacing) kept->push_back(t);
  }
  return true;
}

StateTrajectory::StateTrajectory(int order,
                                 std::shared_ptr<const MeanFunction> mean,
                                 std::vector<double> times)
    : mean_(std::move(mean)), times_(std::move(times)), order_(order) {
  states_.assign(state_size() * times_.size(), 0.0);
  const double unit[3] = {1.0, 0.0, 0.0};
  for (int c = 0; c < 3; ++c) unit_phi_[c] = RowPhi(c, unit);
}

int StateTrajectory::num_blocks() const {
  return static_cast<int>(times_.size());
}

double* StateTrajectory::mutable_block(int block) {
  return states_.data() + state_size() * block;
}

const MeanFunction& StateTrajectory::mean() const { return *mean_; }

void StateTrajectory::set_mean(std::shared_ptr<const MeanFunction> mean) {
  mean_ = std::move(mean);
}

const std::vector<double>& StateTrajectory::state_times() const {
  return times_;
}

void StateTrajectory::SetStatesFromPoses(const std::vector<TimedPose>& poses) {
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
    for (int i = 0; i < n; ++i) {
      positions[i] = deviation[i][c];
      mutable_block(i)[c] = positions[i];
    }
    SetSmoothestDerivatives(c, positions);
  }
}

std::shared_ptr<const Eigen::VectorXd> StateTrajectory::RowPhi(
    int c, const double* weights) const {
  auto phi =
      std::make_shared<Eigen::VectorXd>(Eigen::VectorXd::Zero(state_size()));
  for (int j = 0; j < order_; ++j) (*phi)(c + 3 * j) = weights[j];
  return phi;
}

const StateTrajectory::Interpolation& StateTrajectory::InterpolationAt(
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
    // Outside the span: the Taylor polynomial of the nearest end state,
    // p + e v + e^2 / 2 a ...; at a state time that is its position alone.
    const int block = i < 0 ? 0 : i;
    const double elapsed = t - times_[block];
    interpolation.num_blocks = 1;
    interpolation.blocks[0] = block;
    double taylor[3] = {1.0, elapsed, 0.5 * elapsed * elapsed};
    for (int c = 0; c < 3; ++c) {
      interpolation.phi[0][c] =
          elapsed == 0.0 ? unit_phi_[c] : RowPhi(c, taylor);
    }
  } else {
    double lambda[3], psi[3];
    PositionRows(t - times_[i], times_[i + 1] - times_[i], lambda, psi);
    interpolation.num_blocks = 2;
    interpolation.blocks = {i, i + 1};
    for (int c = 0; c < 3; ++c) {
      interpolation.phi[0][c] = RowPhi(c, lambda);
      interpolation.phi[1][c] = RowPhi(c, psi);
    }
  }
  return cache_->emplace(t, std::move(interpolation)).first->second;
}

Eigen::Vector3d StateTrajectory::Pose(double t) const {
  // TrajectoryModel::Pose's sums over PoseAt's terms, in their order.
  Eigen::Vector3d pose = mean_->Evaluate(t);
  const Interpolation& interpolation = InterpolationAt(t);
  for (int k = 0; k < interpolation.num_blocks; ++k) {
    const Eigen::Map<const Eigen::VectorXd> state(
        block(interpolation.blocks[k]), state_size());
    for (int c = 0; c < 3; ++c) pose[c] += interpolation.phi[k][c]->dot(state);
  }
  return pose;
}

void StateTrajectory::AddPriorCosts(ceres::Problem* problem, int begin,
                                    int end) {
  if (begin == 0 && end > 0) {
    problem->AddResidualBlock(NewInitialStateCost(), nullptr, mutable_block(0));
  }
  for (int i = std::max(begin, 1) - 1; i + 1 < end; ++i) {
    problem->AddResidualBlock(NewMotionCost(times_[i + 1] - times_[i]), nullptr,
                              mutable_block(i), mutable_block(i + 1));
  }
}

double StateTrajectory::PriorLogNormaliser() const {
  // The first state's -sum log sigma, as logs: a product of sigmas leaves
  // double's range first.
  double sum = -InitialStateSigmas().array().log().sum();
  for (std::size_t i = 0; i + 1 < times_.size(); ++i) {
    sum += MotionLogDet(times_[i + 1] - times_[i]);
  }
  return sum;
}

bool StateTrajectory::AdoptScales(TrajectoryModel* rescaled) {
  if (rescaled == nullptr || typeid(*rescaled) != typeid(*this)) return false;
  const auto& same = static_cast<const StateTrajectory&>(*rescaled);
  // The initial-state prior and the states stay as they are.
  return same.times_ == times_ && same.mean_ == mean_ && TakeScales(same);
}

void StateTrajectory::UpdatePriorCosts(
    const std::vector<ceres::CostFunction*>& costs) const {
  for (ceres::CostFunction* cost : costs) SetMotionQc(cost);
}

void StateTrajectory::AdoptCaches(const TrajectoryModel& previous) {
  if (typeid(previous) != typeid(*this)) return;
  const auto& same = static_cast<const StateTrajectory&>(previous);
  if (same.times_ == times_) cache_ = same.cache_;
}

PoseMap StateTrajectory::PoseAt(double t) const {
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

std::vector<TrajectoryModel::PriorScale> StateTrajectory::PriorRowScales(
    const std::vector<double*>& blocks, int num_rows) const {
  std::vector<PriorScale> scales(num_rows, PriorScale::kNone);
  if (blocks.size() != 2) return scales;
  for (int row = 0; row < num_rows; ++row) {
    scales[row] = row % 3 == 2 ? PriorScale::kHeading : PriorScale::kPosition;
  }
  return scales;
}

}  // namespace rff
