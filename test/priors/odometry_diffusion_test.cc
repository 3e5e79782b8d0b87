#include "rff_ceres/priors/odometry_diffusion.h"

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "costs/angle.h"
#include "gtest/gtest.h"

namespace rff {
namespace {

// x, y and theta each an exact WNOA draw (position and velocity of white
// acceleration of density qc, the LTV-SDE prior of Barfoot et al. 2014)
// sampled every dt
// seconds, the x velocity starting at `speed`; the odometry is each step's
// motion in the body frame, noise-free, so that the dead reckoning
// reproduces the samples.
std::vector<Odometry> DrawnOdometry(double position_qc, double heading_qc,
                                    double speed, double seconds, double dt,
                                    unsigned seed) {
  std::mt19937 random(seed);
  std::normal_distribution<double> normal;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Vector3d v(speed, 0.0, 0.0);
  const Eigen::Vector3d qc(position_qc, position_qc, heading_qc);
  std::vector<Odometry> odometry;
  const int steps = static_cast<int>(std::lround(seconds / dt));
  for (int k = 0; k < steps; ++k) {
    const double t = k * dt;
    Eigen::Vector3d next_p, next_v;
    for (int axis = 0; axis < 3; ++axis) {
      // The step's covariance qc [dt^3/3, dt^2/2; dt^2/2, dt], by Cholesky.
      const double a = std::sqrt(qc[axis] * dt * dt * dt / 3.0);
      const double b = qc[axis] * dt * dt / 2.0 / a;
      const double c = std::sqrt(qc[axis] * dt - b * b);
      const double z0 = normal(random), z1 = normal(random);
      next_p[axis] = p[axis] + v[axis] * dt + a * z0;
      next_v[axis] = v[axis] + b * z0 + c * z1;
    }
    const double cos_theta = std::cos(p.z()), sin_theta = std::sin(p.z());
    const Eigen::Vector2d step = next_p.head<2>() - p.head<2>();
    Odometry o;
    o.t0 = t;
    o.t1 = (k + 1) * dt;
    o.dx = cos_theta * step.x() + sin_theta * step.y();
    o.dy = -sin_theta * step.x() + cos_theta * step.y();
    o.dtheta = WrapAngle(next_p.z() - p.z());
    o.sigma_x = o.sigma_y = o.sigma_theta = 0.01;
    odometry.push_back(o);
    p = next_p;
    v = next_v;
  }
  return odometry;
}

TEST(OdometryDiffusionTest, RecoversTheDrawsQc) {
  for (const unsigned seed : {1u, 2u, 3u}) {
    const std::vector<Odometry> odometry =
        DrawnOdometry(0.03, 0.002, 1.0, 3000.0, 0.1, seed);
    OdometryDiffusion d;
    std::string why;
    ASSERT_TRUE(EstimateOdometryDiffusion(odometry, &d, &why)) << why;
    EXPECT_DOUBLE_EQ(d.window_seconds, 0.5);
    EXPECT_NEAR(d.windows, 5999, 1);
    EXPECT_NEAR(d.position_qc / 0.03, 1.0, 0.05) << seed;
    EXPECT_NEAR(d.heading_qc / 0.002, 1.0, 0.07) << seed;
  }
}

TEST(OdometryDiffusionTest, WindowsSpanTheMedianRecord) {
  // Records of 2 s: windows shorter than one would see straight lines.
  const std::vector<Odometry> odometry =
      DrawnOdometry(0.03, 0.002, 1.0, 6000.0, 2.0, 4);
  OdometryDiffusion d;
  std::string why;
  ASSERT_TRUE(EstimateOdometryDiffusion(odometry, &d, &why)) << why;
  EXPECT_DOUBLE_EQ(d.window_seconds, 2.0);
  EXPECT_NEAR(d.position_qc / 0.03, 1.0, 0.1);
}

TEST(OdometryDiffusionTest, SkipsTheWindowsAGapTouches) {
  // Held through a gap, the dead reckoning stops at 1 m/s: the two pairs of
  // windows at each end would add (1 m/s)^2 each, a third of the rest.
  std::vector<Odometry> odometry =
      DrawnOdometry(0.01, 0.001, 1.0, 400.0, 0.1, 5);
  std::vector<Odometry> with_gap;
  for (const Odometry& o : odometry) {
    if (o.t1 <= 150.0 || o.t0 >= 200.0) with_gap.push_back(o);
  }
  OdometryDiffusion whole, gapped;
  std::string why;
  ASSERT_TRUE(EstimateOdometryDiffusion(odometry, &whole, &why)) << why;
  ASSERT_TRUE(EstimateOdometryDiffusion(with_gap, &gapped, &why)) << why;
  EXPECT_LT(gapped.windows, whole.windows - 100);
  EXPECT_NEAR(gapped.position_qc / whole.position_qc, 1.0, 0.1);
}

// 20 s of 0.1 s records with one of `seconds` in the middle.
std::vector<Odometry> WithALongRecord(double seconds) {
  const std::vector<Odometry> drawn =
      DrawnOdometry(0.03, 0.002, 1.0, 20.0, 0.1, 8);
  std::vector<Odometry> odometry;
  for (Odometry o : drawn) {
    if (o.t0 >= 10.0 - 1e-9) {
      o.t0 += seconds;
      o.t1 += seconds;
    }
    odometry.push_back(o);
  }
  Odometry long_record = drawn[99];
  long_record.t0 = long_record.t1;
  long_record.t1 = long_record.t0 + seconds;
  odometry.push_back(long_record);
  return odometry;
}

TEST(OdometryDiffusionTest, ARecordLongerThanAWindowEndsAStretch) {
  // A straight line, whose second differences would be zero: the windows
  // fill the 10 s on either side, 19 pairs each.
  OdometryDiffusion d;
  std::string why;
  ASSERT_TRUE(EstimateOdometryDiffusion(WithALongRecord(10.0), &d, &why))
      << why;
  EXPECT_DOUBLE_EQ(d.window_seconds, 0.5);
  EXPECT_EQ(d.windows, 38);
  EXPECT_NEAR(d.position_qc / 0.03, 1.0, 0.5);
  // One of 10^9 s holds nearly all the odometry's time (and would take
  // 2 10^9 windows of 0.5 s).
  EXPECT_FALSE(EstimateOdometryDiffusion(WithALongRecord(1e9), &d, &why));
  EXPECT_EQ(why,
            "the odometry's records no longer than 0.5 s cover 2e-08 of its "
            "time, under 0.5");
}

TEST(OdometryDiffusionTest, RecordsLongerThanAWindowForMostOfTheRun) {
  // 10 s of 0.1 s records, then 20 s of 2 s ones: the median is 0.1 s and
  // the short records hold a third of the odometry's time.
  std::vector<Odometry> odometry =
      DrawnOdometry(0.03, 0.002, 1.0, 10.0, 0.1, 9);
  for (const Odometry& o : DrawnOdometry(0.03, 0.002, 1.0, 20.0, 2.0, 9)) {
    Odometry late = o;
    late.t0 += 10.0;
    late.t1 += 10.0;
    odometry.push_back(late);
  }
  OdometryDiffusion d;
  std::string why;
  EXPECT_FALSE(EstimateOdometryDiffusion(odometry, &d, &why));
  EXPECT_EQ(why,
            "the odometry's records no longer than 0.5 s cover 0.333333 of "
            "its time, under 0.5");
}

TEST(OdometryDiffusionTest, TooShortAChainEstimatesNothing) {
  OdometryDiffusion d;
  std::string why;
  EXPECT_FALSE(EstimateOdometryDiffusion({}, &d, &why));
  EXPECT_EQ(why, "the run has no odometry");
  // 5 s: 9 pairs of adjacent 0.5 s windows; 5.5 s: 10.
  EXPECT_FALSE(EstimateOdometryDiffusion(
      DrawnOdometry(0.03, 0.002, 1.0, 5.0, 0.1, 6), &d, &why));
  EXPECT_EQ(d.windows, 0);
  EXPECT_EQ(why,
            "the odometry has 9 pairs of adjacent 0.5 s windows of records no "
            "longer than one, under 10");
  EXPECT_TRUE(EstimateOdometryDiffusion(
      DrawnOdometry(0.03, 0.002, 1.0, 5.5, 0.1, 6), &d, &why));
  EXPECT_EQ(d.windows, 10);
  // A robot standing still implies no diffusion at all.
  std::vector<Odometry> still = DrawnOdometry(0.03, 0.002, 0.0, 60.0, 0.1, 7);
  for (Odometry& o : still) o.dx = o.dy = o.dtheta = 0.0;
  EXPECT_FALSE(EstimateOdometryDiffusion(still, &d, &why));
  EXPECT_EQ(why,
            "the odometry's second differences give Q_c 0 (x, y), 0 (theta)");
  EXPECT_EQ(d.windows, 0);
}

}  // namespace
}  // namespace rff
