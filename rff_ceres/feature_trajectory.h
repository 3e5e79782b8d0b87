// The weight-space GP trajectory of the paper (eq. 4):
//
//   x_k(t) = mu_k(t) + phi_k(t - t_origin)^T b_k,   b_k ~ N(0, I),
//
// for k in {x, y, theta}. x and y share one kernel and feature map (with
// their own weights); the heading has its own. Times are shifted to the
// start of their stretch of data (below) before the features see them:
// Unix-epoch seconds (~1.2e9) would leave cos(w t) with no significant
// digits.
//
// Windowed weights: with a segment length S > 0 the run is cut into segments,
// each with its own feature maps and weight blocks, blended across an
// overlap O around each boundary with weights cos(pi u / 2), sin(pi u / 2)
// (u from 0 to 1 across the overlap). The squares of the blend weights sum to
// one, so the prior variance k(0) is kept everywhere, and the reduced system
// is block-banded: its cost grows linearly with the length of the run.
//
// Segments only where data is: the data's times are cut into stretches at
// every gap longer than LongestBridgedGap, and each stretch is laid out as if
// it were the whole run (its own origin, segments and capacity).
#ifndef RFF_CERES_FEATURE_TRAJECTORY_H_
#define RFF_CERES_FEATURE_TRAJECTORY_H_

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "rff_ceres/data_stretches.h"
#include "rff_ceres/features/feature_map.h"
#include "rff_ceres/kernels/kernel.h"
#include "rff_ceres/mean/mean_function.h"
#include "rff_ceres/trajectory_model.h"

namespace rff {

inline constexpr int kAutoCapacity = 0;

// The defaults are rff_slam's (test/slam_flags_test.cc): the starting point
// of hyperparameter learning and, without it, the prior.
struct FeatureTrajectoryOptions {
  KernelOptions position_kernel = {"rbf", 4.0, 10.0};  // x and y: m^2, s
  KernelOptions heading_kernel = {"rbf", 0.1, 10.0};   // theta: rad^2, s
  std::string family = "hilbert";
  // D of x and y and of theta per segment; kAutoCapacity derives D, the
  // segment length and the overlap from the lengthscales (AutoCapacity).
  int num_position_features = kAutoCapacity;
  int num_heading_features = kAutoCapacity;
  std::uint64_t seed = 1;
  double segment_length = 0.0;   // Seconds; 0: one global segment.
  double segment_overlap = 0.0;  // Seconds, < segment_length.
  // Capacity rule: the standard deviation of the motion the basis misses
  // (the square root of the kernel's spectral mass beyond its bandwidth;
  // other families: of the max kernel error), metres and radians.
  double capacity_position_sigma = 0.05;
  double capacity_heading_sigma = 0.005;
};

inline constexpr int kMaxAutoFeatures = 512;
// Bounds of a requested basis: the whitening prior of a segment's D weights
// is a dense D x D Jacobian block, the blocks of every segment are held at
// once, and a dense system of 3 D weights costs O(D^3) per iteration with
// Debian's reference BLAS (an 11-pose run: 4 s at D = 512, 67 s at 1024).
inline constexpr int kMaxFeatures = 512;
inline constexpr int kMaxSegments = 100000;
inline constexpr double kMaxPriorNonZeros = 2e8;  // 1.6 GB of Jacobian.

// Capacity from the data's time scale rather than a constant: with
// num_position_features == kAutoCapacity, segments of kSegmentLengthscales
// position lengthscales (one global map when the run is shorter than 1.5 of
// them), blended over kOverlapLengthscales, and per segment the smallest D
// whose missed spectral mass is below the tolerance (HilbertNumFeatures).
// Returns the options with those values filled in.
FeatureTrajectoryOptions AutoCapacity(const FeatureTrajectoryOptions& options,
                                      double duration);

// The longest time without data that segments still span: a segment, and
// kSegmentLengthscales lengthscales of either kernel (beyond which the prior
// correlates nothing: exp(-50) for rbf).
double LongestBridgedGap(const FeatureTrajectoryOptions& options);

class FeatureTrajectory : public TrajectoryModel {
 public:
  // Blocks of segment s are 3 s + {kX, kY, kTheta}.
  enum Block { kX = 0, kY = 1, kTheta = 2 };

  // The model around `mean` with segments over the stretches of `times`
  // (DataStretches). A time more than kOverlapLengthscales lengthscales from
  // every stretch has no segment: its pose is the prior mean, as the GP
  // posterior's is that far from the data.
  // Returns nullptr and sets `error` on bad options.
  static std::unique_ptr<FeatureTrajectory> Create(
      const FeatureTrajectoryOptions& options,
      std::shared_ptr<const MeanFunction> mean, const DataTimes& times,
      std::string* error);
  // The model on the one stretch [t_begin, t_end].
  static std::unique_ptr<FeatureTrajectory> Create(
      const FeatureTrajectoryOptions& options,
      std::shared_ptr<const MeanFunction> mean, double t_begin, double t_end,
      std::string* error);
  // Checks `options` before any data are read, as Create over a run of
  // 1 s about `mean`: its size limits then speak of any run (each run is
  // checked again with its own times).
  static bool CheckOptions(const FeatureTrajectoryOptions& options,
                           std::shared_ptr<const MeanFunction> mean,
                           std::string* error);

