// The Gauss-Newton information matrix H = J^T J of a SLAM problem at its
// current values, factorised for solves and marginal covariances. With the
// columns ordered [t columns of the trajectory and the other blocks |
// landmarks, two each] and every row touching at most one landmark,
//
//   H = [A B; B^T C],  C = diag(C_1, ..., C_L),  S = A - B C^-1 B^T,
//   H^-1 = [S^-1, -S^-1 B C^-1; ., C^-1 + C^-1 B^T S^-1 B C^-1],
//
// so the trajectory's covariance is S^-1 and landmark k's is
// C_k^-1 + C_k^-1 B_k^T S^-1 B_k C_k^-1: linear in the number of landmarks
// (the Schur complement of Ceres's own solvers, Triggs et al. 2000, 6.1).
// This structured form is used while S (t x t) and B (t x 2L) fit in
// memory (1 <= t <= kMaxDenseReducedSystem, t (t + m) <= 2^25 doubles for
// S and B; their products need as much again) and every C_k keeps 8
// digits; otherwise H is a sparse LDLT, for solves only.
#ifndef RFF_CERES_GAUSS_NEWTON_SYSTEM_H_
#define RFF_CERES_GAUSS_NEWTON_SYSTEM_H_

#include <memory>
#include <string>
#include <vector>

#include "Eigen/Cholesky"
#include "Eigen/Core"
#include "Eigen/SparseCholesky"
#include "Eigen/SparseCore"
#include "rff_ceres/banded_problem.h"
#include "rff_ceres/envelope_cholesky.h"
#include "rff_ceres/slam_problem.h"

namespace rff {

// A Gauss-Newton matrix whose reciprocal condition is at most this is
// singular to rounding: its inverse is noise, and a rank-revealing QR of J
// decides instead (the Schur form here, the envelope's covariance).
inline constexpr double kMinReciprocalCondition = 1e-14;

using RowMajorSparse = Eigen::SparseMatrix<double, Eigen::RowMajor>;

// The problem's parameter blocks with its landmarks last: the model's in
// its order, its shared blocks and calibrations, then the landmarks by id
// (SlamProblem::BandColumns, not the heap's order); `*num_leading` gets the
// parameters before them. The column order GaussNewtonSystem expects.
std::vector<double*> LandmarksLast(SlamProblem* problem, int* num_leading);

// Where each column of a Jacobian over the blocks `columns` goes in the
// time order of BANDED_CHOLESKY (BandedBlockOrder); empty when `columns`
// holds a block that order has not.
std::vector<int> TimeOrderPositions(SlamProblem* problem,
                                    const std::vector<double*>& columns);

// Whether the Schur form of t leading and m landmark columns fits (sizes
// only; the structure and conditioning are checked on the Jacobian).
bool SchurFormFits(int t, Eigen::Index m);

// Whether H is factorised in an envelope of `size` for solves: it fits the
// memory of the dense forms and its work is within the bound of
// BandedSize::WorkWithinBound.
bool EnvelopeAffordable(const BandedSize& size);

// How a GaussNewtonSystem is factorised.
enum class Factorization {
  // The Schur form where it fits (covariances available), else the sparse
  // LDLT.
  kSchurOrSparse,
  // The Schur form only; a system without it is left unfactorised
  // (positive_definite() false).
  kSchurOnly,
  // The sparse LDLT (solves only): for banded states (WNOA), whose dense
  // Schur complement would cost t^3 / 3 for what a band does in O(t).
  kSparse,
  // An envelope Cholesky (envelope_cholesky.h) with the columns in a time
  // order, where EnvelopeAffordable: no symbolic analysis and no fill
  // outside the band (solves only); else kSparse.
  kEnvelopeOrSparse,
};

// The sparse LDLT's symbolic analysis (fill-reducing ordering, elimination
// tree) of one pattern of H, kept between systems of the same structure
// (the rounds of the learned scales). It depends on the pattern alone, so
// reusing it changes no digit.
struct SparseAnalysis {
  std::vector<int> outer, inner;  // The pattern analysed.
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
};

class GaussNewtonSystem {
 public:
  // `jacobian`'s first `t` columns are the leading blocks, the rest the
  // landmarks, two each. With `analysis`, the sparse LDLT is factorised in
  // it, analysed only when H's pattern is not the one it holds; it must
  // outlive this system and serve one system at a time. kEnvelopeOrSparse
  // puts column c at `time_order[c]` (TimeOrderPositions).
  GaussNewtonSystem(const RowMajorSparse& jacobian, int t,
                    Factorization factorization,
                    SparseAnalysis* analysis = nullptr,
                    std::vector<int> time_order = {});

