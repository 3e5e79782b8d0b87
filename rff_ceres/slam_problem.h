// Builds the MAP problem of the paper as a ceres::Problem: one residual block
// per observation over the trajectory blocks its pose map touches and one
// landmark block; odometry over the blocks of two poses; pose, landmark and
// trajectory priors. Landmarks go into elimination group 0 so that the Schur
// solvers eliminate them first.
#ifndef RFF_CERES_SLAM_PROBLEM_H_
#define RFF_CERES_SLAM_PROBLEM_H_

#include <map>
#include <memory>
#include <set>
#include <string>
#include <string_view>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "Eigen/Core"
#include "ceres/loss_function.h"
#include "ceres/ordered_groups.h"
#include "ceres/problem.h"
#include "costs/noise_weighted.h"
#include "rff_ceres/banded_problem.h"
#include "rff_ceres/folded_prior.h"
#include "rff_ceres/odometry_preintegration.h"
#include "rff_ceres/trajectory_model.h"
#include "rff_ceres/types.h"

namespace rff {

// Robust loss on the whitened observation residuals (range, bearing,
// range-bearing); the scale is in units of sigma. "auto" is Cauchy for the
// solve, then none where its residuals show no outlier (RunSlam): on Gaussian
// data the quadratic loss is the MAP, and Cauchy's down-weighting costs.
struct LossOptions {
  std::string name = "none";  // none | huber | cauchy | auto
  double scale = 1.0;
};

// Returns the loss (nullptr for "none"), or sets `error` for an unknown name
// or a scale that is not positive, naming the flags `flag` and
// `flag`_scale ("loss" or "odometry_loss").
bool CreateLoss(const LossOptions& options, const std::string& flag,
                std::unique_ptr<ceres::LossFunction>* loss, std::string* error);

// Self-calibration of the range sensor: the range of every RANGE and
// RANGE_BEARING record is modelled as scale * distance + offset with one
// (scale, offset) for the whole run, under the prior scale ~ N(1,
// scale_sigma^2), offset ~ N(0, offset_sigma^2).
// Bounds of the range self-calibration (scale, offset): a physical sensor.
inline constexpr double kMinRangeScale = 0.5;
inline constexpr double kMaxRangeScale = 2.0;
inline constexpr double kMaxOffsetSigmas = 5.0;

struct RangeCalibrationOptions {
  bool estimate = false;
  double scale_sigma = 0.1;
  double offset_sigma = 1.0;  // m
};

// Self-calibration of the odometry (calibrated_odometry_cost.h): every ODOM
// motion is the true one with its translation scaled by s and its turn by w,
// one (s, w) for the whole run, under the prior s, w ~ N(1, scale_sigma^2)
// and within a factor 2 of one. Commanded velocities (MRCLAM) overstate both
// by 4-10%. Off by default: on the held-out table it helps as often as it
// hurts (docs/heldout.md), bearing-only runs most.
inline constexpr double kMinOdometryScale = 0.5;
inline constexpr double kMaxOdometryScale = 2.0;

struct OdometryCalibrationOptions {
  bool estimate = false;
  double scale_sigma = 0.1;
};

// Factors on the sigmas of the data by kind: 1 keeps the dataset's own;
// re-estimated from the residuals when the data show them wrong
// (variance_components.h).
struct NoiseScales {
  double range = 1.0;
  double bearing = 1.0;
  double odometry = 1.0;
};

// What the variance of a residual row scales with: a noise scale of the
// data, a scale of the trajectory prior, or nothing re-estimated (priors on
// poses, landmarks and calibration, which state the user's knowledge).
enum class VarianceGroup {
  kFixed,
  kRange,
  kBearing,
  kOdometry,
  kPriorPosition,
  kPriorHeading
};
inline constexpr int kNumVarianceGroups = 6;

// The variance group of row `row` of a residual block of data kind `kind`
// (a range-bearing block is range, then bearing); kFixed for the priors.
// For a kind name alone ("range", "bearing", "odometry"), row 0.
VarianceGroup DataRowGroup(std::string_view kind, int row);

// The factor `noise` puts on the sigmas of `group`'s rows; 1 for the rest.
double NoiseScale(const NoiseScales& noise, VarianceGroup group);

// Robust by default: real recordings carry outliers and heavy tails
// (MRCLAM's commanded velocities, wrong associations); "auto" then drops the
// loss where the data turn out Gaussian (docs/heldout.md has both).
inline const LossOptions kDefaultLoss = {"auto", 2.0};

struct ProblemOptions {
  LossOptions loss = kDefaultLoss;
  NoiseScales noise;
  // On the whitened odometry residuals (commanded velocities have heavy
  // tails where the robot lags its commands).
  LossOptions odometry_loss = kDefaultLoss;
  RangeCalibrationOptions range_calibration;
  OdometryCalibrationOptions odometry_calibration;
  // What the range of a RANGE_BEARING record measures: "distance", "depth"
  // along the heading (a camera's range from a landmark's apparent size), or
  // "auto" (range_reading.h: depth where the first solve's residuals say so).
  std::string range_bearing_ranges = "auto";
  bool use_odometry = true;
  // Compose ODOM chains between observation times into one residual each
  // (see odometry_preintegration.h).
  bool preintegrate_odometry = true;
  double max_preintegration_seconds = 1.0;
};

// The odometry residuals of `dataset` under `options` (composed chains
// ending at every observation and prior time, or one per record); none
// without use_odometry. Fails when a covariance cannot be inverted.
bool OdometryChains(const Dataset& dataset, const ProblemOptions& options,
                    std::vector<PreintegratedOdometry>* chains,
                    std::string* error);

// The values of ProblemOptions::range_bearing_ranges.
inline std::vector<std::string> RangeBearingRangeNames() {
  return {"auto", "distance", "depth"};
}

// Fails naming the flag of a calibration prior sigma that is not finite and
// positive (checked whether or not the calibration is estimated), or of an
// unknown range_bearing_ranges.
bool CheckCalibrationOptions(const ProblemOptions& options, std::string* error);

// The linear solver of "auto": DENSE_SCHUR when the reduced system (every
// trajectory parameter after the landmarks are eliminated) is dense by the
// model's structure and has at most kMaxDenseReducedSystem unknowns, else
// SPARSE_NORMAL_CHOLESKY, whose fill-reducing ordering handles landmarks
// seen from the whole run and banded WNOA states.
inline constexpr int kMaxDenseReducedSystem = 2000;
ceres::LinearSolverType AutoLinearSolverType(const TrajectoryModel& model);

// The blocks of `model` as BANDED_CHOLESKY's columns: timed in time order,
// the shared ones last.
BandedColumns ModelBandColumns(TrajectoryModel* model);

class SlamProblem {
 public:
  // `model` must outlive the problem; its blocks are the problem's.
  SlamProblem(TrajectoryModel* model, const ProblemOptions& options);

