#include "rff_ceres/truncation_covariance.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <set>
#include <utility>

#include "Eigen/Cholesky"
#include "Eigen/SparseCore"
#include "rff_ceres/gauss_newton_system.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/variance_components.h"

namespace rff {
namespace {

using ColumnMajorSparse = Eigen::SparseMatrix<double>;

// Where each column of the extended problem goes: kept (the solved
// problem's parameters, in order), new (a mode the solve left out) or
// neither (a new mode of a prior with no variance left).
struct ColumnSplit {
  std::vector<int> kept_of;  // Per extended column: its kept index, or -1.
  std::vector<int> new_of;   // Per extended column: its new index, or -1.
  int num_kept = 0;
  int num_new = 0;
  // Per parameter block: its first extended column.
  std::map<const double*, int> first_column;
};

// The columns of `blocks` (the extended problem's order), whose trajectory
// blocks of `extended` keep `model`'s first block_size(b) columns; the new
// ones of a scale not in `scales` are dropped.
ColumnSplit SplitColumns(ceres::Problem* problem,
                         const std::vector<double*>& blocks,
                         const TrajectoryModel& model,
                         const TrajectoryModel& extended,
                         const std::set<TrajectoryModel::PriorScale>& scales) {
  std::map<const double*, int> trajectory_block;
  for (int b = 0; b < extended.num_blocks(); ++b) {
    trajectory_block[extended.block(b)] = b;
  }
  ColumnSplit split;
  for (double* block : blocks) {
    const int size = problem->ParameterBlockSize(block);
    const auto it = trajectory_block.find(block);
    const bool trajectory = it != trajectory_block.end();
    const int kept = trajectory ? model.block_size(it->second) : size;
    const bool extend =
        trajectory &&
        scales.count(extended.PriorRowScales({block}, 1).front()) > 0;
    split.first_column[block] = static_cast<int>(split.kept_of.size());
    for (int j = 0; j < size; ++j) {
      split.kept_of.push_back(j < kept ? split.num_kept++ : -1);
      split.new_of.push_back(j >= kept && extend ? split.num_new++ : -1);
    }
  }
  return split;
}

// J's kept columns, and J_kept^T J_new (dense) row by row: a row's new
// entries are those of the one or two segments it touches.
void SplitJacobian(const Eigen::SparseMatrix<double, Eigen::RowMajor>& jacobian,
                   const ColumnSplit& split, ColumnMajorSparse* kept,
                   Eigen::MatrixXd* cross) {
  std::vector<Eigen::Triplet<double>> kept_entries;
  cross->setZero(split.num_kept, split.num_new);
  std::vector<std::pair<int, double>> row_kept, row_new;
  for (int row = 0; row < jacobian.outerSize(); ++row) {
    row_kept.clear();
    row_new.clear();
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(
             jacobian, row);
         it; ++it) {
      const int column = static_cast<int>(it.col());
      if (split.kept_of[column] >= 0) {
        kept_entries.emplace_back(row, split.kept_of[column], it.value());
        row_kept.emplace_back(split.kept_of[column], it.value());
      } else if (split.new_of[column] >= 0) {
        row_new.emplace_back(split.new_of[column], it.value());
      }
    }
    for (const auto& [j, c] : row_new) {
      double* column = cross->col(j).data();
      for (const auto& [i, a] : row_kept) column[i] += a * c;
    }
  }
  kept->resize(jacobian.rows(), split.num_kept);
  kept->setFromTriplets(kept_entries.begin(), kept_entries.end());
}

}  // namespace

