#include "rff_ceres/pose_evidence.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <set>

#include "Eigen/Cholesky"
#include "Eigen/Eigenvalues"
#include "ceres/crs_matrix.h"
#include "ceres/problem.h"
#include "rff_ceres/trajectory_model.h"

namespace rff {
namespace {

// Eigenvalues of a pose's information below this fraction of its largest
// are directions the observations do not see.
constexpr double kRelativeRankTolerance = 1e-9;

// One free pose (a 3-block of offsets from x*) at each sample time: the
// model whose Jacobian is the data's in pose space. No prior.
class PoseSamples : public TrajectoryModel {
 public:
  PoseSamples(std::vector<double> times,
              std::shared_ptr<const PiecewiseLinearMean> at)
      : times_(std::move(times)),
        at_(std::move(at)),
        offsets_(3 * times_.size(), 0.0) {
    for (int c = 0; c < 3; ++c) {
      units_[c] =
          std::make_shared<const Eigen::VectorXd>(Eigen::VectorXd::Unit(3, c));
    }
  }

  int num_blocks() const override { return static_cast<int>(times_.size()); }
  int block_size(int) const override { return 3; }
  double* mutable_block(int block) override { return &offsets_[3 * block]; }

  // Only sample times are asked for (LinearizeInPoses samples every
  // observation time).
  PoseMap PoseAt(double t) const override {
    const int block = static_cast<int>(
        std::lower_bound(times_.begin(), times_.end(), t) - times_.begin());
    PoseMap map;
    map.mean = at_->Evaluate(t);
    for (int c = 0; c < 3; ++c) map.terms.push_back({block, c, units_[c]});
    return map;
  }
  void AddPriorCosts(ceres::Problem*, int, int) override {}
  const MeanFunction& mean() const override { return *at_; }
  void set_mean(std::shared_ptr<const MeanFunction>) override {}
  std::vector<PriorScale> PriorRowScales(const std::vector<double*>&,
                                         int num_rows) const override {
    return std::vector<PriorScale>(num_rows, PriorScale::kNone);
  }
  bool PriorScalesWhitenRows() const override { return false; }

 private:
  std::vector<double> times_;
  std::shared_ptr<const PiecewiseLinearMean> at_;
  std::vector<double> offsets_;
  // Coordinate c of a block is its offset of x, y or theta.
  std::array<std::shared_ptr<const Eigen::VectorXd>, 3> units_;
};

}  // namespace

bool LinearizeInPoses(const Dataset& dataset,
                      const std::vector<TimedPose>& estimate,
                      const std::map<LandmarkId, Eigen::Vector2d>& landmarks,
                      const ProblemOptions& problem_options,
                      const MeanFunction& mean, int max_times,
                      PoseLikelihood* likelihood, std::string* error) {
  *likelihood = PoseLikelihood();
  if (estimate.empty()) {
    *error = "linearising the data needs an estimate of the trajectory";
    return false;
  }
  std::set<double> distinct;
  for (const Observation& o : dataset.observations) distinct.insert(o.t);
  std::vector<double> times(distinct.begin(), distinct.end());
  if (times.size() > static_cast<size_t>(max_times)) times.resize(max_times);
  if (times.empty()) {
    *error = "no observations to learn the trajectory prior from";
    return false;
  }
  std::vector<LandmarkId> ids;
  for (const Observation& o : dataset.observations) {
    if (o.t <= times.back()) ids.push_back(o.id);
  }
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  for (const LandmarkId id : ids) {
    if (!landmarks.count(id)) {
      *error = "no estimate of landmark " + std::to_string(id);
      return false;
    }
  }

  PoseSamples samples(times, std::make_shared<PiecewiseLinearMean>(estimate));
  ProblemOptions options = problem_options;
  options.range_calibration.estimate = false;
  SlamProblem problem(&samples, options);
  if (!problem.Begin(ids, error)) return false;
  for (const LandmarkId id : ids) problem.AddLandmark(id, landmarks.at(id));
  for (const Observation& o : dataset.observations) {
    if (o.t <= times.back()) problem.AddObservation(o);
  }

  ceres::Problem::EvaluateOptions evaluate;
  for (int b = 0; b < samples.num_blocks(); ++b) {
    evaluate.parameter_blocks.push_back(samples.mutable_block(b));
  }
  std::vector<double> residuals;
  ceres::CRSMatrix jacobian;
  if (!problem.problem()->Evaluate(evaluate, nullptr, &residuals, nullptr,
                                   &jacobian)) {
    *error = "the observations cannot be evaluated at the estimate";
    return false;
  }
  const int n = static_cast<int>(times.size());
  std::vector<Eigen::Matrix3d> information(n, Eigen::Matrix3d::Zero());
  std::vector<Eigen::Vector3d> gradient(n, Eigen::Vector3d::Zero());
  for (int row = 0; row < jacobian.num_rows; ++row) {
    // Every row sees one pose: its entries lie in one block of three.
    Eigen::Vector3d j = Eigen::Vector3d::Zero();
    int block = -1;
    for (int k = jacobian.rows[row]; k < jacobian.rows[row + 1]; ++k) {
      block = jacobian.cols[k] / 3;
      j[jacobian.cols[k] % 3] = jacobian.values[k];
    }
    if (block < 0) continue;
    information[block] += j * j.transpose();
    gradient[block] -= j * residuals[row];
  }
  for (int i = 0; i < n; ++i) {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(information[i]);
    // Directions the observations do not see (a range-only fix) carry no
    // data: their whitened observation is zero.
    const double floor =
        kRelativeRankTolerance * eigen.eigenvalues().maxCoeff();
    Eigen::Vector3d root = Eigen::Vector3d::Zero();
    Eigen::Vector3d inverse_root = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) {
      if (eigen.eigenvalues()[k] > floor) {
        root[k] = std::sqrt(eigen.eigenvalues()[k]);
        inverse_root[k] = 1.0 / root[k];
      }
    }
    const Eigen::Matrix3d& v = eigen.eigenvectors();
    const Eigen::Vector3d deviation =
        samples.mean().Evaluate(times[i]) - mean.Evaluate(times[i]);
    likelihood->times.push_back(times[i]);
    likelihood->factors.push_back(v * root.asDiagonal());
    likelihood->whitened.push_back(
        root.asDiagonal() * (v.transpose() * deviation) +
        inverse_root.asDiagonal() * (v.transpose() * gradient[i]));
  }
  if (!std::all_of(likelihood->whitened.begin(), likelihood->whitened.end(),
                   [](const Eigen::Vector3d& y) { return y.allFinite(); })) {
    *error = "the linearised observations are not finite";
    return false;
  }
  return true;
}

