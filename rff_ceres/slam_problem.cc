#include "rff_ceres/slam_problem.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string_view>

#include "Eigen/Eigenvalues"
#include "costs/calibrated_odometry_cost.h"
#include "costs/diagonal_prior_cost.h"
#include "costs/landmark_prior_cost.h"
#include "costs/odometry_cost.h"
#include "costs/pose_prior_cost.h"
#include "glog/logging.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/measurement_types.h"
#include "rff_ceres/option_error.h"

namespace rff {

VarianceGroup DataRowGroup(std::string_view kind, int row) {
  if (const MeasurementType* type = FindMeasurementKind(kind)) {
    // Rows are the measured values in the record's order: range first.
    return type->range && row == 0 ? VarianceGroup::kRange
                                   : VarianceGroup::kBearing;
  }
  return kind == "odometry" ? VarianceGroup::kOdometry : VarianceGroup::kFixed;
}

double NoiseScale(const NoiseScales& noise, VarianceGroup group) {
  switch (group) {
    case VarianceGroup::kRange:
      return noise.range;
    case VarianceGroup::kBearing:
      return noise.bearing;
    case VarianceGroup::kOdometry:
      return noise.odometry;
    default:
      return 1.0;
  }
}

namespace {

// The loss a name builds: "auto" is Cauchy's until its judging settles it.
std::string BuiltLossName(const std::string& name) {
  return name == "auto" ? std::string("cauchy") : name;
}

}  // namespace

bool CreateLoss(const LossOptions& options, const std::string& flag,
                std::unique_ptr<ceres::LossFunction>* loss,
                std::string* error) {
  loss->reset();
  // Checked with "none" too: a value given is checked, used or not. Scales
  // are in sigmas: beyond these bounds every residual, or none, is an
  // outlier, and the smallest overflow the loss's 1 / scale^2.
  constexpr double kMinLossScale = 1e-3, kMaxLossScale = 1e3;
  if (!CheckPositiveOption(options.scale, (flag + "_scale").c_str(), error)) {
    return false;
  }
  if (options.scale < kMinLossScale || options.scale > kMaxLossScale) {
    *error = OptionError(flag + "_scale", FormatNumber(options.scale), "",
                         FormatNumber(kMinLossScale) + " to " +
                             FormatNumber(kMaxLossScale) + " sigmas");
    return false;
  }
  const std::string built = BuiltLossName(options.name);
  if (built == "none") return true;
  if (built == "huber") {
    loss->reset(new ceres::HuberLoss(options.scale));
  } else if (built == "cauchy") {
    loss->reset(new ceres::CauchyLoss(options.scale));
  } else {
    *error = OptionError(flag, options.name, "unknown loss",
                         "none, huber, cauchy or auto");
    return false;
  }
  return true;
}

ceres::LinearSolverType AutoLinearSolverType(const TrajectoryModel& model) {
  int trajectory_parameters = 0;
  for (int b = 0; b < model.num_blocks(); ++b) {
    trajectory_parameters += model.block_size(b);
  }
  return model.HasDenseReducedSystem() &&
                 trajectory_parameters <= kMaxDenseReducedSystem
             ? ceres::DENSE_SCHUR
             : ceres::SPARSE_NORMAL_CHOLESKY;
}

namespace {

bool SameLoss(const LossOptions& a, const LossOptions& b) {
  return BuiltLossName(a.name) == BuiltLossName(b.name) && a.scale == b.scale;
}

// Whether problems built under `p` and `o` have the same residual blocks:
// they differ at most in noise scales and losses (which only weight them).
bool SameResidualBlocks(const ProblemOptions& p, const ProblemOptions& o) {
  return p.range_calibration.estimate == o.range_calibration.estimate &&
         p.range_calibration.scale_sigma == o.range_calibration.scale_sigma &&
         p.range_calibration.offset_sigma == o.range_calibration.offset_sigma &&
         p.odometry_calibration.estimate == o.odometry_calibration.estimate &&
         p.odometry_calibration.scale_sigma ==
             o.odometry_calibration.scale_sigma &&
         p.use_odometry == o.use_odometry &&
         p.preintegrate_odometry == o.preintegrate_odometry &&
         p.max_preintegration_seconds == o.max_preintegration_seconds;
}

}  // namespace

bool SlamProblem::BuiltWith(const ProblemOptions& o) const {
  const NoiseScales& n = options_.noise;
  return SameResidualBlocks(options_, o) && SameLoss(options_.loss, o.loss) &&
         SameLoss(options_.odometry_loss, o.odometry_loss) &&
         n.range == o.noise.range && n.bearing == o.noise.bearing &&
         n.odometry == o.noise.odometry;
}

bool SlamProblem::CanFollowScales(const ProblemOptions& options) const {
  // Bounded calibration blocks send the solve to Ceres's own minimiser,
  // which orders an elimination group's blocks by address: a kept problem,
  // its calibration blocks placed apart from the others, solved to other
  // last bits than a new one, and not the same from run to run. Those are
  // built again.
  const bool calibrated = options_.range_calibration.estimate ||
                          options_.odometry_calibration.estimate;
  std::unique_ptr<ceres::LossFunction> loss, odometry_loss;
  std::string error;
  return built_ && weighted_ && !calibrated &&
         SameResidualBlocks(options_, options) &&
         CreateLoss(options.loss, "loss", &loss, &error) &&
         CreateLoss(options.odometry_loss, "odometry_loss", &odometry_loss,
                    &error);
}

bool SlamProblem::SetLosses(const ProblemOptions& options, std::string* error) {
  std::unique_ptr<ceres::LossFunction> loss, odometry_loss;
  if (!CreateLoss(options.loss, "loss", &loss, error) ||
      !CreateLoss(options.odometry_loss, "odometry_loss", &odometry_loss,
                  error)) {
    return false;
  }
  // "none" leaves the wrappers empty: rho(s) = s, whose correction of the
  // residuals and Jacobians multiplies by 1, bit for bit no loss at all.
  loss_.Reset(loss.release(), ceres::TAKE_OWNERSHIP);
  odometry_loss_.Reset(odometry_loss.release(), ceres::TAKE_OWNERSHIP);
  options_.loss = options.loss;
  options_.odometry_loss = options.odometry_loss;
  return true;
}

void SlamProblem::FollowScales(const ProblemOptions& options) {
  const NoiseScales& noise = options.noise;
  std::string error;
  CHECK(SetLosses(options, &error)) << error;  // CanFollowScales built them.
  // The products AddObservation and AddOdometry form.
  for (const ObservationWeights& w : observation_weights_) {
    w.cost->SetSigmas(noise.range * w.sigma_range,
                      noise.bearing * w.sigma_bearing);
  }
  for (const OdometryWeights& w : odometry_weights_) {
    w.cost->SetSqrtInformation(w.sqrt_information / noise.odometry);
  }
  model_->UpdatePriorCosts(prior_costs_);
  options_.noise = noise;
  DropLinearization();
}

SlamProblem::SlamProblem(TrajectoryModel* model, const ProblemOptions& options)
    : model_(model), options_(options) {
  ceres::Problem::Options problem_options;
  // One loss object serves every observation; the problem must not delete it.
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_ = std::make_unique<ceres::Problem>(problem_options);
}

std::vector<double*> SlamProblem::LocalBlocks(std::vector<PoseMap*> maps,
                                              double* landmark) {
  std::vector<double*> blocks = BindPoseMaps(model_, maps);
  if (landmark != nullptr) blocks.push_back(landmark);
  return blocks;
}

void SlamProblem::AddObservation(const Observation& o) {
  PoseMap map = model_->PoseAt(o.t);
  double* landmark = landmark_block(o.id);
  std::vector<double*> blocks = LocalBlocks({&map}, landmark);
  ObservationResidualInputs inputs;
  inputs.sigma_range = options_.noise.range * o.sigma_range;
  inputs.sigma_bearing = options_.noise.bearing * o.sigma_bearing;
  if (options_.range_calibration.estimate) {
    inputs.range_calibration = range_calibration_.data();
  }
  inputs.range_is_depth = options_.range_bearing_ranges == "depth";
  const MeasurementType& type = MeasurementTypeOf(o.type);
  ceres::CostFunction* cost = type.cost(o, std::move(map), inputs, &blocks);
  if (auto* weighted = dynamic_cast<ObservationWeighted*>(cost)) {
    observation_weights_.push_back({weighted, o.sigma_range, o.sigma_bearing});
  } else {
    weighted_ = false;
  }
  Remember(problem_->AddResidualBlock(cost, &loss_, blocks),
           {type.kind, o.t, o.t, o.id, true});
}

bool CheckCalibrationOptions(const ProblemOptions& options,
                             std::string* error) {
  const std::pair<const char*, double> sigmas[] = {
      {"range_scale_sigma", options.range_calibration.scale_sigma},
      {"range_offset_sigma", options.range_calibration.offset_sigma},
      {"odometry_scale_sigma", options.odometry_calibration.scale_sigma}};
  for (const auto& [name, sigma] : sigmas) {
    if (!CheckPositiveOption(sigma, name, error)) return false;
  }
  return CheckOneOf(options.range_bearing_ranges, "range_bearing_ranges",
                    "unknown reading of the ranges", RangeBearingRangeNames(),
                    error);
}

bool SlamProblem::Begin(const std::vector<LandmarkId>& landmark_ids,
                        std::string* error) {
  if (!SetLosses(options_, error)) return false;
  for (const LandmarkId id : landmark_ids) slots_.emplace(id, 0);
  int slot = 0;
  for (auto& [id, index] : slots_) index = slot++;
  storage_.assign(slots_.size(), Eigen::Vector2d::Zero());
  for (int b = 0; b < model_->num_blocks(); ++b) {
    problem_->AddParameterBlock(model_->mutable_block(b),
                                model_->block_size(b));
  }
  // Physical sensors: scales within a factor 2 of one, the range offset
  // within kMaxOffsetSigmas of its prior; a bound that holds the solution is
  // reported as suspect (quality_report.h). The odometry's block joins with
  // the first odometry residual.
  if (!CheckCalibrationOptions(options_, error)) return false;
  const RangeCalibrationOptions& range = options_.range_calibration;
  if (range.estimate) {
    const double max_offset = kMaxOffsetSigmas * range.offset_sigma;
    AddCalibration("range calibration prior", Eigen::Vector2d(1.0, 0.0),
                   Eigen::Vector2d(range.scale_sigma, range.offset_sigma),
                   Eigen::Vector2d(kMinRangeScale, -max_offset),
                   Eigen::Vector2d(kMaxRangeScale, max_offset),
                   range_calibration_.data());
  }
  return true;
}

void SlamProblem::AddCalibration(const char* kind, const Eigen::Vector2d& mean,
                                 const Eigen::Vector2d& sigma,
                                 const Eigen::Vector2d& lower,
                                 const Eigen::Vector2d& upper, double* values) {
  Remember(problem_->AddResidualBlock(new DiagonalPriorCost(mean, sigma),
                                      nullptr, values),
           {kind, 0.0, 0.0, 0, false, /*has_time=*/false});
  for (int i = 0; i < 2; ++i) {
    problem_->SetParameterLowerBound(values, i, lower[i]);
    problem_->SetParameterUpperBound(values, i, upper[i]);
  }
}

void SlamProblem::AddLandmark(LandmarkId id, const Eigen::Vector2d& initial) {
  Eigen::Vector2d& position = storage_[slots_.at(id)];
  position = initial;
  added_.insert(id);
  problem_->AddParameterBlock(position.data(), 2);
}

std::map<LandmarkId, Eigen::Vector2d> SlamProblem::landmarks() const {
  std::map<LandmarkId, Eigen::Vector2d> values;
  for (const LandmarkId id : added_) values[id] = storage_[slots_.at(id)];
  return values;
}

void SlamProblem::AddLandmarkPrior(const LandmarkPrior& p) {
  has_prior_.insert(p.id);
  Remember(problem_->AddResidualBlock(
               new LandmarkPriorCost(Eigen::Vector2d(p.x, p.y), p.sigma),
               nullptr, landmark_block(p.id)),
           {"landmark prior", 0.0, 0.0, p.id, true, /*has_time=*/false});
}

void SlamProblem::AddPosePrior(const PosePrior& p) {
  PoseMap map = model_->PoseAt(p.pose.t);
  const std::vector<double*> blocks = LocalBlocks({&map}, nullptr);
  Remember(
      problem_->AddResidualBlock(
          new PosePriorCost(
              std::move(map), Eigen::Vector3d(p.pose.x, p.pose.y, p.pose.theta),
              Eigen::Vector3d(p.sigma_xy, p.sigma_xy, p.sigma_theta)),
          nullptr, blocks),
      {"pose prior", p.pose.t, p.pose.t});
}

void SlamProblem::AddOdometry(const PreintegratedOdometry& o) {
  PoseMap map0 = model_->PoseAt(o.t0);
  PoseMap map1 = model_->PoseAt(o.t1);
  std::vector<double*> blocks = LocalBlocks({&map0, &map1}, nullptr);
  const Eigen::Matrix3d stated = SqrtInformation(o.covariance);
  const Eigen::Matrix3d sqrt_information = stated / options_.noise.odometry;
  ceres::CostFunction* cost = nullptr;
  if (options_.odometry_calibration.estimate) {
    double* calibration = odometry_calibration_.data();
    if (!problem_->HasParameterBlock(calibration)) {
      AddCalibration(
          "odometry calibration prior", Eigen::Vector2d(1.0, 1.0),
          Eigen::Vector2d::Constant(options_.odometry_calibration.scale_sigma),
          Eigen::Vector2d::Constant(kMinOdometryScale),
          Eigen::Vector2d::Constant(kMaxOdometryScale), calibration);
    }
    blocks.push_back(calibration);
    cost = new CalibratedOdometryCost(std::move(map0), std::move(map1),
                                      o.motion, sqrt_information);
  } else {
    cost = new OdometryCost(std::move(map0), std::move(map1), o.motion,
                            sqrt_information);
  }
  if (auto* weighted = dynamic_cast<OdometryWeighted*>(cost)) {
    odometry_weights_.push_back({weighted, stated});
  } else {
    weighted_ = false;
  }
  Remember(problem_->AddResidualBlock(cost, &odometry_loss_, blocks),
           {"odometry", o.t0, o.t1});
}

bool OdometryChains(const Dataset& dataset, const ProblemOptions& options,
                    std::vector<PreintegratedOdometry>* chains,
                    std::string* error) {
  chains->clear();
  if (!options.use_odometry) return true;
  // Chains end at every time a pose is needed; without preintegration,
  // at every record (each record is a chain of its own).
  std::vector<double> keep_times;
  for (const Observation& o : dataset.observations) keep_times.push_back(o.t);
  for (const PosePrior& p : dataset.pose_priors) keep_times.push_back(p.pose.t);
  if (!options.preintegrate_odometry) {
    for (const Odometry& o : dataset.odometry) keep_times.push_back(o.t0);
  }
  std::sort(keep_times.begin(), keep_times.end());
  *chains = PreintegrateOdometry(dataset.odometry, keep_times,
                                 options.max_preintegration_seconds);
  for (const PreintegratedOdometry& o : *chains) {
    if (!SqrtInformation(o.covariance).allFinite()) {
      // Sigmas beyond 1e154 square past the largest double.
      *error = "odometry from t = " + FormatNumber(o.t0) + " to " +
               FormatNumber(o.t1) +
               ": its covariance cannot be inverted in double precision "
               "(sigmas too " +
               (o.covariance.allFinite() ? "small" : "large") + ")";
      return false;
    }
  }
  return true;
}

bool SlamProblem::Build(const Dataset& dataset,
                        const std::map<LandmarkId, Eigen::Vector2d>& landmarks,
                        std::string* error) {
  for (const Observation& o : dataset.observations) {
    if (landmarks.count(o.id) == 0) {
      *error = "landmark " + std::to_string(o.id) +
               " is observed but has no initial position";
      return false;
    }
  }
  std::vector<LandmarkId> ids;
  for (const auto& [id, position] : landmarks) ids.push_back(id);
  if (!Begin(ids, error)) return false;
  const int before = problem_->NumResidualBlocks();
  model_->AddPriorCosts(problem_.get());
  std::vector<ceres::ResidualBlockId> prior_blocks;
  problem_->GetResidualBlocks(&prior_blocks);
  for (std::size_t i = before; i < prior_blocks.size(); ++i) {
    // The model made them (mutable) and the problem owns them: Ceres hands
    // them back as const.
    prior_costs_.push_back(const_cast<ceres::CostFunction*>(
        problem_->GetCostFunctionForResidualBlock(prior_blocks[i])));
  }
  for (const auto& [id, position] : landmarks) AddLandmark(id, position);
  for (const PosePrior& p : dataset.pose_priors) AddPosePrior(p);
  for (const LandmarkPrior& p : dataset.landmark_priors) AddLandmarkPrior(p);
  std::vector<PreintegratedOdometry> odometry;
  if (!OdometryChains(dataset, options_, &odometry, error)) return false;
  for (const PreintegratedOdometry& o : odometry) AddOdometry(o);
  for (const Observation& o : dataset.observations) AddObservation(o);
  built_ = true;
  return true;
}

std::string SlamProblem::Describe(ceres::ResidualBlockId id) const {
  auto it = sources_.find(id);
  if (it == sources_.end()) return "a trajectory prior residual";
  const Source& s = it->second;
  std::string text = std::string("the ") + s.kind + " residual";
  if (s.t1 != s.t0) {
    text += " from t = " + FormatNumber(s.t0) + " to " + FormatNumber(s.t1);
  } else if (s.has_time) {
    text += " at t = " + FormatNumber(s.t0);
  }
  if (s.has_landmark) text += " of landmark " + std::to_string(s.landmark);
  return text;
}

bool SlamProblem::EvaluateWithoutLoss(ceres::ResidualBlockId id,
                                      std::vector<double>* residuals) {
  residuals->assign(
      problem_->GetCostFunctionForResidualBlock(id)->num_residuals(), 0.0);
  double cost = 0.0;
  return problem_->EvaluateResidualBlock(id, /*apply_loss_function=*/false,
                                         &cost, residuals->data(), nullptr);
}

std::map<std::string, std::vector<double>> SlamProblem::WhitenedResidualsByKind(
    bool stated_sigmas) {
  std::map<std::string, std::vector<double>> by_kind;
  std::vector<ceres::ResidualBlockId> ids;
  problem_->GetResidualBlocks(&ids);
  std::vector<double> residuals;
  for (const ceres::ResidualBlockId id : ids) {
    // Blocks added without a source are the trajectory model's own prior.
    const auto source = sources_.find(id);
    const char* name =
        source == sources_.end() ? "trajectory prior" : source->second.kind;
    if (!EvaluateWithoutLoss(id, &residuals)) continue;
    for (std::size_t row = 0; stated_sigmas && row < residuals.size();
         ++row) {
      residuals[row] *= NoiseScale(
          options_.noise, source == sources_.end()
                              ? VarianceGroup::kFixed
                              : source->second.RowGroup(static_cast<int>(row)));
    }
    std::vector<double>& kind = by_kind[name];
    kind.insert(kind.end(), residuals.begin(), residuals.end());
  }
  return by_kind;
}

std::map<VarianceGroup, std::map<LandmarkId, std::vector<double>>>
SlamProblem::ObservationResidualSeries() {
  // (time, residual) per value and landmark.
  std::map<VarianceGroup,
           std::map<LandmarkId, std::vector<std::pair<double, double>>>>
      timed;
  std::vector<double> residuals;
  for (const auto& [id, source] : sources_) {
    const VarianceGroup first = source.first_row;
    if (!source.has_landmark || !source.has_time ||
        (first != VarianceGroup::kRange && first != VarianceGroup::kBearing)) {
      continue;
    }
    if (!EvaluateWithoutLoss(id, &residuals)) continue;
    for (std::size_t row = 0; row < residuals.size(); ++row) {
      timed[source.RowGroup(static_cast<int>(row))][source.landmark]
          .emplace_back(source.t0, residuals[row]);
    }
  }
  std::map<VarianceGroup, std::map<LandmarkId, std::vector<double>>> series;
  for (auto& [group, by_landmark] : timed) {
    for (auto& [landmark, values] : by_landmark) {
      // By time, and a landmark seen twice at one time by value: the
      // blocks come in no fixed order.
      std::sort(values.begin(), values.end());
      std::vector<double>& out = series[group][landmark];
      for (const auto& [t, r] : values) out.push_back(r);
    }
  }
  return series;
}

bool SlamProblem::EvaluateVariableBlocks(ceres::ResidualBlockId id,
                                         bool apply_loss,
                                         BlockEvaluation* evaluation) {
  BlockEvaluation& e = *evaluation;
  const ceres::CostFunction* cost =
      problem_->GetCostFunctionForResidualBlock(id);
  const int rows = cost->num_residuals();
  e.sizes = cost->parameter_block_sizes();
  problem_->GetParameterBlocksForResidualBlock(id, &e.blocks);
  e.residuals.assign(rows, 0.0);
  e.jacobian_rows.resize(e.blocks.size());
  e.jacobians.assign(e.blocks.size(), nullptr);
  for (std::size_t j = 0; j < e.blocks.size(); ++j) {
    if (problem_->IsParameterBlockConstant(e.blocks[j])) continue;
    e.jacobian_rows[j].assign(static_cast<std::size_t>(rows) * e.sizes[j], 0.0);
    e.jacobians[j] = e.jacobian_rows[j].data();
  }
  e.cost = 0.0;
  return problem_->EvaluateResidualBlock(
      id, apply_loss, &e.cost, e.residuals.data(), e.jacobians.data());
}

bool SlamProblem::FindNonFinite(std::string* description) {
  std::vector<ceres::ResidualBlockId> ids;
  problem_->GetResidualBlocks(&ids);
  BlockEvaluation e;
  for (const ceres::ResidualBlockId id : ids) {
    // A constant (frozen) block's Jacobian is not asked for: Ceres's
    // refusal would be no non-finite value.
    bool finite = EvaluateVariableBlocks(id, /*apply_loss=*/true, &e) &&
                  std::isfinite(e.cost);
    for (const double r : e.residuals) finite = finite && std::isfinite(r);
    for (std::size_t j = 0; j < e.blocks.size(); ++j) {
      if (e.jacobians[j] == nullptr) continue;
      for (const double v : e.jacobian_rows[j]) {
        finite = finite && std::isfinite(v);
      }
    }
    if (!finite) {
      *description = Describe(id) + " is not finite";
      return true;
    }
  }
  return false;
}

Eigen::Matrix2d SlamProblem::LandmarkInformation(LandmarkId id,
                                                 bool apply_loss) {
  Eigen::Matrix2d information = Eigen::Matrix2d::Zero();
  const double* position = landmark_block(id);
  if (position == nullptr) return information;
  std::vector<double> residuals;
  std::vector<double> jacobian;
  std::vector<double*> jacobians;
  std::vector<double*> parameters;
  for (const ceres::ResidualBlockId block : landmark_residuals_[id]) {
    problem_->GetParameterBlocksForResidualBlock(block, &parameters);
    const int n =
        problem_->GetCostFunctionForResidualBlock(block)->num_residuals();
    residuals.assign(n, 0.0);
    jacobian.assign(2 * n, 0.0);
    // Only the landmark's Jacobian is asked for.
    jacobians.assign(parameters.size(), nullptr);
    for (std::size_t i = 0; i < parameters.size(); ++i) {
      if (parameters[i] == position) jacobians[i] = jacobian.data();
    }
    double cost = 0.0;
    if (!problem_->EvaluateResidualBlock(block, apply_loss, &cost,
                                         residuals.data(), jacobians.data())) {
      continue;
    }
    const Eigen::Map<
        const Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor>>
        j(jacobian.data(), n, 2);
    information += j.transpose() * j;
  }
  return information;
}

bool SlamProblem::CheckLandmarksDetermined(double max_condition,
                                           std::string* error) {
  for (const LandmarkId id : added_) {
    // A prior bounds the information from below in every direction; a huge
    // eigenvalue beside it only says that a bearing sees it from close by.
    if (has_prior_.count(id) > 0) continue;
    const Eigen::Vector2d eigenvalues =
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(
            LandmarkInformation(id, /*apply_loss=*/false))
            .eigenvalues();
    if (!eigenvalues.allFinite() || !(eigenvalues[0] > 0.0) ||
        eigenvalues[1] > max_condition * eigenvalues[0]) {
      *error = "landmark " + std::to_string(id) +
               " is not determined by its measurements (information "
               "eigenvalues " +
               FormatNumber(eigenvalues[0]) + " and " +
               FormatNumber(eigenvalues[1]) +
               "): give it a PRIOR_LANDMARK or observe it from more places";
      return false;
    }
  }
  return true;
}

std::vector<VarianceGroup> SlamProblem::RowGroups(
    const std::vector<ceres::ResidualBlockId>& ids) {
  std::vector<VarianceGroup> rows;
  std::vector<double*> blocks;
  for (const ceres::ResidualBlockId id : ids) {
    const int n =
        problem_->GetCostFunctionForResidualBlock(id)->num_residuals();
    const auto source = sources_.find(id);
    if (source == sources_.end()) {  // The trajectory model's own prior.
      problem_->GetParameterBlocksForResidualBlock(id, &blocks);
      for (const TrajectoryModel::PriorScale scale :
           model_->PriorRowScales(blocks, n)) {
        rows.push_back(scale == TrajectoryModel::PriorScale::kPosition
                           ? VarianceGroup::kPriorPosition
                       : scale == TrajectoryModel::PriorScale::kHeading
                           ? VarianceGroup::kPriorHeading
                           : VarianceGroup::kFixed);
      }
      continue;
    }
    for (int row = 0; row < n; ++row) {
      rows.push_back(source->second.RowGroup(row));
    }
  }
  return rows;
}

int SlamProblem::FoldFrozenResiduals() {
  if (timed_blocks_.empty()) {
    for (int b = 0; b < model_->num_blocks(); ++b) {
      if (!model_->IsSharedBlock(b)) {
        timed_blocks_.insert(model_->mutable_block(b));
      }
    }
  }
  // In the problem's (insertion) order: the sums are reproducible.
  std::vector<ceres::ResidualBlockId> ids;
  problem_->GetResidualBlocks(&ids);
  std::vector<double*> blocks;
  BlockEvaluation e;
  std::set<std::pair<bool, LandmarkId>> changed;
  int folded = 0;
  for (const ceres::ResidualBlockId id : ids) {
    const auto source = sources_.find(id);
    // Timed data only: priors on landmarks and calibrations stay exact.
    if (source == sources_.end() || !source->second.has_time) continue;
    problem_->GetParameterBlocksForResidualBlock(id, &blocks);
    bool timed = false, frozen = true, moves = false;
    for (double* block : blocks) {
      const bool constant = problem_->IsParameterBlockConstant(block);
      if (timed_blocks_.count(block) > 0) {
        timed = true;
        frozen = frozen && constant;
      } else {
        moves = moves || !constant;
      }
    }
    if (!timed || !frozen || !moves) continue;
    // A landmark its sightings alone locate can move far after the first
    // of them freeze (bearing-only, it diverged held where it was first
    // seen): its residuals stay exact.
    if (source->second.has_landmark &&
        !has_landmark_prior(source->second.landmark)) {
      continue;
    }
    // Left as it is where Ceres cannot evaluate it (the solve reports it).
    if (!EvaluateVariableBlocks(id, /*apply_loss=*/false, &e)) continue;
    // Under a robust loss, its weight rho'(s) there (reweighted least
    // squares): Ceres's correction where rho'' <= 0 (Cauchy's, Huber's), a
    // positive curvature wherever the gradient is.
    if (const ceres::LossFunction* loss =
            problem_->GetLossFunctionForResidualBlock(id)) {
      double rho[3];
      loss->Evaluate(2.0 * e.cost, rho);
      e.cost = 0.5 * rho[0];
      const double root = std::sqrt(rho[1]);
      for (double& r : e.residuals) r *= root;
      for (std::size_t j = 0; j < e.blocks.size(); ++j) {
        if (e.jacobians[j] == nullptr) continue;
        for (double& v : e.jacobian_rows[j]) v *= root;
      }
    }
    const std::pair<bool, LandmarkId> key(source->second.has_landmark,
                                          source->second.landmark);
    folded_[key].prior.Add(e.blocks, e.sizes, e.jacobians, e.residuals.data(),
                           static_cast<int>(e.residuals.size()), e.cost);
    changed.insert(key);
    ++folded;
    if (source->second.has_landmark) {
      std::vector<ceres::ResidualBlockId>& of_landmark =
          landmark_residuals_[source->second.landmark];
      of_landmark.erase(std::find(of_landmark.begin(), of_landmark.end(), id));
    }
    sources_.erase(source);
    problem_->RemoveResidualBlock(id);
  }
  if (changed.empty()) return 0;
  for (const auto& key : changed) {
    Folded& f = folded_[key];
    if (f.block != nullptr) {
      sources_.erase(f.block);
      problem_->RemoveResidualBlock(f.block);
    }
    f.block = problem_->AddResidualBlock(f.prior.MakeCost().release(), nullptr,
                                         f.prior.blocks());
    Remember(f.block, {"folded past", 0.0, 0.0, 0, false, /*has_time=*/false});
  }
  // Costs were deleted: none can follow new scales, and the layouts and a
  // kept linearisation describe residuals that are gone.
  observation_weights_.clear();
  odometry_weights_.clear();
  weighted_ = false;
  layout_.reset();
  DropLinearization();
  return folded;
}

int SlamProblem::num_folded() const {
  int folded = 0;
  for (const auto& [key, f] : folded_) folded += f.prior.num_folded();
  return folded;
}

std::shared_ptr<ceres::ParameterBlockOrdering> SlamProblem::Ordering() {
  if (added_.empty()) return nullptr;
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  for (const LandmarkId id : added_) {
    ordering->AddElementToGroup(landmark_block(id), 0);
  }
  for (int b = 0; b < model_->num_blocks(); ++b) {
    ordering->AddElementToGroup(model_->mutable_block(b),
                                model_->IsSharedBlock(b) ? 2 : 1);
  }
  // A group of its own, so its place does not depend on its address.
  for (double* calibration :
       {range_calibration_.data(), odometry_calibration_.data()}) {
    if (problem_->HasParameterBlock(calibration)) {
      ordering->AddElementToGroup(calibration, 3);
    }
  }
  return ordering;
}

BandedColumns ModelBandColumns(TrajectoryModel* model) {
  BandedColumns columns;
  for (int b = 0; b < model->num_blocks(); ++b) {
    (model->IsSharedBlock(b) ? columns.last : columns.timed)
        .push_back(model->mutable_block(b));
  }
  return columns;
}

BandedColumns SlamProblem::BandColumns() {
  BandedColumns columns = ModelBandColumns(model_);
  for (double* calibration :
       {range_calibration_.data(), odometry_calibration_.data()}) {
    if (problem_->HasParameterBlock(calibration)) {
      columns.last.push_back(calibration);
    }
  }
  for (const LandmarkId id : added_) {
    columns.placed.push_back(landmark_block(id));
  }
  return columns;
}

bool SlamProblem::BlockState::operator==(const BlockState& other) const {
  return num_residual_blocks == other.num_residual_blocks &&
         blocks == other.blocks && values.size() == other.values.size() &&
         (values.empty() || std::memcmp(values.data(), other.values.data(),
                                        values.size() * sizeof(double)) == 0);
}

SlamProblem::BlockState SlamProblem::CurrentBlockState(bool with_values) const {
  BlockState state;
  state.num_residual_blocks = problem_->NumResidualBlocks();
  std::vector<double*> blocks;
  problem_->GetParameterBlocks(&blocks);
  for (double* block : blocks) {
    state.blocks.emplace_back(block, problem_->IsParameterBlockConstant(block));
    if (!with_values) continue;
    const int size = problem_->ParameterBlockSize(block);
    state.values.insert(state.values.end(), block, block + size);
  }
  return state;
}

std::shared_ptr<BandedProblem> SlamProblem::BandedLayout(
    const BandedColumns& columns) {
  BlockState state = CurrentBlockState(/*with_values=*/false);
  if (!layout_ || !(state == layout_state_) || !(columns == layout_columns_)) {
    layout_ = std::make_shared<BandedProblem>(*problem_, columns);
    layout_state_ = std::move(state);
    layout_columns_ = columns;
  }
  return layout_;
}

void SlamProblem::KeepLinearization(BandedLinearization linearization) {
  kept_ = std::move(linearization);
  kept_state_ = CurrentBlockState();
}

bool SlamProblem::TakeLinearization(BandedLinearization* linearization) {
  BandedLinearization kept = std::move(kept_);
  kept_ = BandedLinearization();
  if (!kept.banded || !kept.hessian) return false;
  const bool same = CurrentBlockState() == kept_state_;
  kept_state_ = BlockState();
  if (!same) return false;
  *linearization = std::move(kept);
  return true;
}

}  // namespace rff
