// The whitening a learning round rescales in place (variance_components.h):
// a cost given new sigmas, or a new square-root information, is then the
// cost its constructor builds with them, bit for bit, and the problem that
// holds it need not be built again.
#ifndef RFF_COSTS_NOISE_WEIGHTED_H_
#define RFF_COSTS_NOISE_WEIGHTED_H_

#include "Eigen/Core"

namespace rff {

// A RANGE, BEARING or RANGE_BEARING residual: each takes the sigma of what
// it measures and ignores the other.
class ObservationWeighted {
 public:
  virtual ~ObservationWeighted() = default;
  virtual void SetSigmas(double sigma_range, double sigma_bearing) = 0;
};

// An odometry residual r = L e.
class OdometryWeighted {
 public:
  virtual ~OdometryWeighted() = default;
  virtual void SetSqrtInformation(const Eigen::Matrix3d& sqrt_information) = 0;
};

}  // namespace rff

#endif  // RFF_COSTS_NOISE_WEIGHTED_H_
