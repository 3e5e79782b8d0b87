// Angle wrapping, for the residuals and for the library (here, so that the
// costs depend on nothing but Eigen and Ceres).
#ifndef RFF_COSTS_ANGLE_H_
#define RFF_COSTS_ANGLE_H_

#include <cmath>

namespace rff {

// Wraps an angle to (-pi, pi]: residuals on the circle are measured along
// the shortest arc. remainder() maps to [-pi, pi]; -pi folds onto pi. An
// angle already in (-pi, pi] is its own remainder, bit for bit, and most are.
inline double WrapAngle(double angle) {
  if (angle > -M_PI && angle <= M_PI) return angle;
  double wrapped = std::remainder(angle, 2.0 * M_PI);
  if (wrapped <= -M_PI) wrapped += 2.0 * M_PI;
  return wrapped;
}

// The same for Ceres Jets: ceil has a zero derivative, so the wrap leaves
// the gradient alone. Doubles take the exact remainder form above.
template <typename T>
T WrapAngle(const T& angle) {
  using std::ceil;
  const T two_pi = T(2.0 * M_PI);
  return angle - two_pi * ceil((angle - T(M_PI)) / two_pi);
}

}  // namespace rff

#endif  // RFF_COSTS_ANGLE_H_
