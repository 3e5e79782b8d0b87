// Synthetic 2D SLAM datasets: the seed paper's protocol (a wandering unicycle
// among landmarks scattered around its path) and a large bearing-only preset
// at the scale of KITTI projected to the plane. See docs/simulator.md.
//
// Everything is seeded and reproducible: the random draws come from
// std::mt19937_64 (whose output the C++ standard fixes) turned into uniform
// and normal numbers by our own code, since the std:: distributions differ
// between standard libraries.
#ifndef RFF_CERES_SIMULATE_H_
#define RFF_CERES_SIMULATE_H_

#include <cstdint>
#include <random>
#include <string>

#include "rff_ceres/measurement_types.h"  // ParseMeasurementKind.
#include "rff_ceres/types.h"

namespace rff {

// How the true trajectory is generated.
enum class TrajectoryShape {
  // Unicycle whose speed swings between 0.5x and 1.5x `speed` and whose turn
  // rate is a smooth sum of three random sinusoids (the paper's protocol).
  kWandering,
  // Car on a road: near-constant speed, long straight stretches joined by
  // smooth turns of 30 to 90 degrees.
  kRoad,
  // x(t), y(t) and theta(t) drawn from independent zero-mean Gaussian
  // processes with the gp_* kernels below (simulate_gp_draw.h).
  kGpDraw,
};

// "wandering", "road", "gp_draw".
std::string TrajectoryShapeName(TrajectoryShape model);

// Every knob of the simulator. The defaults are the seed paper's protocol
// (300 steps of 1 s, 4 random landmarks observed per step, range sigma 1 m,
// bearing sigma 2 deg, landmark priors of 5 m, odometry 0.05 m / 0.01 rad).
struct SimulationOptions {
  std::uint64_t seed = 1;
  // Preset the options came from ("paper", "kitti_scale", "laser_10hz" or
  // "gp_draw"); metadata only.
  std::string preset = "paper";

  // Trajectory: poses at t = 0, dt, ..., (num_steps - 1) dt.
  TrajectoryShape trajectory = TrajectoryShape::kWandering;
  int num_steps = 300;
  double dt = 1.0;     // s
  double speed = 1.0;  // mean forward speed, m/s

  // kGpDraw only: the kernel of every coordinate (a name of CreateKernel,
  // e.g. "rbf" or "matern52"), the lengthscale (s) and variance (m^2) of x
  // and y, and those of theta (s, rad^2). The "# truth:" metadata line
  // records them.
  std::string gp_kernel = "matern52";
  double gp_lengthscale = 8.0;
  double gp_kernel_variance = 25.0;
  double gp_heading_lengthscale = 12.0;
  double gp_heading_kernel_variance = 0.25;

  // Landmarks: ids 0 .. num_landmarks - 1 (plus any that the visibility
  // guarantee below adds).
  int num_landmarks = 50;
  // Without a sensor range, landmarks are uniform in the trajectory's
  // bounding box grown by this margin (m).
  double landmark_margin = 15.0;
  // Sigma of the PRIOR_LANDMARK records, whose means are the true positions
  // plus a draw of this sigma. 0 writes no landmark priors.
  double landmark_prior_sigma = 5.0;

  // Measurements.
  ObservationType kind = ObservationType::kRangeBearing;
  double sigma_range = 1.0;                   // m
  double sigma_bearing = 2.0 * M_PI / 180.0;  // rad
  // Landmarks observed per pose: distinct, drawn at random among all
  // landmarks, or among the visible ones when sensor_range > 0 (then fewer
  // if fewer are visible), at most num_landmarks without sensor_range or
  // observe_nearest.
  int observations_per_step = 4;
  // Observe the observations_per_step nearest candidates at least min_range
  // away (ties by id) instead of a random sample: a sensor that reports
  // what is close. Applies min_range with or without a sensor_range.
  bool observe_nearest = false;

  // Visibility model, used when sensor_range > 0: a landmark is visible from
  // a pose when its distance lies in [min_range, sensor_range] and its
  // bearing in [-field_of_view / 2, field_of_view / 2]. Landmarks are then
  // placed in the view of random poses rather than in the bounding box, and
  // poses that see fewer than min_visible_landmarks get extra landmarks
  // placed in their view, so every pose sees at least that many.
  double sensor_range = 0.0;          // m; 0 = every landmark is visible
  double min_range = 2.0;             // m
  double field_of_view = 2.0 * M_PI;  // rad, in (0, 2 pi]
  int min_visible_landmarks = 0;

  // Odometry: one ODOM record per step with independent noise per component.
  bool odometry = true;
  double odometry_sigma_xy = 0.05;     // m
  double odometry_sigma_theta = 0.01;  // rad

  // Tight prior on the first pose, centred on the truth (it fixes the gauge).
  double first_pose_sigma_xy = 0.01;
  double first_pose_sigma_theta = 0.001;

  // Adds no noise at all, while still writing the sigmas above: the
  // measurements are then the exact geometry (for exact-recovery tests).
  bool noise_free = false;
};

// The paper's protocol with `seed` (the defaults of SimulationOptions).
SimulationOptions PaperOptions(std::uint64_t seed);

// Bearing-only, KITTI-projected scale: 3000 poses at 10 Hz of a car driving
// at about 10 m/s, about 4000 landmarks, a 90 degree field of view out to
// 40 m, at least 10 landmarks seen and up to 15 observed per pose.
SimulationOptions KittiScaleOptions(std::uint64_t seed);

// A ground robot with a laser scanner: 20 minutes at 10 Hz (12000 poses) on
// the wandering path at about 1 m/s, wheel odometry every step (5 mm and
// 0.001 rad per step: dead reckoning ends a few metres off), range-bearing
// to the 6 nearest landmarks in a 270 degree view from 1 to 20 m (0.05 m,
// 0.5 deg), about 150 landmarks of which every pose sees at least 4, and
// landmark priors 1 m off.
SimulationOptions Laser10HzOptions(std::uint64_t seed);

// The "gp_draw" preset is GpDrawOptions in simulate_gp_draw.h.

// Checks every option; on failure `error` names the option, its value and
// the allowed range.
bool ValidateSimulationOptions(const SimulationOptions& options,
                               std::string* error);

// Generates a dataset: metadata (source, seed and every option), a prior on
// the first pose, landmark priors, observations, odometry, GT_POSE at every
// step and GT_LANDMARK for every landmark. Returns false (with `error`) for
// invalid options, or when min_visible_landmarks cannot be met (a view too
// small for double precision). The same options give the same dataset bit
// for bit.
bool Simulate(const SimulationOptions& options, Dataset* dataset,
              std::string* error);

// Seeded random numbers with distributions of our own, so that a seed means
// the same numbers with every standard library.
class SimulationRandom {
 public:
  explicit SimulationRandom(std::uint64_t seed) : engine_(seed) {}

  // Raw 64 bits of std::mt19937_64.
  std::uint64_t Bits() { return engine_(); }
  // Uniform in [0, 1), a multiple of 2^-53.
  double Uniform();
  // Uniform in [low, high).
  double Uniform(double low, double high);
  // Uniform integer in [0, n), without modulo bias; n >= 1.
  std::uint64_t Index(std::uint64_t n);
  // Standard normal (Box-Muller; the second value of each pair is kept for
  // the next call).
  double Normal();

 private:
  std::mt19937_64 engine_;
  bool has_spare_normal_ = false;
  double spare_normal_ = 0.0;
};

}  // namespace rff

#endif  // RFF_CERES_SIMULATE_H_
