#include "rff_ceres/feature_trajectory.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <map>
#include <string>
#include <utility>

#include "costs/weight_prior_cost.h"
#include "rff_ceres/features/hilbert_features.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/option_error.h"

namespace rff {

namespace {

// A segment spans this many position lengthscales and blends into the next
// over this many: correlations beyond ~4 lengthscales are below 1e-3 (rbf).
constexpr double kSegmentLengthscales = 10.0;
constexpr double kOverlapLengthscales = 4.0;
// A stretch of data at one time still needs a window of positive length.
constexpr double kShortestStretch = 1e-3;

// D of one feature map of `kernel` over [begin, end] at `tolerance`.
int AutoNumFeatures(const KernelOptions& kernel_options, double missed_sigma,
                    const FeatureTrajectoryOptions& options, double begin,
                    double end) {
  std::string error;
  const std::unique_ptr<Kernel> kernel = CreateKernel(kernel_options, &error);
  if (!kernel) return 1;  // Create() reports the bad kernel.
  FeatureMapOptions map;
  map.family = options.family;
  map.window_begin = begin;
  map.window_end = end;
  const double tolerance = missed_sigma * missed_sigma;
  if (options.family == "hilbert" && kernel->has_spectral_density()) {
    return std::min(HilbertNumFeatures(*kernel, map, tolerance),
                    kMaxAutoFeatures);
  }
  int d = kMaxAutoFeatures;
  if (!DefaultNumFeatures(*kernel, map, tolerance, kMaxAutoFeatures, &d,
                          &error)) {
    d = kMaxAutoFeatures;
  }
  return d;
}

// Segments of (at most) `segment_length` over `duration`, all of one length;
// 1 without segments. A double: a tiny length must not overflow an int.
double SegmentCount(double segment_length, double duration) {
  if (!(segment_length > 0.0)) return 1.0;
  return std::max(1.0, std::ceil(duration / segment_length - 1e-9));
}

// What the prior's size check and its message need of the stretches.
struct StretchLayout {
  double covered = 0.0;  // Seconds, summed over the stretches.
  std::string what;      // "the run's 10 s", with the number of stretches.
  std::string scope;     // " for this run", or empty for any run.
};

// `any_run`: the lengths are the check of options before the data.
StretchLayout Describe(const std::vector<double>& lengths, bool any_run) {
  StretchLayout layout;
  for (const double length : lengths) layout.covered += length;
  if (any_run) {
    layout.what = "any run of " + FormatNumber(layout.covered) + " s or more";
    return layout;
  }
  layout.scope = " for this run";
  layout.what = lengths.size() == 1 ? "the run's " : "the data's ";
  layout.what += FormatNumber(layout.covered) + " s";
  if (lengths.size() > 1) {
    layout.what += " (in " + std::to_string(lengths.size()) + " stretches)";
  }
  return layout;
}

}  // namespace

FeatureTrajectoryOptions AutoCapacity(const FeatureTrajectoryOptions& options,
                                      double duration) {
  FeatureTrajectoryOptions filled = options;
  if (options.num_position_features != kAutoCapacity) return filled;
  const double lengthscale = options.position_kernel.lengthscale;
  if (options.segment_length == 0.0 &&
      duration > 1.5 * kSegmentLengthscales * lengthscale) {
    filled.segment_length = kSegmentLengthscales * lengthscale;
    filled.segment_overlap = kOverlapLengthscales * lengthscale;
  }
  // Every segment has the length of the first (Create splits evenly).
  const double window =
      duration / SegmentCount(filled.segment_length, duration) +
      filled.segment_overlap;
  filled.num_position_features =
      AutoNumFeatures(options.position_kernel, options.capacity_position_sigma,
                      options, 0.0, window);
  filled.num_heading_features =
      AutoNumFeatures(options.heading_kernel, options.capacity_heading_sigma,
                      options, 0.0, window);
  return filled;
}

double LongestBridgedGap(const FeatureTrajectoryOptions& options) {
  const double gap = std::max(
      {options.segment_length, kShortestStretch,
       kSegmentLengthscales * std::max(options.position_kernel.lengthscale,
                                       options.heading_kernel.lengthscale)});
  // Bad lengthscales (Create names them): one stretch, as without gaps.
  return gap < std::numeric_limits<double>::infinity()
             ? gap
             : std::numeric_limits<double>::infinity();
}

std::unique_ptr<FeatureTrajectory> FeatureTrajectory::Create(
    const FeatureTrajectoryOptions& options,
    std::shared_ptr<const MeanFunction> mean, double t_begin, double t_end,
    std::string* error) {
  DataTimes times;
  times.constraints.push_back({t_begin, t_end});
  return Create(options, std::move(mean), times, error);
}

bool FeatureTrajectory::CheckOptions(const FeatureTrajectoryOptions& options,
                                     std::shared_ptr<const MeanFunction> mean,
                                     std::string* error) {
  DataTimes times;
  times.constraints.push_back({0.0, 1.0});
  return Build(options, std::move(mean), times, true, error) != nullptr;
}

std::unique_ptr<FeatureTrajectory> FeatureTrajectory::Create(
    const FeatureTrajectoryOptions& options,
    std::shared_ptr<const MeanFunction> mean, const DataTimes& times,
    std::string* error) {
  return Build(options, std::move(mean), times, false, error);
}

std::unique_ptr<FeatureTrajectory> FeatureTrajectory::Build(
    const FeatureTrajectoryOptions& requested,
    std::shared_ptr<const MeanFunction> mean, const DataTimes& times,
    bool any_run, std::string* error) {
  for (const auto& [d, name] :
       {std::pair(requested.num_position_features, "num_features"),
        std::pair(requested.num_heading_features, "num_heading_features")}) {
    if (d < 0 || d > kMaxFeatures) {
      *error = OptionError(
          name, std::to_string(d), "",
          "0 (from the capacity rule) to " + std::to_string(kMaxFeatures));
      return nullptr;
    }
  }
  if (requested.num_position_features == kAutoCapacity &&
      requested.num_heading_features != kAutoCapacity) {
    *error = OptionError(
        "num_heading_features", std::to_string(requested.num_heading_features),
        "--num_features=0 derives both counts from the capacity rule",
        "0 there, or give --num_features too");
    return nullptr;
  }
  if (!(requested.segment_length >= 0.0) ||
      !std::isfinite(requested.segment_length)) {
    *error =
        OptionError("segment_length", FormatNumber(requested.segment_length),
                    "", "0 (one global map) or more");
    return nullptr;
  }
  if (!(requested.segment_overlap >= 0.0) ||
      (requested.segment_length > 0.0 &&
       !(requested.segment_overlap < requested.segment_length))) {
    *error = OptionError("segment_overlap",
                         FormatNumber(requested.segment_overlap), "",
                         "0 or more, less than --segment_length=" +
                             FormatNumber(requested.segment_length));
    return nullptr;
  }
  if (requested.segment_length == 0.0 && requested.segment_overlap != 0.0) {
    *error = OptionError(
        "segment_overlap", FormatNumber(requested.segment_overlap),
        "blends segments, but --segment_length=0 has none", "0 there");
    return nullptr;
  }
  const std::vector<TimeInterval> stretches =
      DataStretches(times, LongestBridgedGap(requested));
  std::vector<double> lengths;
  for (const TimeInterval& stretch : stretches) {
    lengths.push_back(std::max(stretch.end - stretch.begin, kShortestStretch));
  }
  const StretchLayout layout = Describe(lengths, any_run);
  if (requested.segment_length > 0.0 &&
      !(layout.covered / requested.segment_length <= kMaxSegments)) {
    *error = OptionError(
        "segment_length", FormatNumber(requested.segment_length),
        "cuts " + layout.what + " into more than " +
            std::to_string(kMaxSegments) + " segments",
        "0 or at least " + FormatNumber(layout.covered / kMaxSegments) +
            layout.scope);
    return nullptr;
  }
  // Each stretch settles its capacity as a run of its length would; many
  // stretches of one length (lone observations) settle it once.
  std::map<double, FeatureTrajectoryOptions> settled_by_length;
  std::vector<const FeatureTrajectoryOptions*> settled;
  double num_segments_needed = 0.0, prior_non_zeros = 0.0;
  double widest_segment_weights = 0.0, dp = 0.0, dh = 0.0;
  for (const double length : lengths) {
    auto it = settled_by_length.find(length);
    if (it == settled_by_length.end()) {
      it = settled_by_length.emplace(length, AutoCapacity(requested, length))
               .first;
    }
    const FeatureTrajectoryOptions& options = it->second;
    settled.push_back(&options);
    const double count = SegmentCount(options.segment_length, length);
    const double features = options.num_position_features;
    const double heading_features = options.num_heading_features;
    const double weights =
        2.0 * features * features + heading_features * heading_features;
    num_segments_needed += count;
    prior_non_zeros += count * weights;
    if (weights > widest_segment_weights) {
      widest_segment_weights = weights;
      dp = features;
      dh = heading_features;
    }
  }
  if (prior_non_zeros > kMaxPriorNonZeros) {
    const std::string why =
        layout.what + " need " + FormatNumber(num_segments_needed) +
        " segments of " + FormatNumber(dp) + " features (x, y) and " +
        FormatNumber(dh) + " (theta): more weights than memory allows";
    // Fewer segments of these features, or as many of fewer features.
    const double shortest_segment =
        layout.covered / std::floor(kMaxPriorNonZeros / widest_segment_weights);
    if (requested.num_position_features == kAutoCapacity &&
        requested.segment_length == 0.0) {
      // Automatic segments follow the lengthscale: that is the cause. Their
      // count, and with it the weights, falls as 1 / lengthscale.
      const double lengthscale = requested.position_kernel.lengthscale;
      *error = OptionError(
          "lengthscale", FormatNumber(lengthscale),
          why + " (automatic segments of " +
              FormatNumber(kSegmentLengthscales) + " lengthscales)",
          "at least about " +
              FormatNumber(lengthscale * prior_non_zeros / kMaxPriorNonZeros) +
              ", or --segment_length of at least " +
              FormatNumber(shortest_segment) + layout.scope);
    } else if (requested.num_position_features == kAutoCapacity) {
      *error = OptionError(
          "segment_length", FormatNumber(requested.segment_length), why,
          "at least " + FormatNumber(shortest_segment) + layout.scope);
    } else {
      const double most_features = std::floor(
          std::sqrt(kMaxPriorNonZeros / (3.0 * num_segments_needed)));
      *error = OptionError(
          "num_features", std::to_string(requested.num_position_features), why,
          "at most " + FormatNumber(most_features) + " (as many for theta)" +
              layout.scope + ", or --segment_length of at least " +
              FormatNumber(shortest_segment));
    }
    return nullptr;
  }
  std::unique_ptr<FeatureTrajectory> model(new FeatureTrajectory);
  const auto longest = std::max_element(lengths.begin(), lengths.end());
  model->options_ = *settled[longest - lengths.begin()];
  model->mean_ = std::move(mean);
  model->reach_ =
      kOverlapLengthscales * std::max(requested.position_kernel.lengthscale,
                                      requested.heading_kernel.lengthscale);
  model->position_kernel_ = CreateKernel(requested.position_kernel, error);
  if (!model->position_kernel_) return nullptr;
  model->heading_kernel_ =
      CreateKernel(requested.heading_kernel, error, "heading_");
  if (!model->heading_kernel_) return nullptr;
  for (std::size_t c = 0; c < stretches.size(); ++c) {
    if (!model->AddStretch(*settled[c], stretches[c], lengths[c], error)) {
      return nullptr;
    }
  }
  model->weights_ = Eigen::VectorXd::Zero(model->offsets_.back());
  return model;
}

bool FeatureTrajectory::AddStretch(const FeatureTrajectoryOptions& options,
                                   const TimeInterval& data, double length,
                                   std::string* error) {
  Stretch stretch;
  stretch.begin = data.begin;
  stretch.end = std::max(data.end, data.begin + length);
  stretch.first_segment = num_segments();
  // Bounded above by the prior's size check.
  stretch.num_segments =
      static_cast<int>(SegmentCount(options.segment_length, length));
  const int num_segments = stretch.num_segments;
  const double segment = length / num_segments;
  stretch.overlap = num_segments > 1 ? options.segment_overlap : 0.0;
  for (int k = 0; k < num_segments; ++k) {
    Segment s;
    s.begin = k * segment;
    s.end = (k + 1) * segment;
    // Its maps cover its extent and half the overlap each side.
    s.window_begin = k > 0 ? -0.5 * stretch.overlap : 0.0;
    s.window_end =
        segment + (k + 1 < num_segments ? 0.5 * stretch.overlap : 0.0);
    if (!AddSegment(options, k, options.num_position_features,
                    options.num_heading_features, std::move(s), error)) {
      return false;
    }
  }
  stretches_.push_back(stretch);
  return true;
}

bool FeatureTrajectory::AddSegment(const FeatureTrajectoryOptions& options,
                                   int k, int num_position_features,
                                   int num_heading_features, Segment segment,
                                   std::string* error) {
  FeatureMapOptions map_options;
  map_options.family = options.family;
  map_options.num_features_flag = "num_features";
  map_options.window_begin = segment.window_begin;
  map_options.window_end = segment.window_end;
  map_options.num_features = num_position_features;
  // The draws restart in each stretch: it solves as it would alone.
  map_options.seed = options.seed + 2 * k;
  segment.position_map =
      CreateFeatureMap(*position_kernel_, map_options, error);
  if (!segment.position_map) return false;
  map_options.num_features = num_heading_features;
  map_options.num_features_flag = "num_heading_features";
  map_options.seed = options.seed + 2 * k + 1;  // Independent draws.
  segment.heading_map = CreateFeatureMap(*heading_kernel_, map_options, error);
  if (!segment.heading_map) return false;
  for (const int size : {segment.position_map->num_features(),
                         segment.position_map->num_features(),
                         segment.heading_map->num_features()}) {
    offsets_.push_back(offsets_.back() + size);
  }
  segments_.push_back(std::move(segment));
  return true;
}

std::unique_ptr<TrajectoryModel> FeatureTrajectory::WithMoreModes(
    double tail_fraction, int most_multiple, std::string* why) const {
  if (options_.family != "hilbert") {
    *why = "more modes of the same basis need the hilbert family, not " +
           options_.family;
    return nullptr;
  }
  // D' of a map of `kernel` with D modes; D for a map of another kind.
  auto modes = [&](const FeatureMap& map, const Kernel& kernel) {
    const int d = map.num_features();
    const auto* hilbert = dynamic_cast<const HilbertFeatures*>(&map);
    if (hilbert == nullptr) return d;
    return HilbertModesForTail(kernel, hilbert->half_width(), d, tail_fraction,
                               std::max(d + 1, most_multiple * d));
  };
  std::unique_ptr<FeatureTrajectory> model(new FeatureTrajectory);
  model->options_ = options_;
  model->mean_ = mean_;
  model->reach_ = reach_;
  model->position_kernel_ = CreateKernel(options_.position_kernel, why);
  model->heading_kernel_ =
      CreateKernel(options_.heading_kernel, why, "heading_");
  if (!model->position_kernel_ || !model->heading_kernel_) return nullptr;
  model->stretches_ = stretches_;
  for (const Stretch& stretch : stretches_) {
    for (int k = 0; k < stretch.num_segments; ++k) {
      const Segment& old = segments_[stretch.first_segment + k];
      Segment segment;
      segment.begin = old.begin;
      segment.end = old.end;
      segment.window_begin = old.window_begin;
      segment.window_end = old.window_end;
      if (!model->AddSegment(options_, k,
                             modes(*old.position_map, *position_kernel_),
                             modes(*old.heading_map, *heading_kernel_),
                             std::move(segment), why)) {
        return nullptr;
      }
    }
  }
  if (model->offsets_ == offsets_) {
    *why = "no map of the basis has modes to add (no kernel with a density)";
    return nullptr;
  }
  // This model's weights first in each block, the new modes' at zero.
  model->weights_ = Eigen::VectorXd::Zero(model->offsets_.back());
  for (int b = 0; b < num_blocks(); ++b) {
    model->weights_.segment(model->offsets_[b], block_size(b)) =
        weights_.segment(offsets_[b], block_size(b));
  }
  return model;
}

const std::vector<FeatureTrajectory::Features>& FeatureTrajectory::FeaturesAt(
    double t) const {
  auto it = cache_.find(t);
  if (it != cache_.end()) return it->second;
  return cache_.emplace(t, EvaluateFeatures(t)).first->second;
}

std::vector<FeatureTrajectory::Features> FeatureTrajectory::EvaluateFeatures(
    double t) const {
  std::vector<Features> features;
  // The stretch holding t, or the nearest within reach_ of its ends.
  const auto after = std::upper_bound(
      stretches_.begin(), stretches_.end(), t,
      [](double time, const Stretch& s) { return time < s.begin; });
  const Stretch* nearest = nullptr;
  double distance = reach_;
  if (after != stretches_.begin() &&
      std::max(t - std::prev(after)->end, 0.0) <= distance) {
    nearest = &*std::prev(after);
    distance = std::max(t - nearest->end, 0.0);
  }
  if (after != stretches_.end() && after->begin - t < distance) {
    nearest = &*after;
  }
  if (!nearest) return features;
  const Stretch& stretch = *nearest;
  const double tau = t - stretch.begin;
  const int first = stretch.first_segment;
  const int last = first + stretch.num_segments - 1;
  // The segment whose nominal extent holds tau (clamped at the ends).
  const double segment = segments_[first].end - segments_[first].begin;
  const int k = first + std::clamp(static_cast<int>(std::floor(tau / segment)),
                                   0, stretch.num_segments - 1);
  // (segment, blend weight) pairs active at tau.
  std::vector<std::pair<int, double>> active;
  const double overlap = stretch.overlap;
  const double half = 0.5 * overlap;
  if (k > first && tau < segments_[k].begin + half) {
    const double u = (tau - (segments_[k].begin - half)) / overlap;
    active = {{k - 1, std::cos(0.5 * M_PI * u)}, {k, std::sin(0.5 * M_PI * u)}};
  } else if (k < last && tau > segments_[k].end - half) {
    const double u = (tau - (segments_[k].end - half)) / overlap;
    active = {{k, std::cos(0.5 * M_PI * u)}, {k + 1, std::sin(0.5 * M_PI * u)}};
  } else {
    active = {{k, 1.0}};
  }
  for (const auto& [s, weight] : active) {
    const Segment& seg = segments_[s];
    auto position =
        std::make_shared<Eigen::VectorXd>(seg.position_map->num_features());
    seg.position_map->Evaluate(tau - seg.begin, position->data(), nullptr);
    *position *= weight;
    auto heading =
        std::make_shared<Eigen::VectorXd>(seg.heading_map->num_features());
    seg.heading_map->Evaluate(tau - seg.begin, heading->data(), nullptr);
    *heading *= weight;
    features.push_back({s, position, heading});
  }
  return features;
}

bool FeatureTrajectory::AdoptScales(TrajectoryModel* rescaled) {
  auto* other = dynamic_cast<FeatureTrajectory*>(rescaled);
  if (other == nullptr || other->mean_ != mean_ ||
      other->offsets_ != offsets_ || other->reach_ != reach_ ||
      other->stretches_.size() != stretches_.size() ||
      other->segments_.size() != segments_.size()) {
    return false;
  }
  for (std::size_t i = 0; i < stretches_.size(); ++i) {
    const Stretch &a = stretches_[i], &b = other->stretches_[i];
    if (a.begin != b.begin || a.end != b.end || a.overlap != b.overlap ||
        a.first_segment != b.first_segment ||
        a.num_segments != b.num_segments) {
      return false;
    }
  }
  for (std::size_t i = 0; i < segments_.size(); ++i) {
    if (segments_[i].begin != other->segments_[i].begin ||
        segments_[i].end != other->segments_[i].end) {
      return false;
    }
  }
  // Offsets equal: every segment has the same feature counts.
  options_ = other->options_;
  position_kernel_ = std::move(other->position_kernel_);
  heading_kernel_ = std::move(other->heading_kernel_);
  for (std::size_t i = 0; i < segments_.size(); ++i) {
    segments_[i].position_map = std::move(other->segments_[i].position_map);
    segments_[i].heading_map = std::move(other->segments_[i].heading_map);
  }
  for (auto& [t, features] : cache_) {
    const std::vector<Features> fresh = EvaluateFeatures(t);
    for (std::size_t i = 0; i < features.size(); ++i) {
      *features[i].position = *fresh[i].position;
      *features[i].heading = *fresh[i].heading;
    }
  }
  return true;
}

PoseMap FeatureTrajectory::PoseAt(double t) const {
  PoseMap map;
  map.mean = mean_->Evaluate(t);
  const std::vector<Features>& features = FeaturesAt(t);
  map.terms.reserve(3 * features.size());  // One allocation, not three.
  for (const Features& f : features) {
    map.terms.push_back({3 * f.segment + kX, 0, f.position});
    map.terms.push_back({3 * f.segment + kY, 1, f.position});
    map.terms.push_back({3 * f.segment + kTheta, 2, f.heading});
  }
  return map;
}

Eigen::Vector3d FeatureTrajectory::Pose(double t) const {
  // TrajectoryModel::Pose's sums over PoseAt's terms, in their order.
  Eigen::Vector3d pose = mean_->Evaluate(t);
  auto weights = [&](int b, const Eigen::VectorXd& phi) {
    return Eigen::Map<const Eigen::VectorXd>(block(b), phi.size());
  };
  for (const Features& f : FeaturesAt(t)) {
    pose[0] += f.position->dot(weights(3 * f.segment + kX, *f.position));
    pose[1] += f.position->dot(weights(3 * f.segment + kY, *f.position));
    pose[2] += f.heading->dot(weights(3 * f.segment + kTheta, *f.heading));
  }
  return pose;
}

std::vector<TrajectoryModel::PriorScale> FeatureTrajectory::PriorRowScales(
    const std::vector<double*>& blocks, int num_rows) const {
  const int offset = static_cast<int>(blocks.front() - weights_.data());
  const int block = static_cast<int>(
      std::upper_bound(offsets_.begin(), offsets_.end(), offset) -
      offsets_.begin() - 1);
  return std::vector<PriorScale>(num_rows, block % 3 == kTheta
                                               ? PriorScale::kHeading
                                               : PriorScale::kPosition);
}

void FeatureTrajectory::AddPriorCosts(ceres::Problem* problem, int begin,
                                      int end) {
  for (int b = begin; b < end; ++b) {
    problem->AddResidualBlock(new WeightPriorCost(block_size(b)), nullptr,
                              mutable_block(b));
  }
}

}  // namespace rff
