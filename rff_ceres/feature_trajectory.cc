#include "rff_ceres/feature_trajectory.h"

#include <algorithm>
#include <cmath>
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

std::unique_ptr<FeatureTrajectory> FeatureTrajectory::Create(
    const FeatureTrajectoryOptions& requested,
    std::shared_ptr<const MeanFunction> mean, double t_begin, double t_end,
    std::string* error) {
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
  // A run with one time still needs a window of positive length.
  const double length = std::max(t_end - t_begin, 1e-3);
  if (requested.segment_length > 0.0 &&
      !(length / requested.segment_length <= kMaxSegments)) {
    *error = OptionError(
        "segment_length", FormatNumber(requested.segment_length),
        "cuts the run's " + FormatNumber(length) + " s into more than " +
            std::to_string(kMaxSegments) + " segments",
        "0 or at least " + FormatNumber(length / kMaxSegments) +
            " for this run");
    return nullptr;
  }
  const FeatureTrajectoryOptions options = AutoCapacity(requested, length);
  const double num_segments_needed =
      SegmentCount(options.segment_length, length);
  const double dp = options.num_position_features;
  const double dh = options.num_heading_features;
  const double weights_per_segment = 2.0 * dp * dp + dh * dh;
  if (num_segments_needed * weights_per_segment > kMaxPriorNonZeros) {
    const std::string why = "the run's " + FormatNumber(length) + " s need " +
                            FormatNumber(num_segments_needed) +
                            " segments of " + FormatNumber(dp) +
                            " features (x, y) and " + FormatNumber(dh) +
                            " (theta): more weights than memory allows";
    // Fewer segments of these features, or as many of fewer features.
    const double shortest_segment =
        length / std::floor(kMaxPriorNonZeros / weights_per_segment);
    if (requested.num_position_features == kAutoCapacity) {
      *error = OptionError(
          "segment_length", FormatNumber(requested.segment_length), why,
          "at least " + FormatNumber(shortest_segment) + " for this run");
    } else {
      const double most_features = std::floor(
          std::sqrt(kMaxPriorNonZeros / (3.0 * num_segments_needed)));
      *error = OptionError(
          "num_features", std::to_string(requested.num_position_features), why,
          "at most " + FormatNumber(most_features) +
              " (as many for theta) for this run, or --segment_length of at "
              "least " +
              FormatNumber(shortest_segment));
    }
    return nullptr;
  }
  std::unique_ptr<FeatureTrajectory> model(new FeatureTrajectory);
  model->options_ = options;
  model->mean_ = std::move(mean);
  model->origin_ = t_begin;
  model->position_kernel_ = CreateKernel(options.position_kernel, error);
  if (!model->position_kernel_) return nullptr;
  model->heading_kernel_ =
      CreateKernel(options.heading_kernel, error, "heading_");
  if (!model->heading_kernel_) return nullptr;

  // Bounded above by the prior's size check.
  const int num_segments = static_cast<int>(num_segments_needed);
  const double segment = length / num_segments;
  model->overlap_ = num_segments > 1 ? options.segment_overlap : 0.0;
  for (int k = 0; k < num_segments; ++k) {
    Segment s;
    s.begin = k * segment;
    s.end = (k + 1) * segment;
    FeatureMapOptions map_options;
    map_options.family = options.family;
    map_options.num_features_flag = "num_features";
    // Each segment's maps cover its extent and half the overlap each side.
    map_options.window_begin = k > 0 ? -0.5 * model->overlap_ : 0.0;
    map_options.window_end =
        segment + (k + 1 < num_segments ? 0.5 * model->overlap_ : 0.0);
    map_options.num_features = options.num_position_features;
    map_options.seed = options.seed + 2 * k;
    s.position_map =
        CreateFeatureMap(*model->position_kernel_, map_options, error);
    if (!s.position_map) return nullptr;
    map_options.num_features = options.num_heading_features;
    map_options.num_features_flag = "num_heading_features";
    map_options.seed = options.seed + 2 * k + 1;  // Independent draws.
    s.heading_map =
        CreateFeatureMap(*model->heading_kernel_, map_options, error);
    if (!s.heading_map) return nullptr;
    for (const int size :
         {s.position_map->num_features(), s.position_map->num_features(),
          s.heading_map->num_features()}) {
      model->offsets_.push_back(model->offsets_.back() + size);
    }
    model->segments_.push_back(std::move(s));
  }
  model->weights_ = Eigen::VectorXd::Zero(model->offsets_.back());
  return model;
}

const std::vector<FeatureTrajectory::Features>& FeatureTrajectory::FeaturesAt(
    double t) const {
  auto it = cache_.find(t);
  if (it != cache_.end()) return it->second;
  const double tau = t - origin_;
  const int last = static_cast<int>(segments_.size()) - 1;
  // The segment whose nominal extent holds tau (clamped at the ends).
  const double segment = segments_[0].end - segments_[0].begin;
  const int k =
      std::clamp(static_cast<int>(std::floor(tau / segment)), 0, last);
  // (segment, blend weight) pairs active at tau.
  std::vector<std::pair<int, double>> active;
  const double half = 0.5 * overlap_;
  if (k > 0 && tau < segments_[k].begin + half) {
    const double u = (tau - (segments_[k].begin - half)) / overlap_;
    active = {{k - 1, std::cos(0.5 * M_PI * u)}, {k, std::sin(0.5 * M_PI * u)}};
  } else if (k < last && tau > segments_[k].end - half) {
    const double u = (tau - (segments_[k].end - half)) / overlap_;
    active = {{k, std::cos(0.5 * M_PI * u)}, {k + 1, std::sin(0.5 * M_PI * u)}};
  } else {
    active = {{k, 1.0}};
  }
  std::vector<Features> features;
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
  return cache_.emplace(t, std::move(features)).first->second;
}

PoseMap FeatureTrajectory::PoseAt(double t) const {
  PoseMap map;
  map.mean = mean_->Evaluate(t);
  for (const Features& f : FeaturesAt(t)) {
    map.terms.push_back({3 * f.segment + kX, 0, f.position});
    map.terms.push_back({3 * f.segment + kY, 1, f.position});
    map.terms.push_back({3 * f.segment + kTheta, 2, f.heading});
  }
  return map;
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
