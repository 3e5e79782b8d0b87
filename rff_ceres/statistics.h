// Small robust statistics shared by the converters.
#ifndef RFF_CERES_STATISTICS_H_
#define RFF_CERES_STATISTICS_H_

#include <algorithm>
#include <vector>

namespace rff {

// Median of `values` (the mean of the middle two for an even count); 0 for
// no values.
inline double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const std::size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  const double upper = values[mid];
  if (values.size() % 2 == 1) return upper;
  return 0.5 *
         (upper + *std::max_element(values.begin(), values.begin() + mid));
}

}  // namespace rff

#endif  // RFF_CERES_STATISTICS_H_
