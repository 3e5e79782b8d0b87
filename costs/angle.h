// Angle wrapping, for the residuals and for the library (here, so that the
// costs depend on nothing but Eigen and Ceres).
#ifndef RFF_COSTS_ANGLE_H_
#define RFF_COSTS_ANGLE_H_

#include <cmath>

namespace rff {

// Wraps an angle to (-pi, pi]: residuals on the circle are measured along
// the shortest arc. remainder() maps to [-pi, pi]; -pi folds onto pi.
inline double WrapAngle(double angle) {
  double wrapped = std::remainder(angle, 2.0 * M_PI);
  if (wrapped <= -M_PI) wrapped += 2.0 * M_PI;
  return wrapped;
}

}  // namespace rff

#endif  // RFF_COSTS_ANGLE_H_
