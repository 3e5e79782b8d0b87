#include "rff_ceres/posterior_covariance.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <set>
#include <utility>

#include "Eigen/Eigenvalues"
#include "ceres/covariance.h"
#include "rff_ceres/banded_problem.h"
#include "rff_ceres/envelope_cholesky.h"
#include "rff_ceres/gauss_newton_system.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/option_error.h"
#include "rff_ceres/selected_inverse.h"
#include "rff_ceres/variance_components.h"

namespace rff {
namespace {

using RowMajorMatrix =
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Landmarks whose own 2x2 block of J^T J (robustified, as Ceres's
// covariance sees it) is singular: the data fix fewer than two directions of
// them (one range, or bearings from one place), so the whole information
// matrix is singular too. A prior fixes both: beside it a block only looks
// singular where a bearing seen from on top of the landmark dwarfs it.
std::vector<LandmarkId> UnconstrainedLandmarks(
    SlamProblem* problem, const std::vector<LandmarkId>& ids) {
  std::vector<LandmarkId> unconstrained;
  for (const LandmarkId id : ids) {
    if (!problem->has_landmark(id) || problem->has_landmark_prior(id)) {
      continue;
    }
    const Eigen::Vector2d eigenvalues =
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(
            problem->LandmarkInformation(id, /*apply_loss=*/true),
            Eigen::EigenvaluesOnly)
            .eigenvalues();
    if (!(eigenvalues[0] > 1e-12 * std::max(eigenvalues[1], 1e-300))) {
      unconstrained.push_back(id);
    }
  }
  return unconstrained;
}

// `method`: what failed, e.g. "ceres::Covariance (SPARSE_QR) failed: ".
std::string SingularMessage(SlamProblem* problem,
                            const std::vector<Landmark>& landmarks,
                            const std::string& method) {
  std::vector<LandmarkId> ids;
  for (const Landmark& l : landmarks) ids.push_back(l.id);
  const std::vector<LandmarkId> unconstrained =
      UnconstrainedLandmarks(problem, ids);
  std::string message = "posterior covariance: " + method +
                        "the information matrix J^T J is singular";
  if (unconstrained.empty()) return message;
  message += "; the data do not fix the position of landmark";
  if (unconstrained.size() > 1) message += "s";
  for (std::size_t k = 0; k < unconstrained.size() && k < 10; ++k) {
    message += (k == 0 ? " " : ", ") + std::to_string(unconstrained[k]);
  }
  if (unconstrained.size() > 10) {
    message += " and " + std::to_string(unconstrained.size() - 10) + " more";
  }
  message +=
      " (e.g. one range or bearings from one place only; a landmark prior "
      "fixes it)";
  return message;
}

// The Jacobian of every residual (through its loss) with the columns in
// LandmarksLast's order, each parameter block's first column, and the
// number of columns before the landmarks'.
struct LinearizedProblem {
  RowMajorSparse jacobian;
  std::map<const double*, int> offsets;
  int num_leading = 0;
};

// False where a block is held constant or the problem cannot be evaluated
// (ceres::Covariance evaluates it again and reports).
bool LinearizeLandmarksLast(SlamProblem* problem, LinearizedProblem* out) {
  ceres::Problem* ceres_problem = problem->problem();
  const std::vector<double*> columns =
      LandmarksLast(problem, &out->num_leading);
  int at = 0;
  for (double* block : columns) {
    if (ceres_problem->IsParameterBlockConstant(block)) return false;
    out->offsets[block] = at;
    at += ceres_problem->ParameterBlockSize(block);
  }
  std::vector<ceres::ResidualBlockId> ids;
  ceres_problem->GetResidualBlocks(&ids);
  double cost = 0.0;
  Eigen::VectorXd residuals;
  std::string why_not;
  return Linearize(ceres_problem, ids, &cost, &residuals, &out->jacobian,
                   &why_not, columns);
}

// Sigma(a, b) of the trajectory block pairs (a <= b) and the landmarks'.
struct CovarianceBlocks {
  std::map<std::pair<int, int>, Eigen::MatrixXd> trajectory;
  std::map<LandmarkId, Eigen::Matrix2d> landmarks;
};

// The blocks from the Schur form of J^T J (gauss_newton_system.h), linear
// in the landmarks. False, with nothing filled, where the problem has not
// that form (sizes, a residual on two landmarks, an
// ill-conditioned landmark) or J^T J is not positive definite.
bool SchurCovariance(SlamProblem* problem, const TrajectoryModel& model,
                     const LinearizedProblem& linearized,
                     const std::set<std::pair<int, int>>& block_pairs,
                     const std::vector<Landmark>& landmarks,
                     CovarianceBlocks* blocks) {
  const int t = linearized.num_leading;
  if (!SchurFormFits(t, linearized.jacobian.cols() - t)) return false;
  const std::map<const double*, int>& offset = linearized.offsets;
  // Not structured or not positive definite: the QR of J (Ceres) decides,
  // and names the landmarks the data leave free.
  const GaussNewtonSystem system(linearized.jacobian, t,
                                 Factorization::kSchurOnly);
  if (!system.structured() || !system.positive_definite()) return false;
  const Eigen::MatrixXd leading = system.LeadingCovariance();
  for (const auto& [a, b] : block_pairs) {
    blocks->trajectory[{a, b}] =
        leading.block(offset.at(model.block(a)), offset.at(model.block(b)),
                      model.block_size(a), model.block_size(b));
  }
  const std::vector<Eigen::Matrix2d> covariances = system.LandmarkCovariances();
  for (const Landmark& l : landmarks) {
    blocks->landmarks[l.id] =
        covariances[(offset.at(problem->landmark_block(l.id)) - t) / 2];
  }
  return true;
}

// The blocks from computed entries of (J^T J)^-1: `column(block)` the
// first column of a parameter block (-1 for none), `entry(i, j, &value)`
// false where (i, j) was not computed. False, with nothing filled, where a
// block needed was not.
template <typename Column, typename Entry>
bool FillBlocks(SlamProblem* problem, const TrajectoryModel& model,
                const std::set<std::pair<int, int>>& block_pairs,
                const std::vector<Landmark>& landmarks, Column column,
                Entry entry, CovarianceBlocks* blocks) {
  ceres::Problem* ceres_problem = problem->problem();
  auto fill = [&](const double* a, const double* b, Eigen::MatrixXd* block) {
    const int rows = ceres_problem->ParameterBlockSize(a);
    const int cols = ceres_problem->ParameterBlockSize(b);
    const int first_row = column(a), first_col = column(b);
    if (first_row < 0 || first_col < 0) return false;
    block->resize(rows, cols);
    for (int i = 0; i < rows; ++i) {
      for (int j = 0; j < cols; ++j) {
        if (!entry(first_row + i, first_col + j, &(*block)(i, j))) {
          return false;
        }
      }
    }
    return true;
  };
  CovarianceBlocks filled;
  Eigen::MatrixXd block;
  for (const auto& [a, b] : block_pairs) {
    if (!fill(model.block(a), model.block(b), &block)) return false;
    filled.trajectory[{a, b}] = block;
  }
  for (const Landmark& l : landmarks) {
    const double* parameters = problem->landmark_block(l.id);
    if (!fill(parameters, parameters, &block)) return false;
    filled.landmarks[l.id] = block;
  }
  *blocks = std::move(filled);
  return true;
}

// The blocks from H^-1 on the time-ordered envelope of a banded system
// (FactorizeBanded: the solve's own H where it left one). False, with
// nothing filled, where the envelope does not serve, H is not positive
// definite or singular to rounding (kMinReciprocalCondition: a QR of J
// then decides and names the free landmarks), or a block lies outside the
// envelope.
bool EnvelopeCovariance(SlamProblem* problem, const TrajectoryModel& model,
                        const std::set<std::pair<int, int>>& block_pairs,
                        const std::vector<Landmark>& landmarks,
                        CovarianceBlocks* blocks) {
  BandedSystem system;
  if (!FactorizeBanded(problem, &system) ||
      !system.factor->InvertOnEnvelope(/*rcond=*/nullptr,
                                       kMinReciprocalCondition)) {
    return false;
  }
  const BandedProblem& banded = *system.banded;
  const EnvelopeMatrix& inverse = *system.factor;
  return FillBlocks(
      problem, model, block_pairs, landmarks,
      [&](const double* block) { return banded.ColumnOf(block); },
      [&](int i, int j, double* value) {
        if (std::min(i, j) < inverse.first(std::max(i, j))) return false;
        *value = inverse.Symmetric(i, j);
        return true;
      },
      blocks);
}

// The same blocks from the selected inverse of a sparse Cholesky of J^T J
// (selected_inverse.h), where every block needed lies on its factor's
// pattern. False, with nothing filled, where J^T J is not positive definite,
// the factor is too large or a block is off its pattern.
constexpr std::int64_t kMaxSelectedInverseNonzeros = std::int64_t{1} << 25;
bool SelectedInverseCovariance(SlamProblem* problem,
                               const TrajectoryModel& model,
                               const LinearizedProblem& linearized,
                               const std::set<std::pair<int, int>>& block_pairs,
                               const std::vector<Landmark>& landmarks,
                               CovarianceBlocks* blocks) {
  const std::map<const double*, int>& offset = linearized.offsets;
  const Eigen::SparseMatrix<double> information =
      linearized.jacobian.transpose() * linearized.jacobian;
  SelectedInverse inverse;
  if (!inverse.Compute(information, kMaxSelectedInverseNonzeros)) return false;
  return FillBlocks(
      problem, model, block_pairs, landmarks,
      [&](const double* block) {
        const auto it = offset.find(block);
        return it == offset.end() ? -1 : it->second;
      },
      [&](int i, int j, double* value) { return inverse.Entry(i, j, value); },
      blocks);
}

// The same blocks from ceres::Covariance with `options.algorithm`.
bool CeresCovariance(
    SlamProblem* problem, const TrajectoryModel& model,
    const std::set<std::pair<int, int>>& block_pairs,
    const std::vector<std::pair<const double*, const double*>>& requests,
    const std::vector<Landmark>& landmarks, const CovarianceOptions& options,
    CovarianceBlocks* blocks, std::string* error) {
  ceres::Covariance::Options covariance_options;
  covariance_options.algorithm_type = options.algorithm;
  covariance_options.num_threads = options.num_threads;
  ceres::Covariance covariance(covariance_options);
  if (!covariance.Compute(requests, problem->problem())) {
    *error = SingularMessage(
        problem, landmarks,
        std::string("ceres::Covariance (") +
            ceres::CovarianceAlgorithmTypeToString(options.algorithm) +
            ") failed: ");
    return false;
  }
  for (const auto& [a, b] : block_pairs) {
    RowMajorMatrix block(model.block_size(a), model.block_size(b));
    covariance.GetCovarianceBlock(model.block(a), model.block(b), block.data());
    blocks->trajectory.emplace(std::make_pair(a, b), block);
  }
  for (const Landmark& l : landmarks) {
    Eigen::Matrix<double, 2, 2, Eigen::RowMajor> block;
    const double* parameters = problem->landmark_block(l.id);
    covariance.GetCovarianceBlock(parameters, parameters, block.data());
    blocks->landmarks[l.id] = block;
  }
  return true;
}

}  // namespace

bool ComputePosteriorCovariance(SlamProblem* problem,
                                const TrajectoryModel& model,
                                const std::vector<double>& times,
                                const CovarianceOptions& options,
                                std::vector<Eigen::Matrix3d>* pose_covariances,
                                std::vector<Landmark>* landmarks,
                                std::string* error, CovarianceMethod* method) {
  pose_covariances->clear();
  if (options.num_threads < 1) {
    *error = OptionError("num_threads", std::to_string(options.num_threads), "",
                         "1 or more");
    return false;
  }
  ceres::Problem* ceres_problem = problem->problem();

  // The pose maps, and every pair of trajectory blocks that meet in one.
  std::vector<PoseMap> maps;
  maps.reserve(times.size());
  std::set<std::pair<int, int>> block_pairs;
  for (const double t : times) {
    maps.push_back(model.PoseAt(t));
    const std::vector<PoseTerm>& terms = maps.back().terms;
    for (const PoseTerm& a : terms) {
      if (a.block < 0 || a.block >= model.num_blocks() ||
          !ceres_problem->HasParameterBlock(model.block(a.block))) {
        *error = "posterior covariance: trajectory block " +
                 std::to_string(a.block) +
                 " of the pose at t = " + FormatNumber(t) +
                 " is not in the problem";
        return false;
      }
      for (const PoseTerm& b : terms) {
        block_pairs.insert(std::minmax(a.block, b.block));
      }
    }
  }
  std::vector<std::pair<const double*, const double*>> requests;
  for (const auto& [a, b] : block_pairs) {
    requests.emplace_back(model.block(a), model.block(b));
  }
  for (const Landmark& l : *landmarks) {
    const double* block = problem->landmark_block(l.id);
    if (block == nullptr || !ceres_problem->HasParameterBlock(block)) {
      *error = "posterior covariance: landmark " + std::to_string(l.id) +
               " is not in the problem";
      return false;
    }
    requests.emplace_back(block, block);
  }
  if (requests.empty()) return true;

  CovarianceBlocks blocks;
  CovarianceMethod used = CovarianceMethod::kEnvelope;
  if (!options.use_envelope ||
      !EnvelopeCovariance(problem, model, block_pairs, *landmarks, &blocks)) {
    // One linearisation serves both sparse exact methods.
    LinearizedProblem linearized;
    const bool exact = (options.use_schur || options.use_selected_inverse) &&
                       LinearizeLandmarksLast(problem, &linearized);
    if (exact && options.use_schur &&
        SchurCovariance(problem, model, linearized, block_pairs, *landmarks,
                        &blocks)) {
      used = CovarianceMethod::kSchur;
    } else if (exact && options.use_selected_inverse &&
               SelectedInverseCovariance(problem, model, linearized,
                                         block_pairs, *landmarks, &blocks)) {
      used = CovarianceMethod::kSelectedInverse;
    } else if (CeresCovariance(problem, model, block_pairs, requests,
                               *landmarks, options, &blocks, error)) {
      used = CovarianceMethod::kCeres;
    } else {
      return false;
    }
  }
  if (method != nullptr) *method = used;
  const auto& sigma = blocks.trajectory;
  pose_covariances->reserve(times.size());
  for (std::size_t k = 0; k < times.size(); ++k) {
    const std::vector<PoseTerm>& terms = maps[k].terms;
    Eigen::Matrix3d pose_covariance = Eigen::Matrix3d::Zero();
    for (const PoseTerm& a : terms) {
      for (const PoseTerm& b : terms) {
        // Only Sigma(a, b) with a <= b is stored; Sigma(b, a) = Sigma(a, b)^T.
        pose_covariance(a.coordinate, b.coordinate) +=
            a.block <= b.block
                ? a.phi->dot(sigma.at({a.block, b.block}) * *b.phi)
                : b.phi->dot(sigma.at({b.block, a.block}) * *a.phi);
      }
    }
    pose_covariance = 0.5 * (pose_covariance + pose_covariance.transpose());
    if (!pose_covariance.allFinite() ||
        !(pose_covariance.diagonal().minCoeff() >= 0.0)) {
      *error = "posterior covariance: the covariance of the pose at t = " +
               FormatNumber(times[k]) +
               " is not finite or has a negative variance";
      return false;
    }
    pose_covariances->push_back(pose_covariance);
  }
  for (Landmark& l : *landmarks) {
    const Eigen::Matrix2d& block = blocks.landmarks.at(l.id);
    if (!block.allFinite() || !(block(0, 0) >= 0.0) || !(block(1, 1) >= 0.0)) {
      *error = "posterior covariance: the covariance of landmark " +
               std::to_string(l.id) +
               " is not finite or has a negative variance";
      return false;
    }
    l.has_covariance = true;
    l.sxx = block(0, 0);
    l.sxy = 0.5 * (block(0, 1) + block(1, 0));
    l.syy = block(1, 1);
  }
  return true;
}

bool ComputePosteriorCovariance(SlamProblem* problem,
                                const TrajectoryModel& model,
                                const std::vector<double>& times,
                                std::vector<Eigen::Matrix3d>* pose_covariances,
                                std::vector<Landmark>* landmarks,
                                std::string* error) {
  return ComputePosteriorCovariance(problem, model, times, CovarianceOptions(),
                                    pose_covariances, landmarks, error);
}

}  // namespace rff
