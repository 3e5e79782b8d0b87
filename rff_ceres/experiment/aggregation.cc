#include "rff_ceres/experiment/aggregation.h"

#include <cmath>
#include <map>
#include <tuple>

#include "rff_ceres/statistics.h"

namespace rff {

Spread SpreadOf(const std::vector<double>& values) {
  std::vector<double> finite;
  for (double v : values) {
    if (std::isfinite(v)) finite.push_back(v);
  }
  Spread spread;
  spread.count = static_cast<int>(finite.size());
  if (finite.empty()) return spread;
  spread.median = Median(finite);
  double sum = 0.0;
  for (double v : finite) sum += v;
  spread.mean = sum / finite.size();
  return spread;
}

std::vector<SeedAggregate> AggregateOverSeeds(const std::vector<RunRow>& rows) {
  using Key = std::tuple<std::string, std::string, int, double, std::string,
                         std::string>;
  std::map<Key, std::size_t> index;
  std::vector<SeedAggregate> aggregates;
  std::vector<std::vector<const RunRow*>> members;
  for (const RunRow& row : rows) {
    const Key key{row.method, row.family,     row.landmarks,
                  row.noise,  row.noise_unit, row.variant};
    auto [it, inserted] = index.emplace(key, aggregates.size());
    if (inserted) {
      SeedAggregate a;
      a.method = row.method;
      a.family = row.family;
      a.kind = row.kind;
      a.landmarks = row.landmarks;
      a.noise = row.noise;
      a.noise_unit = row.noise_unit;
      a.variant = row.variant;
      aggregates.push_back(a);
      members.emplace_back();
    }
    members[it->second].push_back(&row);
  }
  for (std::size_t i = 0; i < aggregates.size(); ++i) {
    SeedAggregate& a = aggregates[i];
    auto spread = [&](double RunRow::*field) {
      std::vector<double> values;
      for (const RunRow* row : members[i]) {
        if (row->ok()) values.push_back(row->*field);
      }
      return SpreadOf(values);
    };
    a.runs = static_cast<int>(members[i].size());
    for (const RunRow* row : members[i]) a.failed += row->ok() ? 0 : 1;
    a.ape_translation = spread(&RunRow::ape_translation);
    a.ape_rotation_deg = spread(&RunRow::ape_rotation_deg);
    a.rpe_translation = spread(&RunRow::rpe_translation);
    a.rpe_rotation_deg = spread(&RunRow::rpe_rotation_deg);
    a.landmark_rms = spread(&RunRow::landmark_rms);
    a.solve_seconds = spread(&RunRow::solve_seconds);
    // Dead reckoning does not depend on the solve: over every run made.
    std::vector<double> dead_reckoning;
    for (const RunRow* row : members[i]) {
      dead_reckoning.push_back(row->dead_reckoning_ape_translation);
    }
    a.dead_reckoning_ape_translation = SpreadOf(dead_reckoning);
  }
  return aggregates;
}

}  // namespace rff