  // Adds every residual of `dataset`; `landmarks` holds the initial position
  // of every observed or prior landmark (see InitializeLandmarks).
  bool Build(const Dataset& dataset,
             const std::map<LandmarkId, Eigen::Vector2d>& landmarks,
             std::string* error);

  // The same problem built piece by piece (incremental mode): Begin() adds
  // the trajectory blocks (and the range calibration) and makes room for the
  // landmarks with the given ids, then the trajectory prior (through the
  // model) and residuals are added as the data arrives. A landmark must be
  // added before its prior or observations.
  bool Begin(const std::vector<LandmarkId>& landmark_ids, std::string* error);
  void AddLandmark(LandmarkId id, const Eigen::Vector2d& initial);
  bool has_landmark(LandmarkId id) const { return added_.count(id) > 0; }
  bool has_landmark_prior(LandmarkId id) const {
    return has_prior_.count(id) > 0;
  }
  void AddLandmarkPrior(const LandmarkPrior& prior);
  void AddPosePrior(const PosePrior& prior);
  void AddOdometry(const PreintegratedOdometry& odometry);
  void AddObservation(const Observation& observation);

  ceres::Problem* problem() { return problem_.get(); }
  const TrajectoryModel& model() const { return *model_; }
  // Whether the residuals built under `options` are those of this problem:
  // the same losses ("auto" builds Cauchy's), noise scales, odometry and
  // calibrations.
  bool BuiltWith(const ProblemOptions& options) const;
  // Whether FollowScales can make this problem the one Build would give
  // under `options` (which may differ from the problem's in noise scales
  // and losses only): built whole (Build) with costs that take new weights
  // in place, and no calibration estimated.
  bool CanFollowScales(const ProblemOptions& options) const;
  // Gives the data costs the noise scales and losses of `options` and the
  // trajectory prior's costs the model's current scales (TrajectoryModel::
  // UpdatePriorCosts), in place, bit for bit as a build would, and drops
  // the kept linearisation.
  void FollowScales(const ProblemOptions& options);
  // (scale, offset) of the range sensor: (1, 0) unless estimated. Set it
  // before Begin() to start from another value.
  const Eigen::Vector2d& range_calibration() const {
    return range_calibration_;
  }
  void set_range_calibration(const Eigen::Vector2d& value) {
    range_calibration_ = value;
  }
  // (translation scale, turn scale) of the odometry: (1, 1) unless
  // estimated. Set it before Begin() to start from another value.
  const Eigen::Vector2d& odometry_calibration() const {
    return odometry_calibration_;
  }
  void set_odometry_calibration(const Eigen::Vector2d& value) {
    odometry_calibration_ = value;
  }

