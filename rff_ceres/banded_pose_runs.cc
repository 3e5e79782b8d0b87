// The runs of PoseMapped costs at one time that BandedProblem linearises
// in pose space: their rows on the weights are G Phi, G their rows on the
// pose, so a run's weight products are Phi^T (G^T G) Phi (banded_problem.h).
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "Eigen/Cholesky"
#include "rff_ceres/banded_problem.h"
#include "rff_ceres/loss_correction.h"

namespace rff {

namespace {

// A term's cost when its rows on the weights are rank one per pose-map
// term: one pose, its map's terms each on its own panel block, which are
// the term's blocks 0..n-1, then at most the landmark, placed after them.
const PoseMapped* CompressibleCost(const ceres::CostFunction* cost,
                                   int num_blocks, const int* column,
                                   const char* in_panel) {
  const auto* mapped = dynamic_cast<const PoseMapped*>(cost);
  if (mapped == nullptr || mapped->num_pose_maps() != 1) return nullptr;
  const PoseMap& map = mapped->pose_map(0);
  const int n = static_cast<int>(map.terms.size());
  if (n > kMaxCompressedTerms ||
      num_blocks != n + (mapped->has_landmark() ? 1 : 0)) {
    return nullptr;
  }
  std::vector<int> blocks;
  for (const PoseTerm& t : map.terms) {
    if (t.block >= n || !in_panel[t.block]) return nullptr;
    // A landmark's row of H is then after the weights' (AccumulateRun).
    if (num_blocks > n && column[n] >= 0 && column[n] < column[t.block]) {
      return nullptr;
    }
    blocks.push_back(t.block);
  }
  std::sort(blocks.begin(), blocks.end());
  const bool distinct =
      std::adjacent_find(blocks.begin(), blocks.end()) == blocks.end();
  return distinct ? mapped : nullptr;
}

// Whether two terms' maps put the same feature vectors on the same columns.
bool SameRows(const PoseMap& a, const int* a_column, const PoseMap& b,
              const int* b_column) {
  if (a.terms.size() != b.terms.size()) return false;
  for (std::size_t i = 0; i < a.terms.size(); ++i) {
    if (a.terms[i].phi != b.terms[i].phi ||
        a_column[a.terms[i].block] != b_column[b.terms[i].block]) {
      return false;
    }
  }
  return true;
}

}  // namespace

void BandedProblem::MarkCompressedRuns() {
  std::vector<const PoseMapped*> costs(terms_.size());
  for (std::size_t k = 0; k < terms_.size(); ++k) {
    const Term& t = terms_[k];
    costs[k] = CompressibleCost(t.cost, t.num_blocks, t.column, t.in_panel);
  }
  std::size_t begin = 0;
  while (begin < terms_.size()) {
    std::size_t end = begin + 1;
    if (costs[begin] == nullptr) {
      begin = end;
      continue;
    }
    const PoseMap& map = costs[begin]->pose_map(0);
    int rows = terms_[begin].cost->num_residuals();
    while (end < terms_.size() && costs[end] != nullptr &&
           SameRows(map, terms_[begin].column, costs[end]->pose_map(0),
                    terms_[end].column)) {
      rows += terms_[end++].cost->num_residuals();
    }
    // A run gives the panel at most one row per pose coordinate: with
    // fewer rows than that it would only grow.
    if (rows > 3) {
      for (std::size_t k = begin; k < end; ++k) {
        terms_[k].compressed = costs[k];
      }
      terms_[end - 1].closes_run = true;
      ++compressed_runs_;
    }
    begin = end;
  }
}

double BandedProblem::ProductWork(bool compressed) const {
  double work = 0.0;
  for (const Term& term : terms_) {
    int panel_width = 0, width = 0;
    for (int a = 0; a < term.num_blocks; ++a) {
      if (term.column[a] < 0) continue;
      width += term.size[a];
      if (term.in_panel[a]) panel_width += term.size[a];
    }
    const double rows = term.cost->num_residuals();
    if (compressed && term.compressed != nullptr) {
      // The run's 3 rows on the weights; each cost's products with its
      // landmark are formed once from its rows on the pose (AccumulateRun).
      if (term.closes_run) work += 3.0 * panel_width * panel_width / 2.0;
      work += (double(width) * width - double(panel_width) * panel_width) / 2.0;
    } else {
      work += rows * width * width / 2.0;
    }
  }
  return work;
}

bool BandedProblem::EvaluateOnPose(const Term& term, const Eigen::VectorXd& x,
                                   double* cost) {
  const int rows = term.cost->num_residuals();
  parameters_.resize(term.num_blocks);
  for (int a = 0; a < term.num_blocks; ++a) {
    parameters_[a] =
        term.column[a] >= 0 ? x.data() + term.column[a] : term.blocks[a];
  }
  residual_buffer_.resize(rows);
  pose_rows_.resize(3 * rows);
  landmark_rows_.resize(2 * rows);
  Eigen::Map<Eigen::VectorXd> residual(residual_buffer_.data(), rows);
  if (!term.compressed->EvaluateAtPoses(parameters_.data(), residual.data(),
                                        pose_rows_.data(),
                                        landmark_rows_.data()) ||
      !residual.allFinite()) {
    return false;
  }
  const LossCorrection correction(term.loss, residual.squaredNorm());
  *cost = correction.cost;
  const bool landmark =
      term.compressed->has_landmark() && term.column[term.num_blocks - 1] >= 0;
  if (!correction.CorrectRows(residual, pose_rows_.data(), 3) ||
      (landmark &&
       !correction.CorrectRows(residual, landmark_rows_.data(), 2))) {
    return false;
  }
  residual *= correction.residual_scaling;
  return std::isfinite(*cost);
}

void BandedProblem::AccumulateRun(const Term& term, Eigen::VectorXd* g,
                                  EnvelopeMatrix* h) {
  // Row r on term i's block is G(r, c_i) phi_i^T (pose_map.h).
  const PoseMap& map = term.compressed->pose_map(0);
  const int n = static_cast<int>(map.terms.size());
  const int rows = static_cast<int>(residual_buffer_.size());
  using Rows =
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const Eigen::Map<const Rows> on_pose(pose_rows_.data(), rows, 3);
  const Eigen::Map<const Eigen::VectorXd> residual(residual_buffer_.data(),
                                                   rows);
  Eigen::Vector3d pose_gradient;
  pose_gradient.noalias() = on_pose.transpose() * residual;
  for (const PoseTerm& t : map.terms) {
    g->segment(term.column[t.block], t.phi->size()) +=
        pose_gradient[t.coordinate] * *t.phi;
  }
  const int l = term.compressed->has_landmark() ? term.column[n] : -1;
  if (l >= 0) {
    const Eigen::Map<const Rows> on_landmark(landmark_rows_.data(), rows, 2);
    Eigen::Vector2d landmark_gradient;
    landmark_gradient.noalias() = on_landmark.transpose() * residual;
    g->segment<2>(l) += landmark_gradient;
    Eigen::Matrix2d ll;
    ll.noalias() = on_landmark.transpose() * on_landmark;
    (*h)(l, l) += ll(0, 0);
    (*h)(l + 1, l) += ll(1, 0);
    (*h)(l + 1, l + 1) += ll(1, 1);
    // The landmark's products with term i's block: C(j, c_i) phi_i^T.
    Eigen::Matrix<double, 2, 3, Eigen::RowMajor> c;
    c.noalias() = on_landmark.transpose() * on_pose;
    for (const PoseTerm& t : map.terms) {
      const int b = term.column[t.block];
      for (int j = 0; j < 2; ++j) {  // Row l + j of H: l > b.
        Eigen::Map<Eigen::RowVectorXd>(&(*h)(l + j, b), t.phi->size()) +=
            c(j, t.coordinate) * t.phi->transpose();
      }
    }
  }
  if (!run_open_) {
    run_gram_.setZero();
    run_open_ = true;
  }
  run_gram_.noalias() += on_pose.transpose() * on_pose;
  if (!term.closes_run) return;
  run_open_ = false;
  // G^T G = P^T L D L^T P, so R = D^(1/2) L^T P: row r puts
  // R(r, c_i) phi_i on term i's block.
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(run_gram_);
  const Eigen::Matrix3d pl =
      ldlt.transpositionsP().transpose() * Eigen::Matrix3d(ldlt.matrixL());
  // Blocks 0..n-1 are the panel's, in order (CompressibleCost).
  std::array<int, kMaxCompressedTerms + 1> offset{};
  for (int a = 0; a < n; ++a) offset[a + 1] = offset[a] + term.size[a];
  for (int r = 0; r < 3; ++r) {
    const double d = ldlt.vectorD()[r];
    if (!(d > 0.0)) continue;
    const double scale = std::sqrt(d);
    double* out = PanelRows(term, 1, h);
    std::fill(out, out + offset[n], 0.0);
    for (const PoseTerm& t : map.terms) {
      Eigen::Map<Eigen::VectorXd>(out + offset[t.block], t.phi->size()) =
          (scale * pl(t.coordinate, r)) * *t.phi;
    }
  }
}

}  // namespace rff
