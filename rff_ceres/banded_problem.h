// The normal equations of a ceres::Problem laid out for EnvelopeMatrix: the
// problem's own residual blocks, cost functions and losses evaluated at a
// state vector, with H = J^T J accumulated in a time-ordered envelope. The
// model side of BANDED_CHOLESKY (banded_minimizer.h runs the loop).
#ifndef RFF_CERES_BANDED_PROBLEM_H_
#define RFF_CERES_BANDED_PROBLEM_H_

#include <algorithm>
#include <cstdint>
#include <memory>
#include <unordered_map>
#include <vector>

#include "Eigen/Core"
#include "ceres/cost_function.h"
#include "ceres/loss_function.h"
#include "ceres/problem.h"
#include "costs/pose_map.h"
#include "rff_ceres/envelope_cholesky.h"

namespace rff {

// The columns of the system: the `timed` blocks in time order; each `placed`
// block right after the last timed block a residual couples it to (a
// landmark's row then spans its sightings, not the run); the `last` blocks
// after all (those rows from the whole run touch: calibrations, shared
// blocks).
struct BandedColumns {
  std::vector<double*> timed, placed, last;
  bool operator==(const BandedColumns& other) const {
    return timed == other.timed && placed == other.placed && last == other.last;
  }
};

// The blocks of `columns` in the system's column order (as above), placed
// by the residuals of `problem`.
std::vector<double*> BandedBlockOrder(const ceres::Problem& problem,
                                      const BandedColumns& columns);

// Timed blocks at least this wide (a feature window's 3 D weights) have
// their products with each other formed a panel of rows at a time (BLAS-3);
// WNOA's 6-wide states gain nothing from it (bench/README.md).
inline constexpr int kMinPanelWidth = 12;
// Rows a panel holds before it is multiplied out.
inline constexpr int kMaxPanelRows = 256;
// Most terms of a pose map whose costs' panel rows are compressed (x, y
// and theta of two blended windows).
inline constexpr int kMaxCompressedTerms = 6;

// The envelope of H in a column order: its columns (the variables), the
// doubles it stores and the multiply-adds of one factorisation.
struct BandedSize {
  int num_columns = 0;
  std::int64_t entries = 0;
  double multiply_adds = 0.0;
  // Whether its factorisation costs at most kMaxEnvelopeWorkPerVariable
  // multiply-adds per variable, or kMaxSmallEnvelopeWork in all
  // (envelope_cholesky.h).
  bool WorkWithinBound() const {
    return multiply_adds <=
               kMaxEnvelopeWorkPerVariable * std::max(num_columns, 1) ||
           multiply_adds <= kMaxSmallEnvelopeWork;
  }
};

class BandedProblem {
 public:
  // The variables are the blocks of `columns` that are not constant and
  // that a residual uses (as Ceres's preprocessor keeps them), in column
  // order; residuals on constant blocks only are the fixed cost. `columns`
  // must hold every block of `problem` once (BandedSolvable checks it).
  BandedProblem(const ceres::Problem& problem, const BandedColumns& columns);

  int num_columns() const { return num_columns_; }
  // Whether some residual has wide timed blocks (kMinPanelWidth): their
  // products are formed a panel at a time.
  bool has_panels() const { return has_panels_; }
  // Whether the envelope beats a fill-reducing sparse Cholesky here
  // (envelope_cholesky.h): feature windows' panels at any fill, narrow
  // states while the factorisation keeps within the work bound.
  bool BeatsSparseCholesky() const {
    return has_panels_ || Size().WorkWithinBound();
  }
  // The runs of costs at one time whose panel rows are compressed (Term).
  int compressed_runs() const { return compressed_runs_; }
  // The multiply-adds that form H from the rows: r w^2 / 2 for r rows of
  // width w. Linearize's own, its compressed runs at 3 rows; with
  // `compressed` false, every residual row's, as a solver that forms J^T J
  // from the Jacobian pays.
  double ProductWork(bool compressed) const;
  int num_variable_blocks() const {
    return static_cast<int>(variables_.size());
  }
  // Row i of H = J^T J stores from the first column any residual couples
  // to column i.
  const std::vector<int>& envelope_first() const { return envelope_first_; }
  // The first column of a parameter block of the problem, -1 for a block
  // that is no variable (constant, or used by no residual).
  int ColumnOf(const double* block) const;
  // Fixed with the envelope at construction: a pass over its entries.
  const BandedSize& Size() const { return size_; }

  // The variables' values as a state vector, and back.
  Eigen::VectorXd Gather() const;
  void Scatter(const Eigen::VectorXd& x) const;
  // `x` clamped to the variables' bounds, as Ceres's ParameterBlock::Plus
  // projects x + dx onto them (a self-calibration's physical range).
  void Project(Eigen::VectorXd* x) const;