void AddTruncationCovariance(
    const Dataset& dataset, const ProblemOptions& options, SlamProblem* problem,
    const TrajectoryModel& model,
    const std::set<TrajectoryModel::PriorScale>& scales,
    const std::vector<double>& times,
    std::vector<Eigen::Matrix3d>* pose_covariances,
    std::vector<Landmark>* landmarks, std::string* note) {
  if (scales.empty()) {
    *note = "none: the data leave the prior no variance";
    return;
  }
  std::string why;
  const std::unique_ptr<TrajectoryModel> extended = model.WithMoreModes(
      kTruncationTailFraction, kTruncationMostModeMultiple, &why);
  if (!extended) {
    *note = "none: " + why;
    return;
  }
  // A dense LLT of H, its solves for the new modes, and every pose's two
  // segments' features through them.
  const double n = problem->problem()->NumParameters();
  const double rows = 3.0 * static_cast<double>(times.size());
  double m = 0.0;
  int widest_block = 0;
  for (int b = 0; b < extended->num_blocks(); ++b) {
    m += extended->block_size(b) - model.block_size(b);
    widest_block = std::max(widest_block, extended->block_size(b));
  }
  const double work =
      n * n * n / 3.0 + 2.0 * n * n * m + rows * 2.0 * widest_block * m;
  if (!(work <= kMaxTruncationWork) ||
      !(std::max(n, rows) * m <= kMaxTruncationEntries)) {
    *note = "none: " + FormatNumber(m) + " more modes over " + FormatNumber(n) +
            " parameters cost more than " + FormatNumber(kMaxTruncationWork) +
            " multiply-adds";
    return;
  }
  SlamProblem wide(extended.get(), options);
  std::string error;
  if (!wide.Build(dataset, problem->landmarks(), &error)) {
    *note = "none: the extended problem: " + error;
    return;
  }
  wide.set_range_calibration(problem->range_calibration());
  wide.set_odometry_calibration(problem->odometry_calibration());

  ceres::Problem* ceres_problem = wide.problem();
  int num_leading = 0;
  const std::vector<double*> blocks = LandmarksLast(&wide, &num_leading);
  for (double* block : blocks) {
    if (ceres_problem->IsParameterBlockConstant(block)) {
      *note = "none: a parameter block is held constant";
      return;
    }
  }
  const ColumnSplit split =
      SplitColumns(ceres_problem, blocks, model, *extended, scales);
  if (split.num_new == 0) {
    *note = "none: no new modes of a scale with variance";
    return;
  }
  std::vector<ceres::ResidualBlockId> ids;
  ceres_problem->GetResidualBlocks(&ids);
  double cost = 0.0, solved_cost = 0.0;
  Eigen::VectorXd residuals;
  Eigen::SparseMatrix<double, Eigen::RowMajor> jacobian;
  if (!Linearize(ceres_problem, ids, &cost, &residuals, &jacobian, &error,
                 blocks) ||
      !problem->problem()->Evaluate(ceres::Problem::EvaluateOptions(),
                                    &solved_cost, nullptr, nullptr, nullptr)) {
    *note = "none: the extended problem cannot be evaluated: " + error;
    return;
  }
  // The new modes are at zero: the same residuals as the solve's, but for
  // the order of the sums over the longer feature vectors.
  if (!(std::abs(cost - solved_cost) <= 1e-9 * (1.0 + solved_cost))) {
    *note = "none: the extended problem's cost " + FormatNumber(cost) +
            " is not the solved " + FormatNumber(solved_cost);
    return;
  }
  // G = H^-1 J_theta^T J_c.
  ColumnMajorSparse kept;
  Eigen::MatrixXd response;
  SplitJacobian(jacobian, split, &kept, &response);
  const Eigen::LLT<Eigen::MatrixXd> factor(
      Eigen::MatrixXd(kept.transpose() * kept));
  if (factor.info() != Eigen::Success ||
      !(factor.rcond() > kMinReciprocalCondition)) {
    *note = "none: J^T J is singular to rounding";
    return;
  }
  factor.solveInPlace(response);

  // Rows 3k .. 3k + 2 of A: A(t_k) = Phi(t_k) G_b - Psi(t_k), the kept
  // features through G and the new ones directly.
  std::vector<Eigen::Triplet<double>> kept_features, new_features;
  for (std::size_t k = 0; k < times.size(); ++k) {
    const PoseMap map = extended->PoseAt(times[k]);
    for (const PoseTerm& term : map.terms) {
      const int row = 3 * static_cast<int>(k) + term.coordinate;
      const int first = split.first_column.at(extended->block(term.block));
      const Eigen::VectorXd& phi = *term.phi;
      for (int j = 0; j < phi.size(); ++j) {
        if (split.kept_of[first + j] >= 0) {
          kept_features.emplace_back(row, split.kept_of[first + j], phi[j]);
        } else if (split.new_of[first + j] >= 0) {
          new_features.emplace_back(row, split.new_of[first + j], phi[j]);
        }
      }
    }
  }
  const int num_rows = 3 * static_cast<int>(times.size());
  ColumnMajorSparse phi(num_rows, split.num_kept), psi(num_rows, split.num_new);
  phi.setFromTriplets(kept_features.begin(), kept_features.end());
  psi.setFromTriplets(new_features.begin(), new_features.end());
  Eigen::MatrixXd a = phi * response;
  a -= psi;
  for (std::size_t k = 0; k < times.size(); ++k) {
    const auto rows_k = a.middleRows(3 * k, 3);
    (*pose_covariances)[k] += rows_k * rows_k.transpose();
  }
  for (Landmark& l : *landmarks) {
    const int column = split.first_column.at(wide.landmark_block(l.id));
    const Eigen::MatrixXd g = response.middleRows(split.kept_of[column], 2);
    const Eigen::Matrix2d added_covariance = g * g.transpose();
    l.sxx += added_covariance(0, 0);
    l.sxy += added_covariance(0, 1);
    l.syy += added_covariance(1, 1);
  }
  *note = "added: the next " + std::to_string(split.num_new) +
          " modes of the basis (" +
          (scales.size() == 2 ? "position and heading"
           : scales.count(TrajectoryModel::PriorScale::kPosition)
               ? "position; heading has no variance"
               : "heading; position has no variance") +
          ")";
}

}  // namespace rff
