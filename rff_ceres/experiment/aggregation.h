// Statistics over seeds: the runs of one setting (method, family,
// landmarks, noise, variant) summarised by the median and mean of each
// metric, as Table I and Figure 1 report them.
#ifndef RFF_CERES_EXPERIMENT_AGGREGATION_H_
#define RFF_CERES_EXPERIMENT_AGGREGATION_H_

#include <string>
#include <vector>

#include "rff_ceres/experiment/runner.h"

namespace rff {

// Median and mean of the finite values (NaN for none).
struct Spread {
  int count = 0;
  double median = RunRow::kNone;
  double mean = RunRow::kNone;
};
Spread SpreadOf(const std::vector<double>& values);

// Runs of one (method, family, landmarks, noise, variant) over seeds.
struct SeedAggregate {
  std::string method;
  std::string family;
  std::string kind;
  int landmarks = 0;
  double noise = 0.0;
  std::string noise_unit;
  std::string variant;
  int runs = 0;
  int failed = 0;
  Spread ape_translation;  // Over the successful runs.
  Spread ape_rotation_deg;
  Spread rpe_translation;
  Spread rpe_rotation_deg;
  Spread landmark_rms;
  Spread dead_reckoning_ape_translation;
  Spread solve_seconds;
};

// Groups `rows` by (method, family, landmarks, noise, variant), in order of
// first appearance.
std::vector<SeedAggregate> AggregateOverSeeds(const std::vector<RunRow>& rows);

}  // namespace rff

#endif  // RFF_CERES_EXPERIMENT_AGGREGATION_H_
