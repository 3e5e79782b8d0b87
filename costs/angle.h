// Angle wrapping, for the residuals and for the library (here, so that the
// costs depend on nothing but Eigen and Ceres).
#ifndef RFF_COSTS_ANGLE_H_
#define RFF_COSTS_ANGLE_H_

#include <cmath>

namespace rff {

// Wraps an angle to (-pi, pi] (pi as M_PI): residuals on the circle are
// measured along the shortest arc. The result is the one angle - k 2pi in
// that interval, exactly, as remainder() gives it (-pi folded onto pi): every
// such value is a multiple of 2^-51 under 4 in size, so representable, and
// fma forms it with one rounding; a k that the quotient's rounding puts one
// off lands 2pi away and is moved back exactly. Past 2^40 rad the quotient
// may miss by more: remainder() there. An angle in the interval is itself.
inline double WrapAngle(double angle) {
  constexpr double kTwoPi = 2.0 * M_PI;
  if (angle > -M_PI && angle <= M_PI) return angle;
  double wrapped;
  if (std::abs(angle) < 0x1p40) {
    wrapped = std::fma(-std::nearbyint(angle / kTwoPi), kTwoPi, angle);
    if (wrapped > M_PI) wrapped -= kTwoPi;
  } else {
    wrapped = std::remainder(angle, kTwoPi);
  }
  if (wrapped <= -M_PI) wrapped += kTwoPi;
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