  // The current values of the added landmarks.
  std::map<LandmarkId, Eigen::Vector2d> landmarks() const;
  // The parameter block of a landmark (nullptr if the problem has none).
  double* landmark_block(LandmarkId id) {
    return has_landmark(id) ? storage_[slots_.at(id)].data() : nullptr;
  }
  // Numerical guards. FindNonFinite evaluates every residual block at the
  // current values and describes the first whose residual or Jacobian is
  // not finite (false if there is none). CheckLandmarksDetermined fails,
  // naming the landmark, when the information of a landmark without a prior
  // from its own residuals (without robust weights) is singular or
  // ill-conditioned (condition number above `max_condition`): its estimate
  // would be noise.
  bool FindNonFinite(std::string* description);
  // The block's whitened residuals without its robust loss; false where
  // Ceres cannot evaluate it (a non-finite residual).
  bool EvaluateWithoutLoss(ceres::ResidualBlockId id,
                           std::vector<double>* residuals);
  // The whitened residuals (without the robust loss) at the current values,
  // grouped by what they are: "range", "bearing", "range-bearing",
  // "odometry", "landmark prior", "pose prior", "range calibration prior"
  // and "trajectory prior" (the model's own: RFF weights, WNOA motion).
  // With `stated_sigmas`, whitened by the data's own sigmas rather than the
  // noise-scaled ones the problem is solved with.
  std::map<std::string, std::vector<double>> WhitenedResidualsByKind(
      bool stated_sigmas = false);
  // The whitened residuals (without the robust loss) of each landmark's
  // observations in time order, per sensor value (kRange, kBearing; a
  // range-bearing block's rows go one to each).
  std::map<VarianceGroup, std::map<LandmarkId, std::vector<double>>>
  ObservationResidualSeries();
  bool CheckLandmarksDetermined(double max_condition, std::string* error);
  // The variance group of every row of the residual blocks `ids`, in order.
  std::vector<VarianceGroup> RowGroups(
      const std::vector<ceres::ResidualBlockId>& ids);
  // Information of a landmark given the trajectory, sum of J_l^T J_l over its
  // residuals (through the robust loss if `apply_loss`); zero if unknown.
  Eigen::Matrix2d LandmarkInformation(LandmarkId id, bool apply_loss);

