#include "rff_ceres/banded_problem.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "rff_ceres/loss_correction.h"

namespace rff {

std::vector<double*> BandedBlockOrder(const ceres::Problem& problem,
                                      const BandedColumns& columns) {
  std::unordered_map<const double*, int> time_index, anchor;
  time_index.reserve(columns.timed.size());
  anchor.reserve(columns.placed.size());
  for (std::size_t k = 0; k < columns.timed.size(); ++k) {
    time_index[columns.timed[k]] = static_cast<int>(k);
  }
  for (const double* block : columns.placed) anchor[block] = -1;
  std::vector<ceres::ResidualBlockId> ids;
  problem.GetResidualBlocks(&ids);
  std::vector<double*> blocks;
  for (const ceres::ResidualBlockId id : ids) {
    problem.GetParameterBlocksForResidualBlock(id, &blocks);
    int latest = -1;
    for (const double* block : blocks) {
      const auto it = time_index.find(block);
      if (it != time_index.end()) latest = std::max(latest, it->second);
    }
    for (const double* block : blocks) {
      const auto it = anchor.find(block);
      if (it != anchor.end()) it->second = std::max(it->second, latest);
    }
  }
  std::vector<std::vector<double*>> after(columns.timed.size() + 1);
  for (double* block : columns.placed) {
    after[anchor[block] + 1].push_back(block);
  }
  std::vector<double*> order = after[0];
  for (std::size_t k = 0; k < columns.timed.size(); ++k) {
    order.push_back(columns.timed[k]);
    order.insert(order.end(), after[k + 1].begin(), after[k + 1].end());
  }
  order.insert(order.end(), columns.last.begin(), columns.last.end());
  return order;
}

namespace {

// h[j] += sum_k a[k * a_stride] b[k * b_stride + j], j < kWidth, the sum in
// k order onto h[j] (the same roundings as row by row), h[j] in registers.
template <int kWidth>
void AddColumnProducts(int rows, const double* a, int a_stride, const double* b,
                       int b_stride, double* h) {
  double sum[kWidth];
  for (int j = 0; j < kWidth; ++j) sum[j] = h[j];
  for (int k = 0; k < rows; ++k) {
    const double v = a[k * a_stride];
    const double* bk = b + k * b_stride;
    for (int j = 0; j < kWidth; ++j) sum[j] += v * bk[j];
  }
  for (int j = 0; j < kWidth; ++j) h[j] = sum[j];
}

// The same for any width: fixed widths up to a WNOA state's 6, wider ones
// (feature windows' non-panel products) 6 columns at a time, each h[j]'s
// sum the same.
void AddColumnProducts(int width, int rows, const double* a, int a_stride,
                       const double* b, int b_stride, double* h) {
  constexpr int kMaxWidth = 6;
  switch (width) {
    case 1:
      return AddColumnProducts<1>(rows, a, a_stride, b, b_stride, h);
    case 2:
      return AddColumnProducts<2>(rows, a, a_stride, b, b_stride, h);
    case 3:
      return AddColumnProducts<3>(rows, a, a_stride, b, b_stride, h);
    case 4:
      return AddColumnProducts<4>(rows, a, a_stride, b, b_stride, h);
    case 5:
      return AddColumnProducts<5>(rows, a, a_stride, b, b_stride, h);
    case 6:
      return AddColumnProducts<6>(rows, a, a_stride, b, b_stride, h);
    default:
      for (int j = 0; j < width; j += kMaxWidth) {
        AddColumnProducts(std::min(kMaxWidth, width - j), rows, a, a_stride,
                          b + j, b_stride, h + j);
      }
  }
}

}  // namespace

BandedProblem::BandedProblem(const ceres::Problem& problem,
                             const BandedColumns& columns) {
  std::vector<ceres::ResidualBlockId> ids;
  problem.GetResidualBlocks(&ids);
  std::vector<int> begin;
  begin.reserve(ids.size() + 1);
  blocks_.reserve(2 * ids.size());
  std::vector<double*> blocks;
  for (const ceres::ResidualBlockId id : ids) {
    problem.GetParameterBlocksForResidualBlock(id, &blocks);
    begin.push_back(static_cast<int>(blocks_.size()));
    blocks_.insert(blocks_.end(), blocks.begin(), blocks.end());
  }
  begin.push_back(static_cast<int>(blocks_.size()));
  // Per block its first column (-1: constant) and size.
  std::unordered_map<const double*, std::pair<int, int>> layout;
  layout.reserve(problem.NumParameterBlocks());
  // As Ceres's preprocessor: blocks no residual uses are no variables.
  const std::unordered_set<const double*> used(blocks_.begin(), blocks_.end());
  for (double* block : BandedBlockOrder(problem, columns)) {
    const int size = problem.ParameterBlockSize(block);
    if (problem.IsParameterBlockConstant(block) || used.count(block) == 0) {
      layout[block] = {-1, size};
      continue;
    }
    layout[block] = {num_columns_, size};
    first_column_[block] = num_columns_;
    variables_.push_back(block);
    variable_sizes_.push_back(size);
    num_columns_ += size;
  }
  constexpr double kUnbounded = std::numeric_limits<double>::max();
  for (std::size_t b = 0; b < variables_.size(); ++b) {
    for (int i = 0; i < variable_sizes_[b]; ++i) {
      const double lower = problem.GetParameterLowerBound(variables_[b], i);
      const double upper = problem.GetParameterUpperBound(variables_[b], i);
      if (lower == -kUnbounded && upper == kUnbounded) continue;
      if (lower_.size() == 0) {
        lower_.setConstant(num_columns_, -kUnbounded);
        upper_.setConstant(num_columns_, kUnbounded);
      }
      const int column = first_column_[variables_[b]] + i;
      lower_[column] = lower;
      upper_[column] = upper;
    }
  }
  const std::unordered_set<const double*> timed(columns.timed.begin(),
                                                columns.timed.end());
  columns_.reserve(blocks_.size());
  sizes_.reserve(blocks_.size());
  in_panel_.reserve(blocks_.size());
  for (double* block : blocks_) {
    const std::pair<int, int>& place = layout.at(block);
    columns_.push_back(place.first);
    sizes_.push_back(place.second);
    in_panel_.push_back(place.first >= 0 && place.second >= kMinPanelWidth &&
                        timed.count(block) > 0);
  }
  terms_.reserve(ids.size());
  for (std::size_t r = 0; r < ids.size(); ++r) {
    Term term;
    term.cost = problem.GetCostFunctionForResidualBlock(ids[r]);
    term.loss = problem.GetLossFunctionForResidualBlock(ids[r]);
    term.num_blocks = begin[r + 1] - begin[r];
    term.blocks = blocks_.data() + begin[r];
    term.column = columns_.data() + begin[r];
    term.size = sizes_.data() + begin[r];
    term.in_panel = in_panel_.data() + begin[r];
    term.num_panel_blocks = static_cast<int>(
        std::count(term.in_panel, term.in_panel + term.num_blocks, 1));
    has_panels_ = has_panels_ || term.num_panel_blocks > 0;
    term.first_row = num_rows_;
    num_rows_ += term.cost->num_residuals();
    const bool variable =
        std::any_of(term.column, term.column + term.num_blocks,
                    [](int c) { return c >= 0; });
    // Terms of constant blocks only are Ceres's fixed cost: outside the
    // tolerance tests and the step quality.
    (variable ? terms_ : fixed_terms_).push_back(term);
  }
  envelope_first_ = EnvelopeFirst();
  size_.num_columns = num_columns_;
  for (int i = 0; i < num_columns_; ++i) {
    size_.entries += i - envelope_first_[i] + 1;
  }
  size_.multiply_adds = EnvelopeMatrix::FactorizationWork(envelope_first_);
  MarkCompressedRuns();
}

int BandedProblem::ColumnOf(const double* block) const {
  const auto it = first_column_.find(block);
  return it == first_column_.end() ? -1 : it->second;
}

std::vector<int> BandedProblem::EnvelopeFirst() const {
  std::vector<int> first(num_columns_);
  for (int i = 0; i < num_columns_; ++i) first[i] = i;
  for (const Term& term : terms_) {
    int lowest = num_columns_;
    for (int a = 0; a < term.num_blocks; ++a) {
      if (term.column[a] >= 0) lowest = std::min(lowest, term.column[a]);
    }
    for (int a = 0; a < term.num_blocks; ++a) {
      if (term.column[a] < 0) continue;
      for (int i = 0; i < term.size[a]; ++i) {
        first[term.column[a] + i] = std::min(first[term.column[a] + i], lowest);
      }
    }
  }
  return first;
}

Eigen::VectorXd BandedProblem::Gather() const {
  Eigen::VectorXd x(num_columns_);
  int c = 0;
  for (std::size_t b = 0; b < variables_.size(); ++b) {
    for (int i = 0; i < variable_sizes_[b]; ++i) x[c++] = variables_[b][i];
  }
  return x;
}

void BandedProblem::Project(Eigen::VectorXd* x) const {
  if (lower_.size() == 0) return;
  *x = x->cwiseMax(lower_).cwiseMin(upper_);
}

void BandedProblem::Scatter(const Eigen::VectorXd& x) const {
  int c = 0;
  for (std::size_t b = 0; b < variables_.size(); ++b) {
    for (int i = 0; i < variable_sizes_[b]; ++i) variables_[b][i] = x[c++];
  }
}

bool BandedProblem::FixedCost(double* cost) {
  *cost = 0.0;
  for (const Term& term : fixed_terms_) {
    double term_cost;
    if (!Evaluate(term, Eigen::VectorXd(), false, &term_cost)) return false;
    *cost += term_cost;
  }
  return true;
}

bool BandedProblem::Cost(const Eigen::VectorXd& x, double* cost) {
  *cost = 0.0;
  for (const Term& term : terms_) {
    double term_cost;
    if (!Evaluate(term, x, /*jacobians=*/false, &term_cost)) return false;
    *cost += term_cost;
  }
  return true;
}

bool BandedProblem::Linearize(const Eigen::VectorXd& x, double* cost,
                              Eigen::VectorXd* g, EnvelopeMatrix* h) {
  *cost = 0.0;
  g->setZero(num_columns_);
  h->SetZero();
  panel_rows_ = 0;
  panel_columns_.clear();
  panel_sizes_.clear();
  run_open_ = false;
  for (const Term& term : terms_) {
    double term_cost;
    if (term.compressed != nullptr) {
      if (!EvaluateOnPose(term, x, &term_cost)) return false;
      AccumulateRun(term, g, h);
    } else {
      if (!Evaluate(term, x, /*jacobians=*/true, &term_cost)) return false;
      Accumulate(term, g, h);
    }
    *cost += term_cost;
  }
  FlushPanel(h);
  return true;
}

bool BandedProblem::RowProducts(const Eigen::VectorXd& x,
                                const EnvelopeMatrix::RowMajorMatrix& z,
                                const EnvelopeMatrix::RowMajorMatrix& u,
                                Eigen::VectorXd* residuals,
                                Eigen::VectorXd* products) {
  residuals->setZero(num_rows_);
  products->setZero(num_rows_);
  Eigen::RowVectorXd jz(z.cols()), ju(u.cols());
  for (const std::vector<Term>* terms : {&terms_, &fixed_terms_}) {
    for (const Term& term : *terms) {
      double term_cost;
      if (!Evaluate(term, x, /*jacobians=*/true, &term_cost)) return false;
      const int rows = static_cast<int>(residual_buffer_.size());
      for (int k = 0; k < rows; ++k) {
        (*residuals)[term.first_row + k] = residual_buffer_[k];
        jz.setZero();
        ju.setZero();
        for (int a = 0; a < term.num_blocks; ++a) {
          if (term.column[a] < 0) continue;
          const double* j = jacobian_rows_[a].data() + k * term.size[a];
          // Most of a row's entries are zeros (a range on a state's
          // heading, one axis's prior on another's): they add nothing.
          for (int i = 0; i < term.size[a]; ++i) {
            if (j[i] == 0.0) continue;
            jz += j[i] * z.row(term.column[a] + i);
            ju += j[i] * u.row(term.column[a] + i);
          }
        }
        (*products)[term.first_row + k] = jz.dot(ju);
      }
    }
  }
  return true;
}

bool BandedProblem::Evaluate(const Term& term, const Eigen::VectorXd& x,
                             bool jacobians, double* cost) {
  const int rows = term.cost->num_residuals();
  const std::size_t n = term.num_blocks;
  parameters_.resize(n);
  jacobian_rows_.resize(n);
  jacobian_pointers_.resize(n);
  for (std::size_t a = 0; a < n; ++a) {
    parameters_[a] =
        term.column[a] >= 0 ? x.data() + term.column[a] : term.blocks[a];
    jacobian_rows_[a].resize(static_cast<std::size_t>(rows) * term.size[a]);
    jacobian_pointers_[a] =
        jacobians && term.column[a] >= 0 ? jacobian_rows_[a].data() : nullptr;
  }
  // A buffer that keeps its capacity: terms of other sizes alternate.
  residual_buffer_.resize(rows);
  Eigen::Map<Eigen::VectorXd> residual(residual_buffer_.data(), rows);
  if (!term.cost->Evaluate(parameters_.data(), residual.data(),
                           jacobians ? jacobian_pointers_.data() : nullptr) ||
      !residual.allFinite()) {
    return false;
  }
  const LossCorrection correction(term.loss, residual.squaredNorm());
  *cost = correction.cost;
  if (!jacobians) return std::isfinite(*cost);
  for (std::size_t a = 0; a < n; ++a) {
    if (jacobian_pointers_[a] != nullptr &&
        !correction.CorrectRows(residual, jacobian_rows_[a].data(),
                                term.size[a])) {
      return false;
    }
  }
  residual *= correction.residual_scaling;
  return std::isfinite(*cost);
}

void BandedProblem::Accumulate(const Term& term, Eigen::VectorXd* g,
                               EnvelopeMatrix* h) {
  const int rows = static_cast<int>(residual_buffer_.size());
  const double* residual = residual_buffer_.data();
  if (term.num_panel_blocks > 0) {
    double* out = PanelRows(term, rows, h);
    for (int k = 0; k < rows; ++k) {
      for (int a = 0; a < term.num_blocks; ++a) {
        if (!term.in_panel[a]) continue;
        const double* j = jacobian_rows_[a].data() + k * term.size[a];
        out = std::copy(j, j + term.size[a], out);
      }
    }
  }
  for (int a = 0; a < term.num_blocks; ++a) {
    if (term.column[a] < 0) continue;
    const double* ja = jacobian_rows_[a].data();
    const int sa = term.size[a], ca = term.column[a];
    for (int k = 0; k < rows; ++k) {
      for (int i = 0; i < sa; ++i) (*g)[ca + i] += ja[k * sa + i] * residual[k];
    }
    for (int b = 0; b < term.num_blocks; ++b) {
      const int cb = term.column[b];
      if (cb < 0 || cb > ca || (term.in_panel[a] && term.in_panel[b])) {
        continue;
      }
      const double* jb = jacobian_rows_[b].data();
      const int sb = term.size[b];
      for (int i = 0; i < sa; ++i) {
        AddColumnProducts(a == b ? i + 1 : sb, rows, ja + i, sa, jb, sb,
                          &(*h)(ca + i, cb));
      }
    }
  }
}

double* BandedProblem::PanelRows(const Term& term, int rows,
                                 EnvelopeMatrix* h) {
  // The term's rows join the panel if it is on the same blocks.
  bool same = panel_rows_ < kMaxPanelRows &&
              static_cast<int>(panel_columns_.size()) == term.num_panel_blocks;
  for (int a = 0, p = 0; same && a < term.num_blocks; ++a) {
    if (term.in_panel[a]) same = panel_columns_[p++] == term.column[a];
  }
  if (!same) {
    FlushPanel(h);
    for (int a = 0; a < term.num_blocks; ++a) {
      if (!term.in_panel[a]) continue;
      panel_columns_.push_back(term.column[a]);
      panel_sizes_.push_back(term.size[a]);
    }
  }
  int width = 0;
  for (const int s : panel_sizes_) width += s;
  panel_.resize(static_cast<std::size_t>(panel_rows_ + rows) * width);
  double* out = panel_.data() + static_cast<std::size_t>(panel_rows_) * width;
  panel_rows_ += rows;
  return out;
}

void BandedProblem::FlushPanel(EnvelopeMatrix* h) {
  if (panel_rows_ > 0) {
    const int blocks = static_cast<int>(panel_columns_.size());
    std::vector<int> offset(blocks + 1, 0);
    for (int p = 0; p < blocks; ++p)
      offset[p + 1] = offset[p] + panel_sizes_[p];
    const Eigen::Map<const EnvelopeMatrix::RowMajorMatrix> panel(
        panel_.data(), panel_rows_, offset[blocks]);
    Eigen::MatrixXd product;
    for (int a = 0; a < blocks; ++a) {
      const int ca = panel_columns_[a], sa = panel_sizes_[a];
      for (int b = 0; b < blocks; ++b) {
        const int cb = panel_columns_[b], sb = panel_sizes_[b];
        if (cb > ca) continue;
        if (a == b) {  // The lower triangle only (SYRK).
          product.setZero(sa, sa);
          product.selfadjointView<Eigen::Lower>().rankUpdate(
              panel.middleCols(offset[a], sa).transpose());
        } else {
          product.noalias() = panel.middleCols(offset[a], sa).transpose() *
                              panel.middleCols(offset[b], sb);
        }
        for (int i = 0; i < sa; ++i) {
          double* hi = &(*h)(ca + i, cb);
          const int width = a == b ? i + 1 : sb;
          for (int j = 0; j < width; ++j) hi[j] += product(i, j);
        }
      }
    }
  }
  panel_rows_ = 0;
  panel_columns_.clear();
  panel_sizes_.clear();
}

}  // namespace rff