  int num_blocks() const override {
    return static_cast<int>(offsets_.size()) - 1;
  }
  int block_size(int block) const override {
    return offsets_[block + 1] - offsets_[block];
  }
  double* mutable_block(int block) override {
    return weights_.data() + offsets_[block];
  }
  int num_segments() const { return static_cast<int>(segments_.size()); }
  int num_stretches() const { return static_cast<int>(stretches_.size()); }
  bool HasDenseReducedSystem() const override { return true; }
  PoseMap PoseAt(double t) const override;
  Eigen::Vector3d Pose(double t) const override;
  using TrajectoryModel::AddPriorCosts;
  void AddPriorCosts(ceres::Problem* problem, int begin, int end) override;

  // Weights of x and y scale with the position kernel's variance, those of
  // theta with the heading kernel's.
  std::vector<PriorScale> PriorRowScales(const std::vector<double*>& blocks,
                                         int num_rows) const override;
  bool PriorScalesWhitenRows() const override { return false; }

  // The options with the capacity settled (see AutoCapacity), of the longest
  // stretch where each settles its own.
  const FeatureTrajectoryOptions& options() const { return options_; }
  const MeanFunction& mean() const override { return *mean_; }
  void set_mean(std::shared_ptr<const MeanFunction> mean) override {
    mean_ = std::move(mean);
  }
  // With the same segments and feature counts, the kernels of `rescaled`
  // replace this model's and every cached feature vector, which the
  // problem's pose maps share, is evaluated again in place.
  bool AdoptScales(TrajectoryModel* rescaled) override;

  // Each Hilbert map gains its next eigenfunctions (HilbertModesForTail);
  // a map of another kind (a kernel without a density) keeps its features.
  // nullptr and `why` for other families.
  std::unique_ptr<TrajectoryModel> WithMoreModes(
      double tail_fraction, int most_multiple, std::string* why) const override;

 private:
  // Create; `any_run`: `times` stand for any run (CheckOptions).
  static std::unique_ptr<FeatureTrajectory> Build(
      const FeatureTrajectoryOptions& options,
      std::shared_ptr<const MeanFunction> mean, const DataTimes& times,
      bool any_run, std::string* error);
  FeatureTrajectory() = default;

  // Data times close together, with segments numbered [first_segment,
  // first_segment + num_segments) blended over `overlap`.
  struct Stretch {
    // Absolute times of the first and last datum. Features see times
    // relative to `begin`, so a stretch gives the same features wherever it
    // is in the run (and precision however late the clock).
    double begin = 0.0;
    double end = 0.0;
    double overlap = 0.0;
    int first_segment = 0;
    int num_segments = 0;
  };
  struct Segment {
    double begin = 0.0;  // Nominal extent, relative to its stretch's begin.
    double end = 0.0;
    // The maps' window, relative to `begin`: the extent and half the overlap
    // each side that has a neighbour.
    double window_begin = 0.0;
    double window_end = 0.0;
    // Of times relative to `begin`: the feature maps keep their precision
    // however long the run.
    std::unique_ptr<FeatureMap> position_map, heading_map;
  };
  // Blend-weighted features of the (one or two) segments active at a time.
  // Shared with the pose maps as const; AdoptScales rewrites them.
  struct Features {
    int segment = 0;
    std::shared_ptr<Eigen::VectorXd> position;
    std::shared_ptr<Eigen::VectorXd> heading;
  };
  const std::vector<Features>& FeaturesAt(double t) const;
  std::vector<Features> EvaluateFeatures(double t) const;
  // Appends `segment`, the k-th of its stretch, with maps of the given sizes
  // over its window, and its three weight blocks.
  bool AddSegment(const FeatureTrajectoryOptions& options, int k,
                  int num_position_features, int num_heading_features,
                  Segment segment, std::string* error);
  // Appends the segments of one stretch of `data`, `length` seconds long.
  bool AddStretch(const FeatureTrajectoryOptions& options,
                  const TimeInterval& data, double length, std::string* error);

  FeatureTrajectoryOptions options_;
  std::shared_ptr<const MeanFunction> mean_;
  std::unique_ptr<Kernel> position_kernel_, heading_kernel_;
  std::vector<Stretch> stretches_;  // In time order.
  // How far past its stretch a segment is evaluated: the margin of the
  // Hilbert domain. Farther from data the pose is the prior mean alone.
  double reach_ = 0.0;
  std::vector<Segment> segments_;
  // All blocks in one buffer, block b at offsets_[b]: Ceres orders the blocks
  // of an elimination group by address, so contiguous storage in block order
  // makes the solve's arithmetic (and its output) reproducible.
  Eigen::VectorXd weights_;
  std::vector<int> offsets_ = {0};
  // Observations at the same time share their feature vectors.
  mutable std::map<double, std::vector<Features>> cache_;
};

}  // namespace rff

#endif  // RFF_CERES_FEATURE_TRAJECTORY_H_