  // Fixed-lag smoothing: every data residual whose timed trajectory blocks
  // are all constant, and which still moves another block (its landmark, a
  // calibration, the mean's rotation), leaves the problem for a FoldedPrior
  // cost on those blocks, linearised where they are now (a robust loss's
  // weight rho' taken there). Residuals of a landmark without a prior stay.
  // Returns how many it folded; a problem with folded residuals is no longer
  // the data's whole problem (whoever folds builds that again for covariances
  // and reports).
  int FoldFrozenResiduals();
  int num_folded() const;  // In all, over the priors.

  // Landmarks in group 0 (eliminated first), trajectory blocks in group 1,
  // the model's shared blocks (a rotation of its mean) in group 2, the range
  // and odometry calibrations in group 3. Null without landmarks: Ceres then
  // finds its own independent set to eliminate.
  std::shared_ptr<ceres::ParameterBlockOrdering> Ordering();
  // Every parameter block in the columns of a time-ordered system: the
  // trajectory blocks in the model's (time) order, the landmarks each placed
  // after its sightings, the shared blocks and calibrations last.
  BandedColumns BandColumns();
  // The problem laid out on `columns` (its BandColumns()) for
  // BANDED_CHOLESKY: the last layout while the residual blocks' count, the
  // parameter blocks (each as constant or not) and `columns` are those it
  // was made for, as the costs take new weights in place between learning
  // rounds; a new one otherwise.
  std::shared_ptr<BandedProblem> BandedLayout(const BandedColumns& columns);
  // What the last BANDED_CHOLESKY solve left (RunSolve): its layout and
  // its linearisation at the values it wrote back, for FactorizeBanded.
  void KeepLinearization(BandedLinearization linearization);
  // Moves it into `linearization` while the problem has the same number of
  // residual blocks and the same parameter blocks, each as constant and
  // with the same values, as when it was kept; false otherwise. None is
  // kept after either way. Residuals changed another way (costs following
  // a model's scales in place, TrajectoryModel::AdoptScales) go unseen:
  // whoever changes them drops it.
  bool TakeLinearization(BandedLinearization* linearization);
  bool has_linearization() const { return kept_.hessian != nullptr; }
  // Frees it: a new solve must not hold an old H beside its own.
  void DropLinearization() { kept_ = BandedLinearization(); }

 private:
  // What TakeLinearization compares: the residual blocks' count, every
  // parameter block (constant or not) and all their values.
  struct BlockState {
    int num_residual_blocks = 0;
    std::vector<std::pair<const double*, bool>> blocks;
    std::vector<double> values;
    bool operator==(const BlockState& other) const;  // Values bit for bit.
  };
  BlockState CurrentBlockState(bool with_values = true) const;
  // Parameter blocks of a cost over `maps` (model block ids rewritten to the
  // cost's local indices, in place), with `landmark` appended if non-null.
  std::vector<double*> LocalBlocks(std::vector<PoseMap*> maps,
                                   double* landmark);

