#include "rff_ceres/residual_drift.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "rff_ceres/statistics.h"

namespace rff {

ResidualDrift MeasureResidualDrift(
    const std::string& kind,
    const std::map<LandmarkId, std::vector<double>>& series) {
  constexpr std::size_t batch = kDriftBatch;
  ResidualDrift drift;
  drift.kind = kind;
  std::vector<double> magnitudes;
  for (const auto& [landmark, values] : series) {
    for (const double r : values) magnitudes.push_back(std::abs(r));
  }
  const double clip_level = 5.0 * 1.4826 * Median(std::move(magnitudes));
  double batch_squares = 0.0, squares = 0.0;
  for (const auto& [landmark, values] : series) {
    const std::size_t whole = values.size() / batch;
    for (std::size_t b = 0; b < whole; ++b) {
      double sum = 0.0;
      for (std::size_t i = b * batch; i < (b + 1) * batch; ++i) {
        const double r = std::clamp(values[i], -clip_level, clip_level);
        sum += r;
        squares += r * r;
      }
      batch_squares += sum * sum;
    }
    drift.batches += static_cast<int>(whole);
  }
  if (drift.batches == 0 || !(squares > 0.0)) {
    drift.batches = 0;
    return drift;
  }
  drift.ratio = batch_squares / squares;
  drift.drifts =
      drift.batches >= kMinDriftBatches &&
      drift.ratio > std::max(kMaxWhiteDriftRatio,
                             1.0 + 4.0 * std::sqrt(2.0 / drift.batches));
  return drift;
}

}  // namespace rff