  // Whether the Schur form was built (covariances are available).
  bool structured() const { return structured_; }
  bool positive_definite() const { return positive_definite_; }
  // Whether H was factorised as an envelope.
  bool envelope() const { return envelope_ != nullptr; }
  // H^-1 z, every column of z at once: the sparse factor is read once for
  // all of them, with the same arithmetic as one column at a time.
  Eigen::MatrixXd Solve(const Eigen::MatrixXd& z) const;
  // log det H (positive definite only): the envelope's, det C det S of the
  // Schur form (C the landmarks' blocks), or the sparse LDLT's pivots.
  double LogDeterminant() const;
  // Structured only: S^-1, the covariance of the leading t parameters.
  Eigen::MatrixXd LeadingCovariance() const;
  // Structured only: the 2x2 covariance of every landmark.
  std::vector<Eigen::Matrix2d> LandmarkCovariances() const;

 private:
  bool FormSchur(const RowMajorSparse& jacobian, int t);
  // False (nothing formed) where the envelope costs too much or its
  // Cholesky finds H not positive definite.
  bool FormEnvelope(const RowMajorSparse& jacobian);
  Eigen::VectorXd ApplyCInverse(const Eigen::VectorXd& v) const;

  bool structured_ = false;
  bool positive_definite_ = false;
  Eigen::MatrixXd b_;
  std::vector<Eigen::Matrix2d> c_inverse_;
  Eigen::LDLT<Eigen::MatrixXd> schur_;
  std::vector<int> time_order_;
  std::unique_ptr<EnvelopeMatrix> envelope_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> own_sparse_;
  // own_sparse_ or the analysis's.
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>* sparse_ = &own_sparse_;
};

// H of a banded-state `problem` at its current values, accumulated from its
// residual blocks in the time-ordered envelope BANDED_CHOLESKY factorises,
// and factorised: `banded` the problem's layout, `x` its values, `gradient`
// J^T r; the H a BANDED_CHOLESKY solve kept at these values when there is
// one (any model). Otherwise built where the envelope serves as auto's
// solve would take it: feature weights whose envelope step costs no more
// than their dense reduced system's (EnvelopeAndDenseStepWork), other
// models where it beats a sparse Cholesky; false where it does not serve
// (bounds, manifolds, too costly, or H not positive definite to rounding).
struct BandedSystem {
  std::shared_ptr<BandedProblem> banded;
  Eigen::VectorXd x, gradient;
  std::unique_ptr<EnvelopeMatrix> factor;
};
bool FactorizeBanded(SlamProblem* problem, BandedSystem* system);

// g^T H^-1 g / 2 at the problem's values, g = J^T r and H = J^T J of its
// whitened, loss-corrected residuals: what the Gauss-Newton model still
// expects to gain (a minimum leaves nothing). Models the envelope serves
// solve with H's envelope factor (FactorizeBanded); others with H's Schur
// form where it costs no
// more than the bound below (few weights beside the landmarks); the rest
// take at most 100 steps of conjugate gradients on J^T J with H's diagonal
// as preconditioner, whose estimate rises towards the value from below
// (Gauss quadrature: Golub and Meurant 2010, 3.2), so no large dense
// reduced system is factorised for a check and a decrease it finds is
// there. NaN where it cannot tell (an evaluation fails, H not positive
// definite). `exact`, when given, is set to whether the value is the
// decrease itself (a factorisation's) rather than a bound or NaN.
double GaussNewtonDecrease(SlamProblem* problem, bool* exact = nullptr);

}  // namespace rff

#endif  // RFF_CERES_GAUSS_NEWTON_SYSTEM_H_