  // What a residual block is, for messages.
  struct Source {
    const char* kind = "";
    double t0 = 0.0, t1 = 0.0;
    LandmarkId landmark = 0;
    bool has_landmark = false;
    bool has_time = true;  // Priors on landmarks and calibrations have none.
    // DataRowGroup of its first row and of the others, set by Remember:
    // looked up per row by every round's variance components.
    VarianceGroup first_row = VarianceGroup::kFixed;
    VarianceGroup later_rows = VarianceGroup::kFixed;
    VarianceGroup RowGroup(int row) const {
      return row == 0 ? first_row : later_rows;
    }
  };
  std::string Describe(ceres::ResidualBlockId id) const;
  // One residual block at the current values: its cost, residuals and the
  // row-major Jacobian of each block not held constant (nullptr for those,
  // whose Jacobian Ceres refuses). Buffers keep their capacity across calls.
  struct BlockEvaluation {
    std::vector<double*> blocks;
    std::vector<int32_t> sizes;
    double cost = 0.0;
    std::vector<double> residuals;
    std::vector<std::vector<double>> jacobian_rows;
    std::vector<double*> jacobians;
  };
  bool EvaluateVariableBlocks(ceres::ResidualBlockId id, bool apply_loss,
                              BlockEvaluation* evaluation);
  // A calibration block `values` under the prior N(mean, diag(sigma^2)) (a
  // residual of kind `kind`, a literal), held within [lower, upper].
  void AddCalibration(const char* kind, const Eigen::Vector2d& mean,
                      const Eigen::Vector2d& sigma,
                      const Eigen::Vector2d& lower,
                      const Eigen::Vector2d& upper, double* values);
  // The losses of `options` into loss_ and odometry_loss_ (and options_);
  // fails for a name or scale CreateLoss refuses.
  bool SetLosses(const ProblemOptions& options, std::string* error);
  void Remember(ceres::ResidualBlockId id, Source source) {
    source.first_row = DataRowGroup(source.kind, 0);
    source.later_rows = DataRowGroup(source.kind, 1);
    sources_[id] = source;
    if (source.has_landmark) landmark_residuals_[source.landmark].push_back(id);
  }

  TrajectoryModel* model_;
  ProblemOptions options_;
  // What FollowScales rewrites: each data cost with its stated sigmas or
  // square-root information (before the noise scales), and the costs the
  // model's AddPriorCosts added. Set by Build; `weighted_` false where a
  // cost cannot follow.
  struct ObservationWeights {
    ObservationWeighted* cost;
    double sigma_range, sigma_bearing;
  };
  struct OdometryWeights {
    OdometryWeighted* cost;
    Eigen::Matrix3d sqrt_information;
  };
  std::vector<ObservationWeights> observation_weights_;
  std::vector<OdometryWeights> odometry_weights_;
  std::vector<ceres::CostFunction*> prior_costs_;
  bool weighted_ = true;
  bool built_ = false;
  // Looked up once per residual block in each pass over them, or walked
  // (ObservationResidualSeries, which orders what it finds).
  std::unordered_map<ceres::ResidualBlockId, Source> sources_;
  // Ceres's own lookup scans every residual (without fast removal).
  std::map<LandmarkId, std::vector<ceres::ResidualBlockId>> landmark_residuals_;
  // Every observation's and every odometry residual's loss, the losses
  // options_ names inside: a settled "auto" changes them in place.
  ceres::LossFunctionWrapper loss_{nullptr, ceres::TAKE_OWNERSHIP};
  ceres::LossFunctionWrapper odometry_loss_{nullptr, ceres::TAKE_OWNERSHIP};
  std::unique_ptr<ceres::Problem> problem_;
  // Landmark blocks in one buffer in id order (Ceres orders an elimination
  // group by address: this keeps the solve's arithmetic reproducible).
  std::map<LandmarkId, int> slots_;
  std::vector<Eigen::Vector2d> storage_;
  BandedLinearization kept_;
  BlockState kept_state_;
  std::shared_ptr<BandedProblem> layout_;
  BlockState layout_state_;  // Without values.
  BandedColumns layout_columns_;
  std::set<LandmarkId> added_;
  std::set<LandmarkId> has_prior_;
  Eigen::Vector2d range_calibration_ = Eigen::Vector2d(1.0, 0.0);
  Eigen::Vector2d odometry_calibration_ = Eigen::Vector2d(1.0, 1.0);
  // One folded prior per landmark (and one for residuals without one): no
  // residual couples two landmarks, so neither do these, and the landmarks
  // stay an independent set for a Schur solver.
  struct Folded {
    FoldedPrior prior;
    ceres::ResidualBlockId block = nullptr;
  };
  std::map<std::pair<bool, LandmarkId>, Folded> folded_;
  // The model's timed blocks (not a shared one, such as the mean's
  // rotation, which moves every pose), filled by the first fold.
  std::unordered_set<const double*> timed_blocks_;
};

}  // namespace rff

#endif  // RFF_CERES_SLAM_PROBLEM_H_
