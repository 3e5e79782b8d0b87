// The continuous-time trajectory as the problem builder sees it: a set of
// parameter blocks, the affine map from them to the pose at any time, and the
// prior over them. The weight-space GP (FeatureTrajectory) and the discrete
// WNOA states are two implementations, so every cost, writer and metric
// serves both.
#ifndef RFF_CERES_TRAJECTORY_MODEL_H_
#define RFF_CERES_TRAJECTORY_MODEL_H_

#include <memory>
#include <string>
#include <vector>

#include "Eigen/Core"
#include "ceres/problem.h"
#include "costs/pose_map.h"
#include "rff_ceres/mean/mean_function.h"

namespace rff {

class TrajectoryModel {
 public:
  virtual ~TrajectoryModel() = default;

  virtual int num_blocks() const = 0;
  virtual int block_size(int block) const = 0;
  virtual double* mutable_block(int block) = 0;
  const double* block(int block) const {
    return const_cast<TrajectoryModel*>(this)->mutable_block(block);
  }

  // pose(t) as an affine function of the blocks; PoseTerm::block indexes the
  // model's blocks.
  virtual PoseMap PoseAt(double t) const = 0;

  // Adds the prior terms over the blocks (whitened weights, GP motion prior)
  // whose newest block lies in [begin, end); blocks are in time order, so the
  // incremental mode adds each term once its blocks come into use.
  virtual void AddPriorCosts(ceres::Problem* problem, int begin, int end) = 0;
  void AddPriorCosts(ceres::Problem* problem) {
    AddPriorCosts(problem, 0, num_blocks());
  }

  // The prior mean mu(t) the blocks deviate from; replaced between the outer
  // rounds of the smoothing-spline prior (paper III-B.2).
  virtual const MeanFunction& mean() const = 0;
  virtual void set_mean(std::shared_ptr<const MeanFunction> mean) = 0;

  // The scale of the prior each row of a prior residual over `blocks` (as
  // AddPriorCosts adds it) belongs to, for re-estimating it from the data
  // (variance_components.h): the position or heading kernel variance / Q_c,
  // or none for terms whose scale is fixed (priors on a start, a rotation).
  enum class PriorScale { kNone, kPosition, kHeading };
  virtual std::vector<PriorScale> PriorRowScales(
      const std::vector<double*>& blocks, int num_rows) const = 0;
  // Whether a scale divides the prior rows it owns (WNOA: Q_c whitens the
  // increments) rather than living in the map from blocks to poses (feature
  // weights: b ~ N(0, I), the kernel's variance in the features). The
  // Laplace evidence counts n log s for the rows a scale divides.
  virtual bool PriorScalesWhitenRows() const = 0;

  // Whether the reduced system (landmarks eliminated) is dense for this
  // model's structure: global feature maps are, Markov states (banded)
  // are not, whatever their number.
  virtual bool HasDenseReducedSystem() const { return false; }

  // Whether every pose depends on the block (not a block local in time):
  // the problem orders such blocks in a group of their own, so that their
  // place in the solve does not depend on their address.
  virtual bool IsSharedBlock(int /*block*/) const { return false; }

  // Sets the blocks to follow `poses` (sorted by time, at least one) by a
  // rule of the model's own, where it has one (states that hold poses);
  // false leaves them to the generic MAP fit (FitModelToPoses).
  virtual bool SetBlocksFromPoses(const std::vector<TimedPose>& /*poses*/) {
    return false;
  }

  // Heading and position at t with the current block values (heading not
  // wrapped: the model's heading is a continuous function of time): the
  // PoseMap's value, which a model may give without forming the map.
  virtual Eigen::Vector3d Pose(double t) const;

  // Takes what `previous`, a model of the same structure whose scales the
  // learning changed, computed that does not depend on the scales (WNOA:
  // the interpolation at each time). Nothing by default.
  virtual void AdoptCaches(const TrajectoryModel& /*previous*/) {}

  // Takes the scales of `rescaled`, a model built as this one but for its
  // prior's scales, where the costs already built over this model can
  // follow them in place: their pose maps then equal `rescaled`'s bit for
  // bit and the blocks keep their values. False, nothing changed, where
  // the structure differs or the model cannot (the default).
  virtual bool AdoptScales(TrajectoryModel* /*rescaled*/) { return false; }
  // The same model with more modes of its basis where it has an ordered one
  // (Hilbert features, FeatureTrajectory): each map gains its next modes
  // until the spectral mass it misses is `tail_fraction` of what it missed,
  // at most `most_multiple` times its modes. Its blocks are this model's in
  // number and order, each holding this model's values first and the new
  // modes at zero. nullptr and `why` otherwise (the default).
  virtual std::unique_ptr<TrajectoryModel> WithMoreModes(
      double /*tail_fraction*/, int /*most_multiple*/, std::string* why) const {
    *why = "the model has no basis to extend";
    return nullptr;
  }
  // Gives `costs`, those AddPriorCosts added to a problem, the prior the
  // model's scales now say (after AdoptScales): each then equals the cost
  // AddPriorCosts would add. Nothing where the prior has no scale.
  virtual void UpdatePriorCosts(
      const std::vector<ceres::CostFunction*>& /*costs*/) const {}
  // log |det S| summed over the prior's residual blocks, S their square-root
  // information at unit scales: the normaliser of the prior's density that
  // LaplaceLogEvidence leaves out (no scale changes it) and that differs
  // between priors. 0 for weights whitened to N(0, I).
  virtual double PriorLogNormaliser() const { return 0.0; }
};

// Every block's values in block order, and back (same model structure).
std::vector<double> ModelBlocks(const TrajectoryModel& model);
void SetModelBlocks(const std::vector<double>& values, TrajectoryModel* model);
// Every block to zero: the model is its prior mean, as a new one is.
void ZeroModelBlocks(TrajectoryModel* model);

// The parameter blocks a cost over `maps` takes, in order of first use; the
// maps' model block ids are rewritten to indices into that list, in place.
std::vector<double*> BindPoseMaps(TrajectoryModel* model,
                                  const std::vector<PoseMap*>& maps);

}  // namespace rff

#endif  // RFF_CERES_TRAJECTORY_MODEL_H_
