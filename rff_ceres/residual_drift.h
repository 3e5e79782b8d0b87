// Whether a sensor's errors drift together over time. The Laplace
// covariance assumes white errors; errors that persist over many sightings
// (a camera's range bias that changes with the viewing geometry) inform the
// estimate far less than their number of rows says, and the covariance
// comes out optimistic. Over the whitened residuals r of one landmark's
// sightings in time order, cut into batches of B consecutive ones,
//
//   ratio = sum_batches (sum_{i in batch} r_i)^2 / sum_i r_i^2,
//
// pooled over the landmarks, is about 1 for white errors and
// 1 + 2 sum_{k=1}^{B-1} (1 - k/B) rho_k for errors of autocorrelation rho_k:
// the batch-means estimate of their integrated autocorrelation time (Flegal and
// Jones 2010). Residuals beyond 5 robust sigmas (1.4826 times the median
// |r|) count as at that level: a robust loss's outliers would decide it.
#ifndef RFF_CERES_RESIDUAL_DRIFT_H_
#define RFF_CERES_RESIDUAL_DRIFT_H_

#include <map>
#include <string>
#include <vector>

#include "rff_ceres/types.h"

namespace rff {

// Sightings per batch: errors that persist over several sightings show, and
// a run leaves many batches.
inline constexpr int kDriftBatch = 16;
// Fewer batches than this tell too little.
inline constexpr int kMinDriftBatches = 20;
// A ratio above this (and above white errors' 4-sigma spread) drifts: twice
// the variance of white errors' batch sums.
inline constexpr double kMaxWhiteDriftRatio = 2.0;

struct ResidualDrift {
  std::string kind;  // "range" or "bearing".
  int batches = 0;   // Whole batches over all landmarks.
  double ratio = 1.0;
  // Over kMaxWhiteDriftRatio and 1 + 4 sqrt(2 / batches) (white errors'
  // ratio has about that standard deviation), with kMinDriftBatches.
  bool drifts = false;
};

// The drift of one kind's residuals over batches of kDriftBatch, `series`
// one landmark's each in time order. batches = 0 (nothing judged) when no
// landmark has a whole batch or the median |r| is 0 (more than half the
// rows fit exactly: the clip level, and every row, is 0).
ResidualDrift MeasureResidualDrift(
    const std::string& kind,
    const std::map<LandmarkId, std::vector<double>>& series);

}  // namespace rff

#endif  // RFF_CERES_RESIDUAL_DRIFT_H_
