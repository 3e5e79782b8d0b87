// Small SE(2) toolkit: planar poses (x, y, theta) with composition, inverse,
// relative pose and interpolation. Templated on the scalar so that Ceres cost
// functors can use the same formulas with Jets; headings stay in (-pi, pi].
#ifndef RFF_CERES_SE2_H_
#define RFF_CERES_SE2_H_

#include <algorithm>
#include <cmath>
#include <vector>

#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/types.h"

namespace rff {

template <typename T>
struct Pose2T {
  T x = T(0.0);
  T y = T(0.0);
  T theta = T(0.0);
};
using Pose2 = Pose2T<double>;

// a * b: the pose b, given in the frame of a, expressed in a's parent frame.
template <typename T>
Pose2T<T> Compose(const Pose2T<T>& a, const Pose2T<T>& b) {
  using std::cos;
  using std::sin;
  const T c = cos(a.theta);
  const T s = sin(a.theta);
  return {a.x + c * b.x - s * b.y, a.y + s * b.x + c * b.y,
          WrapAngle(a.theta + b.theta)};
}

// a^-1, so that Compose(a, Inverse(a)) is the identity.
template <typename T>
Pose2T<T> Inverse(const Pose2T<T>& a) {
  using std::cos;
  using std::sin;
  const T c = cos(a.theta);
  const T s = sin(a.theta);
  return {-(c * a.x + s * a.y), s * a.x - c * a.y, WrapAngle(-a.theta)};
}

// a^-1 * b: the pose b seen from the frame of a (the form of an ODOM record).
template <typename T>
Pose2T<T> Between(const Pose2T<T>& a, const Pose2T<T>& b) {
  using std::cos;
  using std::sin;
  const T c = cos(a.theta);
  const T s = sin(a.theta);
  const T dx = b.x - a.x;
  const T dy = b.y - a.y;
  return {c * dx + s * dy, -s * dx + c * dy, WrapAngle(b.theta - a.theta)};
}

// Pose at fraction `alpha` from a (0) to b (1): linear in x and y, heading
// along the shorter arc of the circle (so 179 deg -> -179 deg passes 180 deg).
template <typename T>
Pose2T<T> Interpolate(const Pose2T<T>& a, const Pose2T<T>& b, const T& alpha) {
  return {a.x + alpha * (b.x - a.x), a.y + alpha * (b.y - a.y),
          WrapAngle(a.theta + alpha * WrapAngle(b.theta - a.theta))};
}

inline Pose2 ToPose2(const TimedPose& p) { return {p.x, p.y, p.theta}; }
inline TimedPose ToTimedPose(double t, const Pose2& p) {
  return {t, p.x, p.y, p.theta};
}

// The pose of `trajectory` (strictly increasing times, not empty) at time t:
// Interpolate() between the poses around t, the end pose outside the span
// (callers that must not extrapolate check the span first).
inline TimedPose PoseAtTime(const std::vector<TimedPose>& trajectory,
                            double t) {
  // First pose strictly after t; the segment is [upper - 1, upper].
  const auto upper = std::upper_bound(
      trajectory.begin(), trajectory.end(), t,
      [](double time, const TimedPose& p) { return time < p.t; });
  if (upper == trajectory.begin()) {
    return ToTimedPose(t, ToPose2(trajectory.front()));
  }
  if (upper == trajectory.end()) {
    return ToTimedPose(t, ToPose2(trajectory.back()));
  }
  const TimedPose& a = *(upper - 1);
  const TimedPose& b = *upper;
  const double alpha = (t - a.t) / (b.t - a.t);
  return ToTimedPose(t, Interpolate(ToPose2(a), ToPose2(b), alpha));
}

// Moves (x, y, theta) along a unicycle arc: forward speed v and turn rate
// omega held for dt seconds. Exact for any omega: the chord of the arc,
// v dt sinc(omega dt / 2), points along the heading halfway through the turn
// (sinc by its series near 0). theta is not wrapped.
inline void IntegrateUnicycle(double v, double omega, double dt, double* x,
                              double* y, double* theta) {
  const double half = 0.5 * omega * dt;
  const double sinc =
      std::abs(half) < 1e-4 ? 1.0 - half * half / 6.0 : std::sin(half) / half;
  const double chord = v * dt * sinc;
  const double mid_heading = *theta + half;
  *x += chord * std::cos(mid_heading);
  *y += chord * std::sin(mid_heading);
  *theta += omega * dt;
}

}  // namespace rff

#endif  // RFF_CERES_SE2_H_