double PoseLogEvidence(const PoseLikelihood& likelihood, const Kernel& position,
                       const Kernel& heading, Eigen::Vector3d* level) {
  if (level != nullptr) level->setZero();
  const int n = static_cast<int>(likelihood.times.size());
  const std::vector<Eigen::Matrix3d>& l = likelihood.factors;
  // M = I + L^T K L, block (i, j) = L_i^T diag(k_p, k_p, k_h)(t_i - t_j) L_j.
  Eigen::MatrixXd m(3 * n, 3 * n);
  Eigen::VectorXd y(3 * n);
  for (int i = 0; i < n; ++i) {
    y.segment<3>(3 * i) = likelihood.whitened[i];
    for (int j = 0; j <= i; ++j) {
      const double tau = likelihood.times[i] - likelihood.times[j];
      const double k_position = position.Evaluate(tau);
      const Eigen::Vector3d k(k_position, k_position, heading.Evaluate(tau));
      m.block<3, 3>(3 * i, 3 * j) = l[i].transpose() * k.asDiagonal() * l[j];
    }
  }
  m.diagonal().array() += 1.0;
  const Eigen::LLT<Eigen::MatrixXd, Eigen::Lower> llt(m);
  if (llt.info() != Eigen::Success) {
    return -std::numeric_limits<double>::infinity();
  }
  // The offset's columns B (B_i = L_i^T); with Z = L_M^-1 B, u = L_M^-1 y:
  // y^T P y = u^T u - u^T Z (Z^T Z)^-1 Z^T u, and log |B^T M^-1 B| joins.
  Eigen::MatrixXd offsets(3 * n, 3);
  for (int i = 0; i < n; ++i) offsets.middleRows<3>(3 * i) = l[i].transpose();
  const Eigen::VectorXd u = llt.matrixL().solve(y);
  const Eigen::MatrixXd z = llt.matrixL().solve(offsets);
  const Eigen::LDLT<Eigen::Matrix3d> gram(z.transpose() * z);
  const Eigen::Vector3d zu = z.transpose() * u;
  double quadratic = u.squaredNorm();
  double log_det = 2.0 * llt.matrixLLT().diagonal().array().log().sum();
  if (gram.info() == Eigen::Success && gram.isPositive() &&
      (gram.vectorD().array() > 0.0).all()) {
    const Eigen::Vector3d offset = gram.solve(zu);
    quadratic -= zu.dot(offset);
    if (level != nullptr) *level = offset;
    log_det += gram.vectorD().array().log().sum();
  }
  const double value = -0.5 * quadratic - 0.5 * log_det;
  return std::isfinite(value) ? value
                              : -std::numeric_limits<double>::infinity();
}

}  // namespace rff
