#include "rff_ceres/scale_learning.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <initializer_list>
#include <iomanip>
#include <limits>
#include <set>
#include <sstream>
#include <vector>

#include "glog/logging.h"
#include "rff_ceres/batch_solver.h"
#include "rff_ceres/initialization.h"
#include "rff_ceres/measurement_types.h"
#include "rff_ceres/priors/trajectory_prior.h"
#include "rff_ceres/quality_report.h"
#include "rff_ceres/variance_components.h"

namespace rff {
namespace {

// Solves whose result only places the next step (the judging of "auto"
// losses, a round of learned scales) stop at this relative cost change: the
// factors and outlier levels they feed are far coarser.
constexpr double kPlacingTolerance = 1e-4;

// The rounds of LearnScales and how far one may move a scale.
constexpr int kMaxScaleRounds = 12;
constexpr double kScaleTolerance = 0.1;
constexpr double kMaxScaleStep = 10.0;  // Per round, either way.
constexpr int kAcceleratingFalls = 3;
// Evidence that moves by less than this fraction of its size has stopped
// (a plateau where the sigmas sit at their bound): a change of rounding.
constexpr double kEvidenceRounding = 1e-9;
// Noise sigmas stay within this factor of the stated ones: noise-free data
// would drive them to 0 and the system to no digits.
constexpr double kMaxNoiseScale = 1e3;

// Whether a noise factor sits at its lower bound: the product of the
// rounds' steps lands there up to a rounding unit.
bool AtNoiseFloor(double factor) {
  return factor <= (1.0 + 1e-12) / kMaxNoiseScale;
}

// Whether either loss is still to be judged.
bool HasAutoLoss(const ProblemOptions& options) {
  return options.loss.name == "auto" || options.odometry_loss.name == "auto";
}

// `ceres_options` stopped at kPlacingTolerance at the latest.
ceres::Solver::Options PlacingOptions(ceres::Solver::Options ceres_options) {
  ceres_options.function_tolerance =
      std::max(ceres_options.function_tolerance, kPlacingTolerance);
  return ceres_options;
}

}  // namespace

std::array<double, kNumVarianceGroups> LogRowScales(
    const TrajectoryModel& model, double position_scale, double heading_scale,
    const NoiseScales& noise) {
  std::array<double, kNumVarianceGroups> log_scales{};
  if (model.PriorScalesWhitenRows()) {
    log_scales[static_cast<int>(VarianceGroup::kPriorPosition)] =
        std::log(position_scale);
    log_scales[static_cast<int>(VarianceGroup::kPriorHeading)] =
        std::log(heading_scale);
  }
  for (const VarianceGroup group :
       {VarianceGroup::kRange, VarianceGroup::kBearing,
        VarianceGroup::kOdometry}) {
    log_scales[static_cast<int>(group)] =
        2.0 * std::log(NoiseScale(noise, group));
  }
  return log_scales;
}

ceres::Solver::Options JudgingOptions(const ProblemOptions& options,
                                      ceres::Solver::Options ceres_options) {
  return HasAutoLoss(options) ? PlacingOptions(ceres_options) : ceres_options;
}

bool SettleAutoLosses(SlamProblem* problem, ProblemOptions* options) {
  const std::map<std::string, std::vector<double>> residuals =
      problem->WhitenedResidualsByKind();
  auto clean = [&](const std::vector<std::string>& kinds) {
    for (const std::string& kind : kinds) {
      const auto it = residuals.find(kind);
      if (it == residuals.end()) continue;
      const double level = OutlierLevel(static_cast<int>(it->second.size()));
      for (const double r : it->second) {
        if (!(std::abs(r) <= level)) return false;
      }
    }
    return true;
  };
  const bool judged = HasAutoLoss(*options);
  auto settle = [&](bool is_clean, LossOptions* loss) {
    if (loss->name == "auto") loss->name = is_clean ? "none" : "cauchy";
  };
  std::vector<std::string> observation_kinds;
  for (const MeasurementType& type : MeasurementTypes()) {
    observation_kinds.push_back(type.kind);
  }
  settle(clean(observation_kinds), &options->loss);
  settle(clean({"odometry"}), &options->odometry_loss);
  return judged;
}

double ScaleInformation(const Dataset& dataset, const ProblemOptions& options) {
  Eigen::Vector2d start = Eigen::Vector2d::Zero();
  if (!dataset.pose_priors.empty()) {
    const TimedPose& first = EarliestPosePrior(dataset).pose;
    start = Eigen::Vector2d(first.x, first.y);
  } else {
    double weights = 0.0;
    for (const LandmarkPrior& l : dataset.landmark_priors) {
      const double w = 1.0 / (l.sigma * l.sigma);
      start += w * Eigen::Vector2d(l.x, l.y);
      weights += w;
    }
    if (weights > 0.0) start /= weights;
  }
  double ranges = 0.0;
  for (const Observation& o : dataset.observations) {
    if (o.HasRange()) {
      ranges += o.range * o.range / (o.sigma_range * o.sigma_range);
    }
  }
  ranges /= options.noise.range * options.noise.range;
  double odometry = 0.0;
  if (options.use_odometry) {
    for (const Odometry& o : dataset.odometry) {
      odometry += o.dx * o.dx / (o.sigma_x * o.sigma_x) +
                  o.dy * o.dy / (o.sigma_y * o.sigma_y);
    }
  }
  odometry /= options.noise.odometry * options.noise.odometry;
  // A sensor whose scale is estimated passes a scaling of the scene to that
  // scale, held only by its prior: the two informations in series.
  const auto through_scale = [](double information, double scale_sigma) {
    return information / (1.0 + information * scale_sigma * scale_sigma);
  };
  if (options.range_calibration.estimate) {
    ranges = through_scale(ranges, options.range_calibration.scale_sigma);
  }
  if (options.odometry_calibration.estimate) {
    odometry =
        through_scale(odometry, options.odometry_calibration.scale_sigma);
  }
  double information = ranges + odometry;
  for (const LandmarkPrior& l : dataset.landmark_priors) {
    information +=
        (Eigen::Vector2d(l.x, l.y) - start).squaredNorm() / (l.sigma * l.sigma);
  }
  for (const PosePrior& p : dataset.pose_priors) {
    information += (Eigen::Vector2d(p.pose.x, p.pose.y) - start).squaredNorm() /
                   (p.sigma_xy * p.sigma_xy);
  }
  return information;
}

bool LearnScales(const Dataset& dataset,
                 std::shared_ptr<const MeanFunction> mean,
                 const ceres::Solver::Options& ceres_options,
                 double initial_extent, bool noise, bool loose,
                 SlamOptions* settled, std::unique_ptr<TrajectoryModel>* model,
                 std::map<LandmarkId, Eigen::Vector2d>* landmarks,
                 std::unique_ptr<SlamProblem>* problem, SlamResult* result,
                 std::string* error) {
  const TrajectoryPrior& prior = PriorOf(*settled);
  // Whether the data hold the trajectory's size against the prior's pull
  // (below), and the scales as given, which it keeps where they do not.
  bool prior_scales_learned = true;
  double* position_scale = prior.PositionScale(settled);
  double* heading_scale = prior.HeadingScale(settled);
  const double given_position = *position_scale;
  const double given_heading = *heading_scale;
  NoiseScales& sigmas = settled->problem.noise;
  // Per noise group: its last fall (-log factor) and the rounds in a row
  // it fell by at least the round before's.
  struct Falls {
    double last = 0.0;
    int accelerating = 0;
  };
  std::map<VarianceGroup, Falls> falls;
  std::set<VarianceGroup> kept;  // Noise sigmas back at the stated ones.
  std::set<VarianceGroup> learned;  // Noise factors the data estimated.
  // Correction variances the data leave at their boundary (at zero).
  std::set<VarianceGroup> at_boundary;
  const ceres::Solver::Options placing_options = PlacingOptions(ceres_options);
  VarianceComponentCache cache;  // The rounds' problems share one structure.
  // The largest trust radius the solves reached: after rounds, the final
  // solve goes on from their point on their problem but for a rescale, so
  // it starts as trusting as they became (from the initial radius
  // Levenberg-Marquardt needs a dozen steps, tripling, to stop damping the
  // weak directions). Without rounds it finishes the first solve as a run
  // without learning would.
  double reached_radius = ceres_options.initial_trust_region_radius;
  bool rounds_solved = false;
  auto note_radius = [&] {
    for (const ceres::IterationSummary& it : result->summary.iterations) {
      reached_radius = std::max(reached_radius, it.trust_region_radius);
    }
  };
  note_radius();
  // The evidence is the Gaussian rows' (LaplaceLogEvidence). Under a robust
  // loss the rounds rescale the loss-weighted squares, whose fixed point is
  // no stationary point of it: it guards nothing there.
  const bool odometry_rows =
      settled->problem.use_odometry && !dataset.odometry.empty();
  const bool gaussian =
      settled->problem.loss.name == "none" &&
      (settled->problem.odometry_loss.name == "none" || !odometry_rows);
  // What the last round solved with (its scales, the groups then at their
  // boundary, its factors) and its evidence; whether the rounds climbed.
  struct Solved {
    double position = 0.0, heading = 0.0;
    NoiseScales noise;
    std::set<VarianceGroup> at_boundary;
    Eigen::Vector2d prior_factors = Eigen::Vector2d::Ones();
    double log_evidence = 0.0;
  };
  Solved last;
  // A Q_c started from the odometry is near its fixed point: a fall is a
  // sign from the first round on. From the given value the first rounds may
  // fall on their way (docs/uncertainty.md).
  bool climbed = !prior.has_features() && result->qc_from_odometry.windows > 0;
  // Scaling the positions about the start by 1 + s scales the position
  // prior's whitened rows; at Q_c's fixed point their squares sum to the
  // group's redundancy R, the prior's pull on s^2. With the data's I the
  // MAP's size s then solves I (1 - s) = R / s (the accelerations and Q_c
  // follow s^2), which has a root near 1 only where 4 R < I: beyond, a
  // learned Q_c feeds on itself (a smaller trajectory, smaller
  // accelerations, a smaller Q_c; bearing-only maps at 0.64-0.89 of their
  // size, 0.5 with an estimated odometry scale, docs/heldout.md). Q_c then
  // goes back to the given value, and only the noise factors are learned.
  auto note_kept = [&](double pull, double information) {
    prior_scales_learned = false;
    std::ostringstream why;
    why << std::setprecision(3)
        << "the data hold the trajectory's size too loosely for a learned "
           "one (the prior's pull "
        << pull << " against the data's scale information " << information
        << ", under 4 times the pull)";
    result->prior_scales_kept = why.str();
  };
  // Back to the given scales: a jump, not a step of the climb. Returns
  // whether they had moved, and so need a model rescaled and solved again.
  auto back_to_given = [&] {
    const bool moved =
        *position_scale != given_position || *heading_scale != given_heading;
    *position_scale = given_position;
    *heading_scale = given_heading;
    climbed = false;
    return moved;
  };
  // Each round the data at face value (the stated sigmas, every sensor's
  // scale as known) must hold the size against the round's pull: they can
  // only overstate it. A collapse lowers the pull as it goes (the paper's
  // bearing-only sets: R 218 -> 147), so the settled rounds alone miss it.
  ProblemOptions face_value = settled->problem;
  face_value.noise = NoiseScales();
  face_value.range_calibration.estimate = false;
  face_value.odometry_calibration.estimate = false;
  const double face_value_information = ScaleInformation(dataset, face_value);
  // Whether any round had enough of the prior's rows to estimate its scale.
  bool prior_estimated = false;
  int rounds_cap = kMaxScaleRounds;
  for (int round = 0; round < rounds_cap; ++round) {
    VarianceComponents components;
    std::string why;
    if (!EstimateVarianceComponents(problem->get(), VarianceComponentOptions(),
                                    &components, &why, &cache)) {
      // Data that leave part of the run beyond double precision (a pose
      // after a gap of days): the scales stay as they are, and say so.
      result->scales_not_learned = why;
      break;
    }
    const double pull =
        components[static_cast<int>(VarianceGroup::kPriorPosition)].redundancy;
    const bool prior_scales_reset =
        prior_scales_learned && 4.0 * pull > face_value_information;
    if (prior_scales_reset) note_kept(pull, face_value_information);
    const Eigen::Vector2d prior_factors(
        components[static_cast<int>(VarianceGroup::kPriorPosition)].factor,
        components[static_cast<int>(VarianceGroup::kPriorHeading)].factor);
    const Solved solved{
        *position_scale,
        *heading_scale,
        sigmas,
        at_boundary,
        prior_factors,
        LaplaceLogEvidence(components, LogRowScales(**model, *position_scale,
                                                    *heading_scale, sigmas))};
    if (gaussian) result->scale_log_evidence.push_back(solved.log_evidence);
    // Near their fixed point the rounds climb the evidence. Once they have,
    // a fall means a round overshot, or the probes' noise in a weakly
    // determined redundancy walks a sigma downhill: back to what the round
    // before solved with, and the final solve.
    const double rounding =
        kEvidenceRounding * std::max(1.0, std::abs(last.log_evidence));
    bool evidence_fell = gaussian && climbed && round > 0 &&
                         !prior_scales_reset &&
                         solved.log_evidence < last.log_evidence - rounding;
    climbed = climbed || (round > 0 && solved.log_evidence > last.log_evidence);
    double largest_step = 0.0;
    if (prior_scales_reset && back_to_given()) {
      largest_step = std::numeric_limits<double>::infinity();
    }
    const std::size_t boundary_before = at_boundary.size();
    const double position_solved = *position_scale;
    const double heading_solved = *heading_scale;
    // `power` 1 for a variance, 0.5 for a sigma.
    auto rescale = [&](VarianceGroup group, double power, double* scale) {
      const VarianceComponent& c = components[static_cast<int>(group)];
      if (power == 1.0 && c.estimated) prior_estimated = true;
      if (!c.estimated || kept.count(group) > 0 || at_boundary.count(group) ||
          (power == 1.0 && !prior_scales_learned)) {
        return;
      }
      if (power == 1.0 && prior.has_features() &&
          c.factor < 1.0 / (kMaxScaleStep * kMaxScaleStep)) {
        // A correction to the mean whose weights use under 1% of their
        // variance: its likelihood peaks at zero variance, where the
        // rounds would walk a tenfold step at a time until the data fix
        // under min_redundancy of them. One step, and it is learned.
        *scale /= kMaxScaleStep;
        at_boundary.insert(group);
        result->scales_at_boundary.push_back(VarianceGroupName(group));
        return;
      }
      const double fall = -std::log(c.factor);
      Falls& f = falls[group];
      // A sigma at its lower bound falls no further: its factors there are
      // the rounding of residuals near zero, not a trend.
      const bool at_bound = power < 1.0 && AtNoiseFloor(*scale);
      f.accelerating =
          !at_bound && fall > 0.0 && fall >= f.last ? f.accelerating + 1 : 0;
      f.last = fall;
      if (power < 1.0 && f.accelerating > kAcceleratingFalls) {
        // A noise sigma falling faster round after round runs to the
        // likelihood's degenerate edge, its rows fit exactly as it goes to
        // 0 (a misfit prior lets them): back to the stated one. A real
        // scale's falls slow down towards its fixed point.
        *scale = 1.0;
        kept.insert(group);
        result->noise_kept.push_back(VarianceGroupName(group));
        largest_step = std::numeric_limits<double>::infinity();
        return;
      }
      largest_step = std::max(largest_step, std::abs(std::log(c.factor)));
      *scale *= std::pow(
          std::clamp(c.factor, 1.0 / kMaxScaleStep, kMaxScaleStep), power);
      if (power < 1.0) {
        *scale = std::clamp(*scale, 1.0 / kMaxNoiseScale, kMaxNoiseScale);
        learned.insert(group);
      }
    };
    if (evidence_fell) {
      *position_scale = last.position;
      *heading_scale = last.heading;
      sigmas = last.noise;
      at_boundary = last.at_boundary;
      result->scales_at_boundary.clear();
      for (const VarianceGroup group : at_boundary) {
        result->scales_at_boundary.push_back(VarianceGroupName(group));
      }
      result->learning_evidence_fell = true;
      result->noise_evidence_fell = noise;
    } else {
      const std::size_t kept_before = kept.size();
      rescale(VarianceGroup::kPriorPosition, 1.0, position_scale);
      rescale(VarianceGroup::kPriorHeading, 1.0, heading_scale);
      if (noise) {
        rescale(VarianceGroup::kRange, 0.5, &sigmas.range);
        rescale(VarianceGroup::kBearing, 0.5, &sigmas.bearing);
        rescale(VarianceGroup::kOdometry, 0.5, &sigmas.odometry);
      }
      // A sigma sent back to the stated one is a jump, not a step of the
      // climb: the next one starts from there.
      if (kept.size() > kept_before) climbed = false;
    }
    last = solved;
    VLOG(1)
        << "scale round " << round << ": prior position factor "
        << components[static_cast<int>(VarianceGroup::kPriorPosition)].factor
        << ", heading factor "
        << components[static_cast<int>(VarianceGroup::kPriorHeading)].factor
        << " (redundancies "
        << components[static_cast<int>(VarianceGroup::kPriorPosition)]
               .redundancy
        << ", "
        << components[static_cast<int>(VarianceGroup::kPriorHeading)].redundancy
        << "); sigma factors range " << sigmas.range << ", bearing "
        << sigmas.bearing << ", odometry " << sigmas.odometry;
    result->learning_rounds = round + 1;
    result->prior_scale_factors =
        evidence_fell ? last.prior_factors : prior_factors;
    // Every factor but those stepping to the boundary within tolerance.
    bool others_settled =
        !evidence_fell && largest_step < std::log1p(kScaleTolerance);
    const bool boundary_step = at_boundary.size() > boundary_before;
    // Where the rounds end, the same with the information the data carry
    // at the noise levels learned (MRCLAM's odometry sigmas end 0.02-0.5 of
    // the stated ones), a sensor whose scale is estimated counted through
    // its scale's prior (ScaleInformation), against the learned scales'
    // pull. Past it the rounds go on from the given scales.
    const bool ending =
        others_settled || evidence_fell || round + 1 == rounds_cap;
    if (ending && prior_scales_learned) {
      const double information = ScaleInformation(dataset, settled->problem);
      if (4.0 * pull > information) note_kept(pull, information);
      if (!prior_scales_learned && back_to_given()) {
        // Rounds of its own from there.
        others_settled = false;
        evidence_fell = false;
        result->learning_evidence_fell = false;
        result->noise_evidence_fell = false;
        rounds_cap = round + 1 + kMaxScaleRounds;
      }
    }
    if (others_settled && !boundary_step) {
      // Within tolerance: the prior keeps the scales it was solved with, so
      // that those reported are those the final solve uses (the noise
      // scales it takes in place).
      *position_scale = position_solved;
      *heading_scale = heading_solved;
      result->learning_converged = true;
      break;
    }
    // A diffusion scales the prior only: the states stay as they are.
    // Features follow the variance (capacity): refit them to the estimate.
    const std::vector<double> blocks = ModelBlocks(**model);
    const std::vector<TimedPose> estimate = result->trajectory;
    std::unique_ptr<TrajectoryModel> rescaled =
        CreateTrajectoryModel(dataset, *settled, mean, error);
    if (!rescaled) return false;
    rescaled->AdoptCaches(**model);
    // The problem as built serves where its costs can follow the new
    // scales in place: the same residuals but for their weights.
    const bool in_place = (*problem)->CanFollowScales(settled->problem) &&
                          (*model)->AdoptScales(rescaled.get());
    if (in_place) {
      (*problem)->FollowScales(settled->problem);
    } else {
      *model = std::move(rescaled);
    }
    if (!prior.has_features()) {
      SetModelBlocks(blocks, model->get());
    } else {
      // From zero, as a new model's weights: a kept model's refit then ends
      // where a new one's does.
      ZeroModelBlocks(model->get());
      if (!FitModelToPoses(estimate, model->get(), error)) return false;
    }
    rounds_solved = true;
    result->learned = true;
    loose = true;
    if (others_settled || evidence_fell) {
      // Only a boundary step, or the way back, left: the final solve takes
      // it, on a problem built anew where the features followed the
      // variance (the old one holds costs of the model replaced).
      if (!in_place) problem->reset();
      result->learning_converged = others_settled;
      break;
    }
    if (!SolveBatch(dataset, *settled, placing_options, model->get(), landmarks,
                    initial_extent, problem, result, error, in_place)) {
      return false;
    }
    note_radius();
  }
  if (!prior_estimated && result->prior_scales_kept.empty() &&
      result->scales_not_learned.empty()) {
    std::ostringstream why;
    why << "the data leave its rows under "
        << VarianceComponentOptions().min_redundancy
        << " of redundancy (rows less the parameters they determine)";
    result->prior_scales_kept = why.str();
  }
  const bool capped = result->learning_rounds == rounds_cap &&
                      !result->learning_converged &&
                      !result->learning_evidence_fell;
  for (const VarianceGroup group : learned) {
    if (kept.count(group) > 0) continue;
    result->noise_learned.push_back(VarianceGroupName(group));
    // Still falling at the cap, above its bound: the sigma, and the
    // covariances that follow it, sit where the cap stopped them.
    if (capped && falls[group].last > std::log1p(kScaleTolerance) &&
        !AtNoiseFloor(NoiseScale(sigmas, group))) {
      result->noise_unsettled.push_back(VarianceGroupName(group));
    }
  }
  // The rounds' solves only placed the next factors.
  ceres::Solver::Options final_options = ceres_options;
  if (rounds_solved) {
    final_options.initial_trust_region_radius =
        std::min(reached_radius, ceres_options.max_trust_region_radius);
  }
  if (!loose) return true;
  // The model is the last round's: a problem built over it serves with the
  // last noise scales given in place.
  const bool reuse =
      *problem != nullptr && (*problem)->CanFollowScales(settled->problem);
  if (reuse && !(*problem)->BuiltWith(settled->problem)) {
    (*problem)->FollowScales(settled->problem);
  }
  return SolveBatch(dataset, *settled, final_options, model->get(), landmarks,
                    initial_extent, problem, result, error, reuse);
}

}  // namespace rff