  // The cost of the terms no variable changes; false as Linearize.
  bool FixedCost(double* cost);
  // The cost at x, the same sum as Linearize's; false as Linearize.
  bool Cost(const Eigen::VectorXd& x, double* cost);
  // The cost, gradient g = J^T r and H = J^T J at x, with each robust
  // loss's correction of the residual and Jacobian (Triggs et al. 2000,
  // 4.3, clamped as Ceres's Corrector clamps it where rho'' <= 0); false
  // where a residual or Jacobian is not finite or a cost function fails.
  bool Linearize(const Eigen::VectorXd& x, double* cost, Eigen::VectorXd* g,
                 EnvelopeMatrix* h);
  // The residual rows of the problem, its residual blocks in order (the
  // fixed cost's too).
  int num_rows() const { return num_rows_; }
  // At x, per residual row: the residual as its loss corrects it, and the
  // row's share of tr(U^T J^T J Z), sum_p (J z_p)_row (J u_p)_row over the
  // columns of `z` and `u` (num_columns() rows each; 0 on fixed rows). One
  // pass over the terms, no Jacobian kept. False as Linearize.
  bool RowProducts(const Eigen::VectorXd& x,
                   const EnvelopeMatrix::RowMajorMatrix& z,
                   const EnvelopeMatrix::RowMajorMatrix& u,
                   Eigen::VectorXd* residuals, Eigen::VectorXd* products);

 private:
  // One residual block: its cost, loss and parameter blocks, each with its
  // first column in the system (-1 for a constant block) and size; the
  // arrays are BandedProblem's, shared by all terms.
  struct Term {
    const ceres::CostFunction* cost = nullptr;
    const ceres::LossFunction* loss = nullptr;
    int num_blocks = 0;
    double* const* blocks = nullptr;
    const int* column = nullptr;
    const int* size = nullptr;
    int first_row = 0;  // Among the problem's residual rows.
    // Per block: whether it is a wide timed variable, whose products with
    // the term's other such blocks go through the panel.
    const char* in_panel = nullptr;
    int num_panel_blocks = 0;
    // Set on each of a run of PoseMapped costs of one pose map (the costs
    // at one time) with more than 3 rows in all. Such a cost is evaluated at
    // its pose (EvaluateOnPose): its rows on the weights are G Phi, G its
    // rows on the pose (x, y, theta), and the run's join the panel as the
    // at most 3 rows R Phi, R^T R = G^T G, which the last of the run
    // (`closes_run`) adds.
    const PoseMapped* compressed = nullptr;
    bool closes_run = false;
  };

  std::vector<int> EnvelopeFirst() const;
  // Marks the runs of terms whose panel rows are compressed (Term).
  void MarkCompressedRuns();
  // The rows of `rows` more rows in the panel, after flushing it when full
  // or on other blocks than the term's panel blocks.
  double* PanelRows(const Term& term, int rows, EnvelopeMatrix* h);
  // A compressed term's cost at x, its corrected residual, its rows G on
  // its pose and on its landmark in the buffers below.
  bool EvaluateOnPose(const Term& term, const Eigen::VectorXd& x, double* cost);
  // g and H from the last EvaluateOnPose: the landmark's products at once,
  // the weights' through the run's G^T G, and at the run's end the rows of
  // R Phi to the panel (banded_pose_runs.cc).
  void AccumulateRun(const Term& term, Eigen::VectorXd* g, EnvelopeMatrix* h);
  // One term's cost at x and, with `jacobians`, its corrected residual and
  // Jacobian blocks in the buffers below.
  bool Evaluate(const Term& term, const Eigen::VectorXd& x, bool jacobians,
                double* cost);
  // g += J^T r and the lower triangle of H += J^T J, block pair by pair,
  // from the last Evaluate; the products among a term's panel blocks are
  // deferred to the panel (FlushPanel).
  void Accumulate(const Term& term, Eigen::VectorXd* g, EnvelopeMatrix* h);
  // H += P_a^T P_b for the panel's block pairs: consecutive terms on the
  // same wide blocks (a feature window's observations) as one BLAS-3
  // product instead of a rank-one update per row.
  void FlushPanel(EnvelopeMatrix* h);

  std::vector<double*> variables_;  // In column order, with their sizes.
  std::unordered_map<const double*, int> first_column_;  // Of variables.
  std::vector<int> variable_sizes_;
  // Per column: its bounds (infinite where it has none); empty without any.
  Eigen::VectorXd lower_, upper_;
  std::vector<double*> blocks_;  // Every term's blocks, columns and sizes.
  std::vector<int> columns_, sizes_;
  std::vector<char> in_panel_;
  std::vector<Term> terms_, fixed_terms_;
  int num_columns_ = 0;
  int num_rows_ = 0;
  bool has_panels_ = false;
  int compressed_runs_ = 0;
  std::vector<int> envelope_first_;
  BandedSize size_;
  std::vector<const double*> parameters_;
  std::vector<std::vector<double>> jacobian_rows_;
  std::vector<double*> jacobian_pointers_;
  std::vector<double> residual_buffer_;  // The last term's residual.
  // The panel: rows of the terms on `panel_columns_` (their first columns;
  // widths `panel_sizes_`), row-major, panel_rows_ of them.
  std::vector<int> panel_columns_, panel_sizes_;
  std::vector<double> panel_;
  int panel_rows_ = 0;
  // The last EvaluateOnPose's rows (row-major): on the pose (x, y, theta)
  // and on the landmark.
  std::vector<double> pose_rows_, landmark_rows_;
  // The open run's G^T G.
  Eigen::Matrix3d run_gram_;
  bool run_open_ = false;
};

// A layout with g = J^T r and H = J^T J accumulated at x (Linearize), as
// a solve leaves them: the variance components and the convergence check
// factorise that H rather than linearising the same point again.
struct BandedLinearization {
  std::shared_ptr<BandedProblem> banded;
  Eigen::VectorXd x, gradient;
  std::unique_ptr<EnvelopeMatrix> hessian;
};

}  // namespace rff

#endif  // RFF_CERES_BANDED_PROBLEM_H_
